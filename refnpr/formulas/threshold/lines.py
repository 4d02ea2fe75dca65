"""Veryovka 2002 eqs. 3-8: step functions, dyadic scale and re-mapping, multi-scale line function
(conventions: :mod:`refnpr.formulas.threshold`)."""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import ONE_BELOW, clip, frac

from .._face import elementwise, face
from .._shading_checks import check_positive, check_range, reals
from .._validate import check_bool, check_int

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

#: |floor(s)| beyond this changes nothing: v * 2**k is an integer (k >= 1075) or rounds to 0.
K_MAX = 1100
#: Smallest normal float64: a zero gradient is clamped to it (eq. 5 stays finite).
TINY = float(np.finfo(np.float64).tiny)
#: 2.0 ** k for k in [-POW2_K, POW2_K] (normal floats: v * 2^k is ldexp(v, k), one rounding).
POW2_K = 1000
POW2 = np.array([2.0**k for k in range(-POW2_K, POW2_K + 1)], dtype=np.float64)
#: Most steps of T_n (eq. 4): x n and k / n are formed in float64, where every integer up to
#: 2^53 is exact.
N_MAX = 2**53


def check_steps(n) -> int:
    """The number of steps ``n`` of T_n as an int in [1, :data:`N_MAX`] (``TypeError`` /
    ``ValueError`` naming ``n`` otherwise)."""
    return check_int("n", n, lo=1, hi=N_MAX, hint="T_n counts its steps in float64")


# ------------------------------------------------------------------ device helpers (private)


@njit(inline="always")
def ldexp(v, k):
    """``v 2^k`` for an integer-valued float k: a product by an exact power of two (the
    correctly rounded ``np.ldexp``) where 2^k is a normal float, else ``math.ldexp``."""
    if -POW2_K <= k <= POW2_K:
        return v * POW2[int(k) + POW2_K]
    return math.ldexp(v, int(k))


@njit(inline="always")
def level(s):
    """``floor(s)`` clipped to [-K_MAX, K_MAX] (a float), the dyadic level of scale s."""
    return clip(np.floor(s), -K_MAX, K_MAX)


@njit(inline="always")
def below_one(f):
    """``f`` clamped to [0, 1): the range of a threshold texture."""
    if f < 0.0:
        f = 0.0
    return f if f <= ONE_BELOW else ONE_BELOW


# ---------------------------------------------------------------------------- eqs. 3 and 4


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
    dt, x, t = reals(x=x, t=t)
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
    n : int in [1, 2**53]
        Number of steps (n = 1 is eq. 3 for x in [0, 1]); x n is formed in float64.

    Returns
    -------
    ndarray with the broadcast shape; float64, or float32 if the inputs are float32.
    """
    n = check_steps(n)
    dt, x, t = reals(x=x, t=t)
    return elementwise(step_n.scalar, dt, x, t, n)  # eq. 4


# ---------------------------------------------------------------------------- eqs. 5 and 6


@njit
def _dyadic_scale(d, w):
    return math.log2(d) - math.log2(w)  # eq. 5: log2(d / w), no overflow in d / w


@face(_dyadic_scale)
def dyadic_scale(d, w) -> np.ndarray:
    """Dyadic texture scale of Veryovka eq. 5: ``s = log2(d / w)``.

    ``dyadic_scale.scalar(d, w)`` is the device function.

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
    dt, d, w = reals(d=d, w=w)
    check_positive("d", d, "d is a distance between iso-lines in pixels; mask empty pixels")
    check_positive("w", w, "w is the desired line period in pixels, e.g. 8")
    return elementwise(dyadic_scale.scalar, dt, d, w)


@njit
def _dyadic_scale_from_gradient(gx, gy, log2_w):
    g = math.hypot(gx, gy)
    if not g >= TINY:  # a zero gradient: the smallest normal float (NaN stays NaN)
        g = TINY if g == g else g
    return -(math.log2(g) + log2_w)  # eq. 5, d = 1 / |grad v|


@face(_dyadic_scale_from_gradient)
def dyadic_scale_from_gradient(dv_dx, dv_dy, w) -> np.ndarray:
    """Eq. 5 with d = 1 / |grad v|: ``s = -log2(w * |(dv/dx, dv/dy)|)``.

    A zero gradient (v constant on screen) is clamped to the smallest normal float64, so s
    stays finite (about 1022 - log2(w)) instead of +inf. ``dyadic_scale_from_gradient.scalar(
    dv_dx, dv_dy, log2_w)`` is the device function (``log2_w = log2(w)``, a frame constant).

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
    dt, gx, gy, w = reals(dv_dx=dv_dx, dv_dy=dv_dy, w=w)
    check_positive("w", w, "w is the desired line period in pixels, e.g. 8")
    log2_w = np.log2(w.astype(np.float64))
    return elementwise(dyadic_scale_from_gradient.scalar, dt, gx, gy, log2_w)


@njit(inline="always")
def scaled(v, s):
    """``v 2^floor(s)``, exact unless it under- or overflows; 0 where it overflows (an integer,
    whose Frac is 0)."""
    p = ldexp(v, level(s))
    return p if math.isfinite(p) else 0.0


@njit
def _dyadic_remap(v, s):
    return frac(scaled(v, s))  # eq. 6: Frac(v 2^floor(s))


@face(_dyadic_remap)
def dyadic_remap(v, s) -> np.ndarray:
    """Dyadic re-mapping of Veryovka eq. 6, read as ``Frac(v * 2**floor(s))``.

    The paper prints ``Frac(v|s|)``; the scale meant is 2**floor(s) (docs/paper-notes.md).
    Products that overflow are integers and map to 0, so huge s or v never give NaN.
    ``dyadic_remap.scalar(v, s)`` is the device function.

    Parameters
    ----------
    v : array_like
        Line coordinate in texture units.
    s : array_like
        Dyadic scale (eq. 5); broadcasts against ``v``.

    Returns
    -------
    ndarray in [0, 1) with the broadcast shape; computed in float64, returned as float32 if
    the inputs are float32.
    """
    dt, v, s = reals(v=v, s=s)
    return _below_one(elementwise(dyadic_remap.scalar, dt, v, s))  # eq. 6


def _below_one(a: np.ndarray) -> np.ndarray:
    """A float32 result of a [0, 1) formula kept below 1 (float64 rounding up to 1)."""
    if a.dtype == np.float32:
        np.minimum(a, np.nextafter(np.float32(1), np.float32(0)), out=a)
    return a


# ---------------------------------------------------------------------------- eqs. 7 and 8


@njit(inline="always")
def _multiscale_line(v, t, uniform):
    vr = frac(v)
    if uniform:  # F(., t)'s CDF applied to F(., t): slopes 1, 2, 2, 1
        a = (1 - t) / (2 * (1 + t))
        b = 1 - a
        if vr < a:
            f = vr
        elif vr < 0.5:
            f = 2 * vr - a
        elif vr < b:
            f = 2 * vr - b
        else:
            f = vr
    else:
        v1 = 2 * vr if vr < 0.5 else 2 * vr - 1  # eq. 7: F(v, 1)
        f = (1 - t) * vr + t * v1  # eq. 8
    return below_one(f)


@face(_multiscale_line)
def multiscale_line(v, t, *, uniform: bool = False) -> np.ndarray:
    """Multi-scale line function F(v, t) of Veryovka eqs. 7-8 with base f(v) = v.

    ``F(v, 0) = Frac(v)``, ``F(v, 1) = Frac(2 v)`` (eq. 7) and ``F(v, t) = (1 - t) F(v, 0) +
    t F(v, 1)`` (eq. 8). Contrary to the paper, F(., t) is not uniform for 0 < t < 1: its density
    is 2 / (1 + t) on [(1 - t) / 2, (1 + t) / 2) and 1 / (1 + t) elsewhere (see
    :func:`multiscale_line_cdf`). ``uniform=True`` returns G(F(v, t), t) with G that CDF: uniform
    for every t, strictly increasing in F (same line order, minima and maxima where F has them)
    and equal to F at t = 0 and t = 1. It is piecewise linear in v with slopes 1, 2, 2, 1.
    ``multiscale_line.scalar(v, t, uniform)`` is the device function.

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
    ndarray in [0, 1) with the broadcast shape; computed in float64, returned as float32 if the
    inputs are float32 (within an ulp of float32 of the float64 values).
    """
    dt, v, t = reals(v=v, t=t)
    check_range("t", t, 0.0, 1.0, "t is the fractional part of the dyadic scale")
    return _below_one(elementwise(multiscale_line.scalar, dt, v, t, check_bool("uniform", uniform)))


@njit
def _multiscale_line_cdf(y, t):
    y = clip(y, 0.0, 1.0)
    lo = (1 - t) / 2
    hi = (1 + t) / 2
    if y < lo:
        g = y / (1 + t)
    elif y < hi:
        g = (2 * y - lo) / (1 + t)
    else:
        g = (y + t) / (1 + t)
    return clip(g, 0.0, 1.0)


@face(_multiscale_line_cdf)
def multiscale_line_cdf(y, t) -> np.ndarray:
    """CDF G(y, t) of the paper's F(., t) (eq. 8) over one period of v.

    ``G = y / (1 + t)`` below (1 - t) / 2, ``(2 y - (1 - t) / 2) / (1 + t)`` up to (1 + t) / 2
    and ``(y + t) / (1 + t)`` above; G(y, 0) = G(y, 1) = y. The paper's claim of a uniform
    distribution holds only at t = 0 and t = 1. ``multiscale_line_cdf.scalar(y, t)`` is the
    device function.

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
    dt, y, t = reals(y=y, t=t)
    check_range("t", t, 0.0, 1.0, "t is the fractional part of the dyadic scale")
    return elementwise(multiscale_line_cdf.scalar, dt, y, t)


@njit(inline="always")
def _line_threshold(v, s, uniform, noise):
    t = s - np.floor(s)  # eq. 8's blend: Frac(s)
    f = _multiscale_line(scaled(v, s), t, uniform)  # eqs. 6-8 (F takes Frac of eq. 6 itself)
    return frac(f + noise) if noise != 0.0 else f  # the phase modulation


@face(_line_threshold)
def line_threshold(v, s, *, uniform: bool = False, noise=None) -> np.ndarray:
    """Multi-scale line threshold texture of Veryovka sec. 3.2 at continuous dyadic scale s.

    ``F(Frac(v * 2**floor(s)), Frac(s))`` (eqs. 6-8): lines of constant screen period between w
    and 2 w pixels (eq. 5), and no jump where s crosses an integer (F at t = 1 equals F at the
    next scale with t = 0). Threshold an intensity against it with :func:`step`: white where
    ``intensity >= line_threshold``; the black line fraction of a period is 1 - intensity (with
    ``uniform=True``; the paper's blend drifts at intermediate scales).
    ``line_threshold.scalar(v, s, uniform, noise)`` is the device function (noise 0: none).

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
    (...) ndarray in [0, 1); computed in float64, returned as float32 if the inputs are float32
    (within an ulp of float32 of the float64 values).
    """
    dt, v, s, *z = reals(v=v, s=s, **({} if noise is None else {"noise": noise}))
    z = z[0] if z else 0.0
    return _below_one(
        elementwise(line_threshold.scalar, dt, v, s, check_bool("uniform", uniform), z)
    )
