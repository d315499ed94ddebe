"""What a scene asks of a final render that bvhlab does not render, in words: F12 says each (a
warning report and the Last Render record's `unrendered`), as it says motion blur is not
rendered, and renders the rest. Read from the render depsgraph, which holds what renders in the
view layer being rendered."""

from __future__ import annotations

#: Object types Blender renders whose geometry the export does not read (it reads meshes and what
#: converts to one: mesh.py CONVERTIBLE_TYPES).
UNREAD_TYPES = {"CURVES": "hair curves", "POINTCLOUD": "point clouds", "VOLUME": "volumes"}

#: Object Properties ▸ Visibility: per-object render effects bvhlab does not make (holdout and ray
#: visibility it makes: Material.holdout and hidden_from, material_table.py).
OBJECT_EFFECTS = {"is_shadow_catcher": "shadow catcher"}


def _named(what: str, names) -> str:
    """`what` and the first of `names` (a list, or a dict's keys in insertion order)."""
    first = next(iter(names))
    more = f" and {len(names) - 1} more" if len(names) > 1 else ""
    return f"{what} '{first}'{more}"


def unrendered_features(depsgraph, camera=None) -> list[str]:
    """What the render depsgraph's scene, view layer and objects ask for that bvhlab does not
    render, each in words. `camera`: the object rendered through where it is not the scene camera
    (RenderEngine.camera_override: a Sequencer strip's)."""
    from bvhlab.blender.scope import shown_object  # bvhlab.blender is imported when first used

    render = depsgraph.scene.render
    found = _Found()
    # what renders (a render depsgraph leaves out the rest): the objects and what they instance (a
    # collection instanced, geometry nodes' output), each object once for each kind of geometry it
    # shows (a mesh object whose geometry nodes put out points shows a mesh and a point cloud)
    seen, instancers, copies = set(), set(), {}
    for instance in depsgraph.object_instances:
        # valid until the iterator moves on: looked at now (an instance's without leaking Blender's
        # wrapper where it can: scope.shown_object)
        obj = shown_object(instance, copies) if instance.is_instance else instance.object
        original = obj.original
        if (original, obj.type) not in seen:
            seen.add((original, obj.type))
            found.look_at(obj, original.name)
        if instance.is_instance:  # an instancer's effects are its instances' too (Cycles ors them)
            parent = instance.parent.original
            if parent not in instancers:
                instancers.add(parent)
                found.look_at_effects(parent, parent.name)
    unread, effects, strands = found.unread, found.effects, found.strands
    notes = []
    for kind, names in unread.items():
        notes.append(f"{UNREAD_TYPES[kind]} are not rendered ({_named('object', names)})")
    if strands:
        notes.append(f"particle hair drawn as strands is not rendered ({_named('on', strands)})")
    for flag, names in effects.items():
        notes.append(f"{OBJECT_EFFECTS[flag]} is not rendered ({_named('object', names)}): it is rendered as a surface")
    if render.use_motion_blur:
        notes.append("motion blur is not rendered (Render ▸ Motion Blur is on): the frame shows one moment")
    camera = camera or depsgraph.scene.camera
    if render.use_multiview and camera is not None and getattr(camera.data, "type", "") == "PANO":
        notes.append(
            "a panorama's stereoscopy is two panoramas from the eyes' positions (as Blender frames it for "
            "an engine without Cycles' spherical stereo)"
        )
    return notes


class _Found:
    """What the objects looked at ask for, by kind: the names of the objects asking."""

    def __init__(self):
        from bvhlab.blender.mesh import CONVERTIBLE_TYPES  # bvhlab.blender is imported when first used

        self.shapes = {"MESH", *CONVERTIBLE_TYPES}  # what the export reads (a light's flags are its own)
        # names in the order first seen, each once (dicts as ordered sets: 10,000 objects were a
        # list scan each)
        self.unread: dict[str, dict[str, None]] = {}
        self.effects: dict[str, dict[str, None]] = {}
        self.strands: dict[str, None] = {}

    def look_at_effects(self, obj, name: str) -> None:
        """The render effects of OBJECT_EFFECTS `obj` (named `name`) asks for."""
        for flag in OBJECT_EFFECTS:
            if getattr(obj, flag, False):
                self.effects.setdefault(flag, {})[name] = None

    def look_at(self, obj, name: str) -> None:
        """An object or instance of kind obj.type whose original is named `name` (asked once for each
        kind an original shows: each name is kept once in each list)."""
        kind = obj.type
        if kind in UNREAD_TYPES:
            self.unread.setdefault(kind, {})[name] = None
            return
        if kind not in self.shapes:
            return
        self.look_at_effects(obj, name)
        if len(obj.particle_systems) and any(_renders_strands(m) for m in obj.modifiers):
            self.strands[name] = None


def _renders_strands(modifier) -> bool:
    """A particle system modifier on in renders whose particles are hair drawn as paths."""
    if modifier.type != "PARTICLE_SYSTEM" or not modifier.show_render:
        return False
    settings = modifier.particle_system.settings
    return settings.type == "HAIR" and settings.render_type == "PATH"
