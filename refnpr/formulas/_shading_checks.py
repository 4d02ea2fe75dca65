"""Private helpers of ``threshold``, ``halftone`` and ``lighting``: array checks and exact
fractional parts. Imports nothing of refnpr but ``_validate``.
"""

from __future__ import annotations

import numpy as np

from ._validate import as_float, result_dtype


def real(name: str, value, dtype: np.dtype) -> np.ndarray:
    """``value`` as a finite float array of ``dtype`` (TypeError/ValueError naming ``name``)."""
    return as_float(name, value, finite=True).astype(dtype, copy=False)


def reals(compute=None, /, **values) -> tuple:
    """``(dtype, *arrays)``: the result dtype of the named ``values`` and each of them as a
    finite float array (:func:`real`; of ``compute`` if given, else of that dtype) whose shapes
    broadcast together (:func:`broadcast`)."""
    dt = result_dtype(*values.values())
    arrays = {k: real(k, v, np.dtype(compute or dt)) for k, v in values.items()}
    broadcast(**arrays)
    return (dt, *arrays.values())


def broadcast(**arrays: np.ndarray) -> tuple[int, ...]:
    """The broadcast shape of the named arrays, or a ``ValueError`` naming every one of them."""
    try:
        return np.broadcast_shapes(*(np.shape(a) for a in arrays.values()))
    except ValueError:
        shapes = ", ".join(f"{k} {np.shape(a)}" for k, a in arrays.items())
        raise ValueError(
            f"{', '.join(arrays)}: shapes do not broadcast ({shapes}); pass arrays of one shape, "
            "or shapes that numpy broadcasts (e.g. (H, W) with (H, W), (W,) or a scalar)"
        ) from None


def check_range(name: str, arr: np.ndarray, lo: float, hi: float, hint: str) -> None:
    """Raise ``ValueError`` unless every value of ``arr`` lies in [lo, hi]."""
    bad = (arr < lo) | (arr > hi)
    if np.any(bad):
        i = int(np.flatnonzero(np.ravel(bad))[0])
        raise ValueError(
            f"{name}: expected values in [{lo}, {hi}], got {np.ravel(arr)[i]} at flat index {i}; "
            + hint
        )


def check_positive(name: str, arr: np.ndarray, hint: str) -> None:
    """Raise ``ValueError`` unless every value of ``arr`` is > 0."""
    bad = ~(arr > 0)
    if np.any(bad):
        i = int(np.flatnonzero(np.ravel(bad))[0])
        raise ValueError(
            f"{name}: expected values > 0, got {np.ravel(arr)[i]} at flat index {i}; " + hint
        )


def trailing(name: str, arr: np.ndarray, size: int, what: str) -> None:
    """Raise ``ValueError`` unless ``arr`` has a trailing axis of length ``size``."""
    if arr.ndim == 0 or arr.shape[-1] != size:
        raise ValueError(
            f"{name}: expected shape (..., {size}) ({what}), got shape {arr.shape}; "
            f"stack the {size} components on the last axis"
        )


def one_below(dtype: np.dtype):
    """The largest float of ``dtype`` below 1."""
    one = np.dtype(dtype).type(1)
    return np.nextafter(one, np.dtype(dtype).type(0))


def frac(x: np.ndarray) -> np.ndarray:
    """Frac(x) = x - floor(x) in [0, 1) for finite x.

    Exact except where x is a tiny negative number and x - floor(x) rounds to 1; that case returns
    the largest float below 1 (the nearest value of the half-open range).
    """
    r = x - np.floor(x)
    return np.minimum(r, one_below(r.dtype))


def scaled_lengths(vec: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(m, w, |w|)`` of vectors along the last axis: the largest |component| ``m``, the
    vectors divided by it ``w`` (zero vectors stay zero) and their lengths, each keeping the
    last axis (length 1 for ``m`` and ``|w|``). ``|vec| = m |w|`` without overflow or underflow
    on the way."""
    m = np.max(np.abs(vec), axis=-1, keepdims=True)
    w = vec / np.where(m > 0, m, 1)
    return m, w, np.sqrt(np.sum(w * w, axis=-1, keepdims=True))


def unit_vectors(vec: np.ndarray) -> np.ndarray:
    """``vec / |vec|`` along the last axis without overflow; zero vectors stay zero."""
    _, w, length = scaled_lengths(vec)
    return w / np.where(length > 0, length, 1)
