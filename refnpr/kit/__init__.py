"""Conformance kit: every input of a golden case in standard formats, and a checker.

* :func:`export_kit` (``refnpr kit export DIR``) writes ``DIR/index.json``, the JSON Schema and
  per case ``case.json``, glTF meshes, texture files, expected images and tolerances (see
  ``docs/kit.md``).
* ``refnpr.kit.check`` (``refnpr kit check DIR RENDERS``) compares a backend's renders with it.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "export_kit",
    "check_kit",
    "CaseCheck",
    "StyleExport",
    "write_texture_levels",
    "KIT_FORMAT",
    "KIT_VERSION",
]

KIT_FORMAT = "refnpr-kit"
KIT_VERSION = 1


def __getattr__(name: str) -> Any:  # lazy: importing refnpr.kit stays cheap
    if name == "export_kit":
        from .export import export_kit

        return export_kit
    if name in ("check_kit", "CaseCheck"):
        from . import check

        return getattr(check, name)
    if name == "StyleExport":
        from .styles import StyleExport

        return StyleExport
    if name == "write_texture_levels":
        from .textures import write_texture_levels

        return write_texture_levels
    raise AttributeError(name)
