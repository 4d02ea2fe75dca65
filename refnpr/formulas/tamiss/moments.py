"""Per-fragment regressors and exact aggregation by stroke id (TAMISS sec. 3.2 and sec. 4).

Private helper of :mod:`refnpr.formulas.tamiss` (which re-exports the public names).
"""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit

from .._face import elementwise, face
from .._validate import as_float, describe, result_dtype

__all__ = ["N_REGRESSORS", "fragment_regressors", "normalize_t", "aggregate"]

#: Per-fragment regressors: s^0..s^6 (7), s^0..s^3 x (4), s^0..s^3 y (4).
N_REGRESSORS = 15


@njit
def _fragment_regressors(s, x, y, one):
    p2 = s * s
    p3 = p2 * s
    p4 = p3 * s
    p5 = p4 * s
    # eq. 1: t_i t_i^T (as power sums), t_i x_i, t_i y_i
    return (one, s, p2, p3, p4, p5, p5 * s, x, s * x, p2 * x, p3 * x, y, s * y, p2 * y, p3 * y)


@face(_fragment_regressors)
def fragment_regressors(s, x, y) -> np.ndarray:
    """The terms one fragment adds to its stroke's sums (sec. 3.2, after eq. 1).

    ``fragment_regressors.scalar(s, x, y, one)`` is the device function (``one``: 1 in the
    float type of s, x, y; it computes in that type).

    Parameters
    ----------
    s : (n,) float, stroke parameter (centred s, or raw t for the paper's basis)
    x, y : (n,) float, screen position in pixels

    Returns
    -------
    (n, 15): s^0 .. s^6, s^0 x .. s^3 x, s^0 y .. s^3 y; dtype float32 if all inputs are float32.
    """
    s_, x_, y_ = (as_float(k, v, finite=True) for k, v in (("s", s), ("x", x), ("y", y)))
    dt = result_dtype(s_, x_, y_)
    try:
        np.broadcast_shapes(s_.shape, x_.shape, y_.shape)
    except ValueError:
        raise ValueError(
            f"s, x, y: expected equal shapes, got {np.shape(s)}, {np.shape(x)}, {np.shape(y)}"
        ) from None
    return elementwise(fragment_regressors.scalar, dt, s_, x_, y_, dt.type(1), compute=dt)


@njit
def _normalize_t(t, lo, hi, half_c):
    half = (hi - lo) * half_c
    if half == np.inf:  # t_max - t_min overflows; their halves' difference does not
        half = hi * half_c - lo * half_c
    if half > 0:
        return (t - (lo + half)) / half
    return half_c - half_c  # a single t: s = 0


@face(_normalize_t)
def normalize_t(t, t_min, t_max) -> np.ndarray:
    """s = (2 t - t_min - t_max) / (t_max - t_min), so [t_min, t_max] maps to [-1, 1].

    Computed as (t - c) / h with h = (t_max - t_min) / 2 (t_max / 2 - t_min / 2 where the
    difference overflows), c = t_min + h. Where t_max == t_min, s = 0. Inputs broadcast;
    float32 in -> float32 out (float32 arithmetic).
    ``normalize_t.scalar(t, t_min, t_max, half)`` is the device function (``half``: 0.5 in
    the float type of its arguments).
    """
    t_ = as_float("t", t, finite=True)
    lo = as_float("t_min", t_min, finite=True)
    hi = as_float("t_max", t_max, finite=True)
    if np.any(lo > hi):
        raise ValueError(
            f"t_min, t_max: expected t_min <= t_max, got {describe(lo)}, {describe(hi)}; swap them"
        )
    dt = result_dtype(t, t_min, t_max)  # Python scalars do not promote float32
    return elementwise(normalize_t.scalar, dt, t_, lo, hi, dt.type(0.5), compute=dt)


def group_ids(ids):
    """Sort fragments by id: (distinct ids, sort order, group starts, inverse index)."""
    arr = np.asarray(ids)
    if arr.dtype.kind not in "iu" or arr.ndim != 1:
        raise TypeError(f"ids: expected a 1D integer array of stroke ids, got {describe(arr)}")
    order = np.argsort(arr, kind="stable")
    sorted_ids = arr[order]
    if arr.size == 0:
        return sorted_ids, order, np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    starts = np.concatenate([[0], np.flatnonzero(sorted_ids[1:] != sorted_ids[:-1]) + 1])
    inverse = np.empty(arr.size, dtype=np.intp)
    inverse[order] = np.repeat(np.arange(starts.size), np.diff(np.append(starts, arr.size)))
    return sorted_ids[starts], order, starts, inverse


_REDUCERS = {"sum": np.add, "min": np.minimum, "max": np.maximum}


def aggregate(ids, values, *, op: str = "sum"):
    """Exact aggregation of per-fragment values by stroke id (sec. 3.1 "summation", sec. 4).

    Fragments are sorted by id (stably, so the summation order is the input order within a
    stroke) and reduced with ``numpy.ufunc.reduceat``: no hashing, no collisions, deterministic.

    Parameters
    ----------
    ids : (n,) int, stroke id per fragment
    values : (n, ...) float
    op : {"sum", "min", "max"}

    Returns
    -------
    stroke_ids : (S,) the distinct ids, ascending
    reduced : (S, ...) same dtype as ``values`` (sums accumulate in that dtype, like GPU blending)
    """
    if op not in _REDUCERS:
        raise ValueError(f"op: expected 'sum', 'min' or 'max', got {op!r}")
    v = as_float("values", values)
    uid, order, starts, _ = group_ids(ids)
    if v.ndim < 1 or v.shape[0] != np.asarray(ids).shape[0]:
        raise ValueError(
            f"values: expected {np.asarray(ids).shape[0]} rows (one per fragment), got "
            f"{describe(v)}"
        )
    if uid.size == 0:
        return uid, np.zeros((0,) + v.shape[1:], dtype=v.dtype)
    return uid, _REDUCERS[op].reduceat(v[order], starts, axis=0)
