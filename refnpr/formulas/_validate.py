"""Input validation shared by the formula modules (imports nothing else of refnpr).

Conventions: float32 in -> float32 out (if every floating input is float32, or a Python scalar
beside float32 arrays); anything else computes in float64. Errors name the parameter, the value
received, what was expected and how to fix it.
"""

from __future__ import annotations

import numbers

import numpy as np

__all__ = [
    "as_float",
    "result_dtype",
    "check_finite",
    "check_scalar",
    "to_float",
    "BEYOND_FLOAT_RANGE",
    "check_int",
    "check_bool",
    "as_ints",
    "INT64_MIN",
    "INT64_MAX",
    "describe",
]

#: The range of int64, the integer type the faces and the kernels compute in.
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1


def describe(value) -> str:
    """Short description of a value for an error message."""
    if isinstance(value, np.ndarray):
        if value.size <= 4:
            return f"array {value.tolist()!r} ({value.dtype})"
        return f"array of shape {value.shape} ({value.dtype})"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


#: How messages name a Python int that float() refuses (``OverflowError``): about 309 digits.
BEYOND_FLOAT_RANGE = "an integer beyond the float range (|value| > 1.8e308)"


def to_float(name: str, value) -> float:
    """``float(value)`` of a real number ``value``; an integer beyond the float range (a Python
    int of about 309 digits or more, where ``float`` raises ``OverflowError``) is a
    ``ValueError`` naming ``name``. NaN and inf pass: the caller checks finiteness."""
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name}: expected a finite number, got {BEYOND_FLOAT_RANGE}") from None


def as_float(name: str, value, *, finite: bool = False) -> np.ndarray:
    """``value`` as a float ndarray: float32 stays float32, every other real type becomes float64.

    Raises ``TypeError`` for non-numeric, boolean-free complex or object input and, with
    ``finite=True``, ``ValueError`` for NaN or inf.
    """
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name}: expected a real number or array, got {describe(value)}")
    arr = np.asarray(value)
    if arr.dtype.kind == "c":
        raise TypeError(
            f"{name}: expected real values, got complex {describe(value)}; take .real first"
        )
    if arr.dtype.kind not in "biuf":
        raise TypeError(
            f"{name}: expected a real number or numeric array, got {describe(value)}; "
            "convert with numpy.asarray(..., dtype=float)"
        )
    arr = arr.astype(np.float32 if arr.dtype == np.float32 else np.float64, copy=False)
    if finite:
        check_finite(name, arr)
    return arr


def as_vectors(name: str, value, k: int, *, finite: bool = False, hint: str = "") -> np.ndarray:
    """``value`` as a float array of ``k``-vectors in its last axis, shape ``(..., k)``
    (:func:`as_float`; ``ValueError`` naming ``name`` for another shape)."""
    arr = as_float(name, value, finite=finite)
    if arr.ndim < 1 or arr.shape[-1] != k:
        raise ValueError(f"{name}: expected shape (..., {k}), got {describe(arr)}" + hint)
    return arr


def result_dtype(*values) -> np.dtype:
    """float32 if every array-valued floating input is float32 (Python scalars do not promote);
    float64 otherwise."""
    arrays = [v for v in values if isinstance(v, np.ndarray) or isinstance(v, np.floating)]
    if arrays and all(np.asarray(v).dtype == np.float32 for v in arrays):
        return np.dtype(np.float32)
    return np.dtype(np.float64)


def check_finite(name: str, arr: np.ndarray) -> None:
    """Raise ``ValueError`` if ``arr`` holds NaN or inf."""
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.isfinite(np.ravel(arr)))[0]
        raise ValueError(
            f"{name}: must be finite, got {np.ravel(arr)[bad]} at flat index {bad}; "
            "remove NaN/inf before calling"
        )


def check_scalar(
    name: str,
    value,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
    hint: str = "",
) -> float:
    """Validate a real scalar parameter in the interval given by ``lo``/``hi`` and return it."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
            value = value.item()
        else:
            raise TypeError(f"{name}: expected a real number, got {describe(value)}")
    v = to_float(name, value)
    if not np.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    bad = (lo is not None and (v <= lo if lo_open else v < lo)) or (
        hi is not None and (v >= hi if hi_open else v > hi)
    )
    if bad:
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        interval = f"{left}{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}{right}"
        raise ValueError(
            f"{name}: expected a value in {interval}, got {v}" + (f"; {hint}" if hint else "")
        )
    return v


def check_bool(name: str, value) -> bool:
    """Validate a flag: ``True`` or ``False`` (a numpy bool too), returned as a Python bool.

    Anything else is a ``TypeError``: a string such as ``"no"`` or a number would otherwise be
    taken by its truth value.
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise TypeError(f"{name}: expected a bool (True or False), got {describe(value)}")


def _int_range(lo: int | None, hi: int | None) -> tuple[int, int, str]:
    """The bounds to check (a None bound: int64's) and the interval to name in a message (a None
    bound: -inf / inf)."""
    text = f"[{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]"
    return (INT64_MIN if lo is None else lo), (INT64_MAX if hi is None else hi), text


def _int_hint(v: int, lo: int | None, hi: int | None, hint: str) -> str:
    if (lo is None and v < INT64_MIN) or (hi is None and v > INT64_MAX):
        hint = (
            "the formulas compute in int64, where an integer outside [-2**63, 2**63 - 1] overflows"
        )
    return f"; {hint}" if hint else ""


def check_int(
    name: str, value, *, lo: int | None = None, hi: int | None = None, hint: str = ""
) -> int:
    """Validate an integer parameter (bools rejected) in [lo, hi] and return it.

    A bound left None is int64's on that side (:data:`INT64_MIN`, :data:`INT64_MAX`): the
    faces pass integers to numba and numpy as int64, where a larger one would overflow.
    """
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral,)):
        raise TypeError(f"{name}: expected an integer, got {describe(value)}")
    v = int(value)
    lo_, hi_, interval = _int_range(lo, hi)
    if v < lo_ or v > hi_:
        raise ValueError(
            f"{name}: expected an integer in {interval}, got {v}" + _int_hint(v, lo, hi, hint)
        )
    return v


def as_ints(
    name: str, value, *, lo: int | None = None, hi: int | None = None, hint: str = ""
) -> np.ndarray:
    """``value`` as an int64 ndarray of integers in [lo, hi] (bounds as :func:`check_int`).

    Raises ``TypeError`` naming ``name`` for non-integer input (floats, bools, strings, objects)
    and ``ValueError`` for a value outside [lo, hi] (also an unsigned one past int64), naming
    the first such value and its flat index.
    """
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name}: expected integers, got {describe(value)}")
    arr = np.asarray(value)
    if arr.dtype.kind not in "iu":
        raise TypeError(
            f"{name}: expected integers, got {describe(value)}; "
            "convert with numpy.asarray(..., dtype=numpy.int64)"
        )
    lo_, hi_, interval = _int_range(lo, hi)
    info = np.iinfo(arr.dtype)
    bad = np.zeros(arr.shape, dtype=bool)
    if lo_ > info.min:  # a bound inside the dtype's range: compared in the dtype
        bad |= arr < lo_
    if hi_ < info.max:
        bad |= arr > hi_
    if np.any(bad):
        at = int(np.flatnonzero(np.ravel(bad))[0])
        v = int(np.ravel(arr)[at])
        raise ValueError(
            f"{name}: expected integers in {interval}, got {v} at flat index {at}"
            + _int_hint(v, lo, hi, hint)
        )
    return arr.astype(np.int64)
