"""Validation of texture and screen parameters (private): messages name the parameter, the value
received and what is expected."""

from __future__ import annotations

import math

import numpy as np


def _int(name: str, value, lo: int, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if value < lo or (hi is not None and value > hi):
        rng = f"[{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise ValueError(f"{name}: expected an integer {rng}, got {value}")
    return int(value)


def _real(name: str, value, lo: float, hi: float | None = None, *, lo_open: bool = False):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__} {value!r}")
    v = float(value)
    if not math.isfinite(v) or (v <= lo if lo_open else v < lo) or (hi is not None and v > hi):
        lo_s = f"> {lo}" if lo_open else f">= {lo}"
        hi_s = f" and <= {hi}" if hi is not None else ""
        raise ValueError(f"{name}: expected a finite number {lo_s}{hi_s}, got {value!r}")
    return v


def _pow2(name: str, value, lo: int, hi: int) -> int:
    v = _int(name, value, lo, hi)
    if v & (v - 1):
        raise ValueError(f"{name}: expected a power of two in [{lo}, {hi}], got {v}")
    return v


def _image_shape(name: str, a: np.ndarray) -> None:
    if a.ndim not in (2, 3) or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(
            f"{name}: expected a (rows, cols) or (rows, cols, C) image, got shape {a.shape}"
        )
