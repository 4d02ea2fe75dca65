"""Conformance kit: every input of a golden case in standard formats, and a checker.

* :func:`export_kit` (``refnpr kit export DIR``) writes ``DIR/index.json``, the JSON Schema and
  per case ``case.json``, glTF meshes, texture files, expected images and tolerances (see
  ``docs/kit.md``).
* ``refnpr.kit.check`` (``refnpr kit check DIR RENDERS``) compares a backend's renders with it.
"""

from __future__ import annotations

import importlib
from typing import Any

KIT_FORMAT = "refnpr-kit"
KIT_VERSION = 1

#: The module of each lazily imported name (importing refnpr.kit stays cheap).
_LAZY = {
    "export_kit": ".export",
    "check_kit": ".check",
    "CaseCheck": ".check",
    "StyleExport": ".styles",
    "write_texture_levels": ".textures",
}

__all__ = [*_LAZY, "KIT_FORMAT", "KIT_VERSION"]


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(name)
    return getattr(importlib.import_module(_LAZY[name], __name__), name)
