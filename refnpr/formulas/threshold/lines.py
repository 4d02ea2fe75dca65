"""Veryovka 2002 eqs. 3-8: step functions, dyadic scale and re-mapping, multi-scale line function.

Public names are re-exported by :mod:`refnpr.formulas.threshold`; see its docstring for the
conventions.
"""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit

from .._face import elementwise, face
from .._shading_checks import (
    broadcast,
    check_positive,
    check_range,
    floor_int,
    frac,
    one_below,
    real,
    scaled_frac,
)
from .._validate import check_int, result_dtype

__all__ = [
    "step",
    "step_n",
    "dyadic_scale",
    "dyadic_scale_from_gradient",
    "dyadic_remap",
    "multiscale_line",
    "multiscale_line_cdf",
    "line_threshold",
]


# ---------------------------------------------------------------- unvalidated kernels (private)


@njit
def _step(x, t):
    return 1.0 if x >= t else 0.0  # eq. 3: 0 where x < t, 1 otherwise


@njit
def _step_n(x, t, n):
    xn = x * n
    whole = np.floor(xn)
    levels = whole + (1.0 if xn - whole >= t else 0.0)  # eq. 4: floor(x n) + T(Frac(x n), t)
    top = np.ceil(xn)  # bounded by ceil(x n): eq. 4 jumps a level above x at t <= 0, x n whole
    return (levels if levels <= top else top) / n  # eq. 4, divided by n


@njit
def step_any(x, t, n):
    """T(x, t) (eq. 3) for n == 1, T_n(x, t) (eq. 4) otherwise (device function)."""
    return _step(x, t) if n == 1 else _step_n(x, t, n)


def step_kernel(x: np.ndarray, t: np.ndarray, n: int) -> np.ndarray:
    """:func:`step_any` over broadcast arrays, float64 (no validation)."""
    x = np.asarray(x, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    return elementwise(step_any, np.float64, x, t, int(n))


def multiscale_kernel(v: np.ndarray, t: np.ndarray, uniform: bool) -> np.ndarray:
    """F(v, t) of eqs. 7-8 (base f(v) = v) for v in [0, 1), t in [0, 1]; result in [0, 1)."""
    v1 = np.where(v < 0.5, 2 * v, 2 * v - 1)  # eq. 7: F(v, 1)
    if uniform:
        a = (1 - t) / (2 * (1 + t))  # F(., t)'s CDF applied to F(., t): slopes 1, 2, 2, 1
        b = 1 - a
        f = np.where(v < a, v, np.where(v < 0.5, 2 * v - a, np.where(v < b, 2 * v - b, v)))
    else:
        f = (1 - t) * v + t * v1  # eq. 8
    return np.clip(f, 0, one_below(f.dtype))


def scale_split(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(floor(s) as clipped int64, t = Frac(s) in [0, 1]) for finite s."""
    return floor_int(s), s - np.floor(s)


# ---------------------------------------------------------------------------- public functions


@face(_step)
def step(x, t) -> np.ndarray:
    """Threshold function T(x, t) of Veryovka eq. 3: 0 where ``x < t``, 1 otherwise.

    ``step.scalar(x, t)`` is the device function.

    Parameters
    ----------
    x : array_like
        Continuous shading value (e.g. a diffuse term).
    t : array_like
        Threshold, e.g. a threshold texture; broadcasts against ``x``.

    Returns
    -------
    ndarray of 0.0 / 1.0 with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(x, t)
    x = real("x", x, dt)
    t = real("t", t, dt)
    broadcast(x=x, t=t)
    return elementwise(step.scalar, dt, x, t)


@face(_step_n)
def step_n(x, t, n: int) -> np.ndarray:
    """n-level step function T_n(x, t) of Veryovka eq. 4: ``(floor(x n) + T(Frac(x n), t)) / n``.

    For x in [0, 1] the result takes the n + 1 values k / n (n + 1 discrete colours), always
    floor(x n) / n or ceil(x n) / n (refnpr bounds eq. 4 by ceil(x n) / n, which matters only
    for t = 0 at x n integer, where eq. 4 jumps a level above x); with t uniform on (0, 1) its
    mean over t is x (tone preservation). ``step_n.scalar(x, t, n)`` is the device function.

    Parameters
    ----------
    x : array_like
        Continuous shading value.
    t : array_like
        Threshold in [0, 1]; broadcasts against ``x``.
    n : int >= 1
        Number of steps (n = 1 is eq. 3 for x in [0, 1]).

    Returns
    -------
    ndarray with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    n = check_int("n", n, lo=1)
    dt = result_dtype(x, t)
    x = real("x", x, dt)
    t = real("t", t, dt)
    broadcast(x=x, t=t)
    return elementwise(step_n.scalar, dt, x, t, n)  # eq. 4


def dyadic_scale(d, w) -> np.ndarray:
    """Dyadic texture scale of Veryovka eq. 5: ``s = log2(d / w)``.

    Parameters
    ----------
    d : array_like, > 0
        Screen distance in pixels between the iso-lines v and v + 1 of the coordinate the lines
        are a function of (v; the paper's text says u, see docs/paper-notes.md).
    w : array_like, > 0
        Desired line period in pixels.

    Returns
    -------
    ndarray s with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(d, w)
    d = real("d", d, dt)
    w = real("w", w, dt)
    check_positive("d", d, "d is a distance between iso-lines in pixels; mask empty pixels")
    check_positive("w", w, "w is the desired line period in pixels, e.g. 8")
    broadcast(d=d, w=w)
    return np.asarray(np.log2(d) - np.log2(w), dtype=dt)  # eq. 5 (no overflow in d / w)


def dyadic_scale_from_gradient(dv_dx, dv_dy, w) -> np.ndarray:
    """Eq. 5 with d = 1 / |grad v|: ``s = -log2(w * |(dv/dx, dv/dy)|)``.

    A zero gradient (v constant on screen) is clamped to the smallest normal float of the dtype,
    so s stays finite (about 1022 in float64, 126 in float32) instead of +inf.

    Parameters
    ----------
    dv_dx, dv_dy : array_like
        Screen derivatives of the line coordinate v, per pixel.
    w : array_like, > 0
        Desired line period in pixels.

    Returns
    -------
    ndarray s with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(dv_dx, dv_dy, w)
    gx = real("dv_dx", dv_dx, dt)
    gy = real("dv_dy", dv_dy, dt)
    w = real("w", w, dt)
    check_positive("w", w, "w is the desired line period in pixels, e.g. 8")
    broadcast(dv_dx=gx, dv_dy=gy, w=w)
    g = np.maximum(np.hypot(gx, gy), np.finfo(dt).tiny)
    return np.asarray(-(np.log2(g) + np.log2(w)), dtype=dt)  # eq. 5, d = 1 / |grad v|


def dyadic_remap(v, s) -> np.ndarray:
    """Dyadic re-mapping of Veryovka eq. 6, read as ``Frac(v * 2**floor(s))``.

    The paper prints ``Frac(v|s|)``; the scale meant is 2**floor(s) (docs/paper-notes.md).
    Products that overflow are integers and map to 0, so huge s or v never give NaN.

    Parameters
    ----------
    v : array_like
        Line coordinate in texture units.
    s : array_like
        Dyadic scale (eq. 5); broadcasts against ``v``.

    Returns
    -------
    ndarray in [0, 1) with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(v, s)
    v = real("v", v, dt)
    s = real("s", s, dt)
    broadcast(v=v, s=s)
    return np.asarray(scaled_frac(v, floor_int(s)), dtype=dt)  # eq. 6


def multiscale_line(v, t, *, uniform: bool = False) -> np.ndarray:
    """Multi-scale line function F(v, t) of Veryovka eqs. 7-8 with base f(v) = v.

    ``F(v, 0) = Frac(v)``, ``F(v, 1) = Frac(2 v)`` (eq. 7) and ``F(v, t) = (1 - t) F(v, 0) +
    t F(v, 1)`` (eq. 8). Contrary to the paper, F(., t) is not uniform for 0 < t < 1: its density
    is 2 / (1 + t) on [(1 - t) / 2, (1 + t) / 2) and 1 / (1 + t) elsewhere (see
    :func:`multiscale_line_cdf`). ``uniform=True`` returns G(F(v, t), t) with G that CDF: uniform
    for every t, strictly increasing in F (same line order, minima and maxima where F has them)
    and equal to F at t = 0 and t = 1. It is piecewise linear in v with slopes 1, 2, 2, 1.

    Parameters
    ----------
    v : array_like
        Coordinate; only Frac(v) matters (period 1).
    t : array_like in [0, 1]
        Scale blend, Frac(s); broadcasts against ``v``.
    uniform : bool, keyword-only
        Apply the tone-preserving correction.

    Returns
    -------
    ndarray in [0, 1) with the broadcast shape; float64, or float32 if the inputs are float32.
    Float32 agrees with float64 on the same inputs to 1e-6 except within 1e-6 of the jumps at
    Frac(v) = 0 and 0.5.
    """
    dt = result_dtype(v, t)
    v = real("v", v, dt)
    t = real("t", t, dt)
    check_range("t", t, 0.0, 1.0, "t is the fractional part of the dyadic scale")
    broadcast(v=v, t=t)
    return np.asarray(multiscale_kernel(frac(v), t, uniform), dtype=dt)


def multiscale_line_cdf(y, t) -> np.ndarray:
    """CDF G(y, t) of the paper's F(., t) (eq. 8) over one period of v.

    ``G = y / (1 + t)`` below (1 - t) / 2, ``(2 y - (1 - t) / 2) / (1 + t)`` up to (1 + t) / 2
    and ``(y + t) / (1 + t)`` above; G(y, 0) = G(y, 1) = y. The paper's claim of a uniform
    distribution holds only at t = 0 and t = 1.

    Parameters
    ----------
    y : array_like
        Threshold value (clipped to [0, 1]).
    t : array_like in [0, 1]
        Scale blend; broadcasts against ``y``.

    Returns
    -------
    ndarray in [0, 1] with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(y, t)
    y = real("y", y, dt)
    t = real("t", t, dt)
    check_range("t", t, 0.0, 1.0, "t is the fractional part of the dyadic scale")
    broadcast(y=y, t=t)
    y = np.clip(y, 0, 1)
    lo = (1 - t) / 2
    hi = (1 + t) / 2
    g = np.where(y < lo, y / (1 + t), np.where(y < hi, (2 * y - lo) / (1 + t), (y + t) / (1 + t)))
    return np.asarray(np.clip(g, 0, 1), dtype=dt)


def line_threshold(v, s, *, uniform: bool = False, noise=None) -> np.ndarray:
    """Multi-scale line threshold texture of Veryovka sec. 3.2 at continuous dyadic scale s.

    ``F(Frac(v * 2**floor(s)), Frac(s))`` (eqs. 6-8): lines of constant screen period between w
    and 2 w pixels (eq. 5), and no jump where s crosses an integer (F at t = 1 equals F at the
    next scale with t = 0). Threshold an intensity against it with :func:`step`: white where
    ``intensity >= line_threshold``; the black line fraction of a period is 1 - intensity (with
    ``uniform=True``; the paper's blend drifts at intermediate scales).

    Parameters
    ----------
    v : (...) array
        Line coordinate in texture units (the lines are iso-lines of v).
    s : (...) array
        Dyadic scale of eq. 5 (e.g. :func:`dyadic_scale_from_gradient` or the G-buffer
        ``dyadic_scale`` channel); broadcasts against ``v``.
    uniform : bool, keyword-only
        Use the tone-preserving correction of :func:`multiscale_line`.
    noise : (...) array or None, keyword-only
        Phase modulation in line periods: the result is ``Frac(F + noise)``. Tone preserving
        (a shifted uniform variable mod 1 is uniform), continuous across scales, and for the
        sawtooth a lateral displacement of the lines by ``noise`` periods (wobbly lines when
        ``noise`` is a smooth noise texture of amplitude ~0.1-0.3).

    Returns
    -------
    (...) ndarray in [0, 1); float64, or float32 if the inputs are float32. Float32 agrees with
    float64 on the same inputs to 1e-6 except within 1e-6 of the jumps of the sawtooth.
    """
    extra = () if noise is None else (noise,)
    dt = result_dtype(v, s, *extra)
    v = real("v", v, dt)
    s = real("s", s, dt)
    named = {"v": v, "s": s}
    if noise is not None:
        noise = real("noise", noise, dt)
        named["noise"] = noise
    broadcast(**named)
    k, t = scale_split(s)
    f = multiscale_kernel(scaled_frac(v, k), t, uniform)  # eqs. 6-8
    if noise is not None:
        f = frac(f + noise)
    return np.asarray(f, dtype=dt)
