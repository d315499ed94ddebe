"""The two ways a Blender export tells its caller about bad input."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class ExportError(ValueError):
    """The scene cannot be exported (nothing in scope, a NaN vertex, no camera...). The message
    says what is wrong and names the object, so a panel can show it as it is."""


@contextmanager
def naming(kind: str, name: str) -> Iterator[None]:
    """A bvhlab scene part's check failing inside (a ValueError: "light position must be finite")
    raised as an ExportError that names the Blender datablock it was read from ("light 'Lamp':
    light position must be finite..."), as a mesh's errors name their object (the audit: a NaN
    light, material or world refused the scene without saying which)."""
    try:
        yield
    except ExportError:
        raise
    except ValueError as error:
        raise ExportError(f"{kind} '{name}': {error}") from None


class ExportWarning(UserWarning):
    """The export went on with an approximation (a texture read as one colour, a lens shift
    ignored); issued through `warnings.warn` so scripts see it and operators can report it."""


class SubstituteWarning(ExportWarning):
    """A missing camera or light was replaced by bvhlab's default (it matters for rendering, not
    for building a tree)."""


class EmptySceneWarning(ExportWarning):
    """Nothing in scope was exported, and the caller allowed that (a render engine's frame: the
    world alone is rendered; the sidebar's follow: an empty tree)."""
