"""Which objects move (issue 34): an object whose transform is animated, or that moved between two
syncs, gets a mesh and an instance of its own (LiveScene, instancing.py), so that moving it makes
only a new TLAS instead of updating the tree of mesh 0 (where objects used once are placed into
the world)."""

from __future__ import annotations

from .compat import action_data_paths

#: The data paths of an object's own transform (an F-curve or a driver on one moves the object).
TRANSFORM_PATHS = frozenset(
    {
        "location",
        "rotation_euler",
        "rotation_quaternion",
        "rotation_axis_angle",
        "rotation_mode",
        "scale",
        "delta_location",
        "delta_rotation_euler",
        "delta_rotation_quaternion",
        "delta_scale",
        "matrix_world",
        "matrix_basis",
        "matrix_local",
        "matrix_parent_inverse",
    }
)


def transform_animated(obj) -> bool:
    """Whether the transform of `obj` (an original bpy Object) can change with the frame or with
    another object: an F-curve (its action's or an NLA strip's) or a driver on a transform path,
    an enabled constraint, or a parent (or its parent...) that is so."""
    seen: set[int] = set()
    while obj is not None and obj.as_pointer() not in seen:
        seen.add(obj.as_pointer())
        if _animates_transform(obj.animation_data) or any(not c.mute for c in obj.constraints):
            return True
        obj = obj.parent
    return False


def _animated_paths(animation) -> set[str]:
    """The data paths an object's animation data animates: its action's, its unmuted NLA strips'
    and its drivers'."""
    if animation is None:
        return set()
    paths = action_data_paths(animation.action)
    for track in animation.nla_tracks:
        if not track.mute:
            for strip in track.strips:
                paths |= action_data_paths(strip.action)
    paths.update(driver.data_path for driver in animation.drivers)
    return paths


def _animates_transform(animation) -> bool:
    return not TRANSFORM_PATHS.isdisjoint(_animated_paths(animation))


def animates_only_transform(obj) -> bool:
    """Whether `obj` (an original bpy Object) has animation data and it animates its transform
    alone: a frame change then moves it and changes nothing else of it (placed_only.py)."""
    paths = _animated_paths(obj.animation_data)
    return bool(paths) and paths <= TRANSFORM_PATHS


def animates_more_than_transform(obj) -> bool:
    """Whether `obj`'s (an original bpy Object) animation data animates anything but its transform
    (its visibility, say): a frame change may then change more of it than its update names."""
    return not _animated_paths(obj.animation_data) <= TRANSFORM_PATHS


class AnimatedMemo:
    """`transform_animated` asked once per object and sync (an instancer owns thousands of
    instances), by name."""

    def __init__(self):
        self._known: dict[str, bool] = {}

    def __call__(self, origin: tuple) -> bool:
        """Whether an item moves with the frame: `origin` is (owner's name, owner, shown object's
        name, shown object), originals (InScope); its owner (the object, or the instancer) or the
        object it shows is animated."""
        for name, obj in (origin[:2], origin[2:]):
            if name not in self._known:
                self._known[name] = obj is not None and transform_animated(obj)
            if self._known[name]:
                return True
        return False
