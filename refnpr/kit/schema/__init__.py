"""The JSON Schemas (draft 2020-12) of a kit's ``case.json`` and ``index.json``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

__all__ = ["SCHEMA_FILES", "schema_path", "load_schema"]

#: Files shipped in this package and copied into every exported kit.
SCHEMA_FILES = ("case.schema.json", "index.schema.json")
_HERE = Path(__file__).parent


def schema_path(name: str) -> Path:
    """Path of a schema file of this package (one of ``SCHEMA_FILES``)."""
    if name not in SCHEMA_FILES:
        raise ValueError(f"name: expected one of {list(SCHEMA_FILES)}, got {name!r}")
    return _HERE / name


def load_schema(name: str = "case.schema.json") -> dict[str, Any]:
    """The schema as a dict."""
    return json.loads(schema_path(name).read_text(encoding="utf-8"))
