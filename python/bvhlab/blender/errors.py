"""The two ways a Blender export tells its caller about bad input."""


class ExportError(ValueError):
    """The scene cannot be exported (nothing in scope, a NaN vertex, no camera...). The message
    says what is wrong and names the object, so a panel can show it as it is."""


class ExportWarning(UserWarning):
    """The export went on with an approximation (a texture read as one colour, a lens shift
    ignored); issued through `warnings.warn` so scripts see it and operators can report it."""


class SubstituteWarning(ExportWarning):
    """A missing camera or light was replaced by bvhlab's default (it matters for rendering, not
    for building a tree)."""


class EmptySceneWarning(ExportWarning):
    """Nothing in scope was exported, and the caller allowed that (a render engine's frame: the
    world alone is rendered; the sidebar's follow: an empty tree)."""
