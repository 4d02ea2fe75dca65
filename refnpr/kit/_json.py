"""JSON in the kit: conversion of parameter values to plain JSON (lists, numbers, strings,
bools, null), writing it, and reading untrusted JSON with a depth limit."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import fields, is_dataclass
from pathlib import Path, PurePath
from typing import Any

import numpy as np

from ..image import atomic_file

__all__ = ["jsonable", "find_strings", "json_depth", "load_json", "write_json"]


def write_json(path: str | Path, data: Any) -> Path:
    """Write JSON (2-space indent, UTF-8, newline at the end) atomically."""
    path = Path(path)
    with atomic_file(path, suffix=".json") as tmp:
        tmp.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return path


def jsonable(value: Any, *, where: str = "params", nonfinite_as_none: bool = False) -> Any:
    """``value`` as JSON data: tuples and arrays become lists, numpy scalars Python numbers,
    dataclasses and styles dicts (a style: ``{"name": ..., **params}``), paths strings.

    Raises
    ------
    TypeError
        Naming ``where`` (the key path) for a value with no JSON form.
    ValueError
        For NaN or infinite floats (JSON has none), naming ``where``; unless
        ``nonfinite_as_none``, which writes them as null.
    """

    def conv(v: Any, w: str) -> Any:
        return jsonable(v, where=w, nonfinite_as_none=nonfinite_as_none)

    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isfinite(v) or nonfinite_as_none:
            return v if math.isfinite(v) else None
        raise ValueError(f"{where}: {v!r} has no JSON form; resolve it to a finite number")
    if isinstance(value, np.ndarray):
        return conv(value.tolist(), where)
    if isinstance(value, (list, tuple)):
        return [conv(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, Mapping):
        return {str(k): conv(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, np.dtype) or (isinstance(value, type) and issubclass(value, np.generic)):
        return np.dtype(value).name  # e.g. rasterize's dtype=np.float64 -> "float64"
    if isinstance(value, PurePath):
        return str(value)
    if hasattr(value, "params") and hasattr(value, "name") and callable(value.params):
        return {"name": value.name, **conv(value.params(), where)}
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: conv(getattr(value, f.name), f"{where}.{f.name}") for f in fields(value)}
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


def json_depth(value: Any) -> int:
    """How deeply JSON data nests: 0 for a scalar, 1 for ``[]`` or ``{"a": 1}``, 2 for
    ``[[1]]``; measured without recursion (any depth)."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict):
            v = list(v.values())
        if isinstance(v, list):
            deepest = max(deepest, d)
            stack.extend((x, d + 1) for x in v)
    return deepest


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a JSON number; write a finite number")


def _finite(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError(f"{text[:40]} overflows a float64; write a finite number")
    return v


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"the key {k!r} appears twice in one object; keys must be unique")
        out[k] = v
    return out


def load_json(data: bytes, *, what: str, max_depth: int, finite: bool = False) -> Any:
    """Parse untrusted JSON bytes (UTF-8).

    Parameters
    ----------
    data : bytes
        The file's contents (the caller bounds their size).
    what : str
        What the data is (a file name), the start of every message.
    max_depth : int
        Deepest nesting of arrays and objects allowed (see :func:`json_depth`).
    finite : bool
        Refuse ``NaN``, ``Infinity`` and numbers that overflow a float64 (else they are read
        as floats, below).

    Returns
    -------
    The parsed value. ``NaN``, ``Infinity`` and ``-Infinity`` (which JSON lacks) are read as
    floats so that the caller's range check names the key that holds them.

    Raises
    ------
    ValueError
        Naming ``what``: not UTF-8, not JSON (with line and column), a key repeated in one
        object, or nested deeper than ``max_depth`` (also when deeper than Python's recursion
        limit: no RecursionError escapes).
    """
    too_deep = (
        f"{what}: JSON nested deeper than {max_depth} levels of arrays and objects; "
        "a kit file never nests that deep"
    )
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"{what}: not UTF-8 text (byte {exc.start}: {exc.reason}); expected a JSON file"
        ) from None
    try:
        hooks = {"parse_constant": _no_constant, "parse_float": _finite} if finite else {}
        value = json.loads(text, object_pairs_hook=_unique_keys, **hooks)
    except RecursionError:
        raise ValueError(too_deep) from None
    except ValueError as exc:  # JSONDecodeError, a repeated key, an over-long integer
        raise ValueError(f"{what}: not valid JSON: {exc}") from None
    if json_depth(value) > max_depth:
        raise ValueError(too_deep)
    return value
