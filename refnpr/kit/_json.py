"""Conversion of parameter values to plain JSON (lists, numbers, strings, bools, null)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields, is_dataclass
from pathlib import PurePath
from typing import Any

import numpy as np

__all__ = ["jsonable", "find_strings"]


def jsonable(value: Any, *, where: str = "params") -> Any:
    """``value`` as JSON data: tuples and arrays become lists, numpy scalars Python numbers,
    dataclasses and styles dicts (a style: ``{"name": ..., **params}``), paths strings.

    Raises
    ------
    TypeError
        Naming ``where`` (the key path) for a value with no JSON form.
    ValueError
        For NaN or infinite floats (JSON has none), naming ``where``.
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(f"{where}: {v!r} has no JSON form; resolve it to a finite number")
        return v
    if isinstance(value, np.ndarray):
        return [jsonable(v, where=f"{where}[{i}]") for i, v in enumerate(value.tolist())]
    if isinstance(value, (list, tuple)):
        return [jsonable(v, where=f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, Mapping):
        return {str(k): jsonable(v, where=f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, np.dtype) or (isinstance(value, type) and issubclass(value, np.generic)):
        return np.dtype(value).name  # e.g. rasterize's dtype=np.float64 -> "float64"
    if isinstance(value, PurePath):
        return str(value)
    if hasattr(value, "params") and hasattr(value, "name") and callable(value.params):
        return {"name": value.name, **jsonable(value.params(), where=where)}
    if is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: jsonable(getattr(value, f.name), where=f"{where}.{f.name}")
            for f in fields(value)
        }
    raise TypeError(
        f"{where}: {type(value).__name__} {value!r} has no JSON form; the style's kit exporter "
        "must export it (a texture file, a number or a list)"
    )


def find_strings(value: Any, wanted: set[str], *, where: str = "params") -> list[str]:
    """Key paths in JSON data ``value`` whose string value is one of ``wanted``."""
    out: list[str] = []
    if isinstance(value, str):
        if value in wanted:
            out.append(f"{where} = {value!r}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += find_strings(v, wanted, where=f"{where}[{i}]")
    elif isinstance(value, dict):
        for k, v in value.items():
            out += find_strings(v, wanted, where=f"{where}.{k}")
    return out
