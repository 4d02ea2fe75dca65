"""The fallback exporter of a style without its own kit module: ``params()`` as they are.

It resolves nothing: a style whose parameters include "auto" values, preset names or textures
needs its own module (``refnpr/kit/styles/<name>.py``); :func:`unresolved` then reports them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .._json import find_strings, jsonable
from ._export import StyleExport

__all__ = ["export", "unresolved"]

#: String values that mean "refnpr decides": never valid in a kit.
UNRESOLVED_WORDS = {"auto", "default", "preset"}


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """``style.params()`` converted to JSON; no textures, no derived texts."""
    return StyleExport(params=jsonable(style.params(), where=f"style {style.name!r} params"))


def unresolved(params: dict[str, Any]) -> list[str]:
    """Key paths of ``params`` (JSON) still holding a value refnpr would resolve ("auto")."""
    return find_strings(params, UNRESOLVED_WORDS)
