"""Filtered thresholding of Veryovka sec. 4: percentage-closer filtering of thresholding results
and the analytic box filter of a thresholded multi-scale line texture.

Public names are re-exported by :mod:`refnpr.formulas.threshold`.
"""

from __future__ import annotations

import numpy as np

from .._shading_checks import broadcast, check_range, frac, real, scaled_frac
from .._validate import check_int, result_dtype
from .lines import multiscale_kernel, scale_split, step_kernel

__all__ = ["pcf_threshold", "mip_threshold", "line_coverage"]


def pcf_threshold(x, t_samples, *, weights=None, n: int = 1) -> np.ndarray:
    """Percentage-closer filtered thresholding (Veryovka sec. 4): ``sum_k w_k T(x, t_k) / sum w``.

    The thresholding results are filtered, not the thresholds (filtering thresholds does not
    remove aliasing, sec. 4). T is eq. 3 for n = 1 and T_n of eq. 4 otherwise.

    Parameters
    ----------
    x : (...) array
        Continuous shading value.
    t_samples : (..., K) array
        K threshold-texture samples per pixel (last axis).
    weights : (K,) or (..., K) array >= 0, or None, keyword-only
        Filter weights with a positive sum per pixel; None weighs samples equally.
    n : int >= 1, keyword-only
        Number of steps of T_n.

    Returns
    -------
    (...) ndarray in [0, 1] for x in [0, 1]; float64, or float32 if the inputs are float32.
    """
    n = check_int("n", n, lo=1)
    extra = () if weights is None else (weights,)
    dt = result_dtype(x, t_samples, *extra)
    x = real("x", x, dt)
    ts = real("t_samples", t_samples, dt)
    if ts.ndim == 0:
        raise ValueError(
            "t_samples: expected shape (..., K) with the K samples on the last axis, got a scalar"
        )
    if ts.shape[-1] == 0:
        raise ValueError(
            f"t_samples: expected K >= 1 threshold samples on the last axis, got shape {ts.shape}"
        )
    broadcast(x=x[..., None], t_samples=ts)
    hits = step_kernel(x[..., None], ts, n)
    if weights is None:
        return np.asarray(np.mean(hits, axis=-1), dtype=dt)
    wts = real("weights", weights, dt)
    if np.any(wts < 0):
        raise ValueError("weights: expected values >= 0, got a negative weight; use |w|")
    broadcast(t_samples=ts, weights=wts)
    total = np.sum(np.broadcast_to(wts, np.broadcast_shapes(wts.shape, hits.shape)), axis=-1)
    if np.any(total <= 0):
        raise ValueError(
            "weights: the weights of some pixel sum to 0; give every pixel a positive weight"
        )
    return np.asarray(np.sum(hits * wts, axis=-1) / total, dtype=dt)


def mip_threshold(x, t_fine, t_coarse, lod_frac, *, n: int = 1) -> np.ndarray:
    """Two-mip-level weighted thresholding (Veryovka sec. 4, image textures).

    ``(1 - lod_frac) T(x, t_fine) + lod_frac T(x, t_coarse)``: the thresholding results at the
    two nearest mip levels of a (CLAHE) threshold pyramid are blended with the trilinear weight,
    instead of thresholding the blended threshold.

    Parameters
    ----------
    x : (...) array
        Continuous shading value.
    t_fine, t_coarse : (...) arrays
        Threshold samples at mip levels floor(lambda) and floor(lambda) + 1.
    lod_frac : (...) array in [0, 1]
        Frac(lambda), the weight of the coarse level.
    n : int >= 1, keyword-only
        Number of steps of T_n.

    Returns
    -------
    (...) ndarray; float64, or float32 if the inputs are float32.
    """
    n = check_int("n", n, lo=1)
    dt = result_dtype(x, t_fine, t_coarse, lod_frac)
    x = real("x", x, dt)
    t0 = real("t_fine", t_fine, dt)
    t1 = real("t_coarse", t_coarse, dt)
    f = real("lod_frac", lod_frac, dt)
    check_range("lod_frac", f, 0.0, 1.0, "lod_frac is the fractional part of the mip LOD")
    broadcast(x=x, t_fine=t0, t_coarse=t1, lod_frac=f)
    out = (1 - f) * step_kernel(x, t0, n) + f * step_kernel(x, t1, n)
    return np.asarray(out, dtype=dt)


# ------------------------------------------------------------------ analytic box filter (lines)


def _pieces(intensity: np.ndarray, t: np.ndarray, uniform: bool) -> list[tuple]:
    """{v in [0, 1): F(v, t) <= intensity} as disjoint intervals [c_j, c_j + len_j]."""
    i = intensity
    if not uniform:  # F = (1 + t) v on [0, 1/2), (1 + t) v - t on [1/2, 1)
        return [
            (0.0, np.clip(i / (1 + t), 0, 0.5)),
            (0.5, np.clip((i + t) / (1 + t) - 0.5, 0, 0.5)),
        ]
    a = (1 - t) / (2 * (1 + t))  # slopes 1, 2, 2, 1 on [0, a), [a, 1/2), [1/2, b), [b, 1)
    b = 1 - a
    return [
        (0.0, np.clip(i, 0, a)),
        (a, np.clip((i - a) / 2, 0, 0.5 - a)),
        (0.5, np.clip((i + b) / 2 - 0.5, 0, b - 0.5)),
        (b, np.clip(i - b, 0, 1 - b)),
    ]


def _h(x: np.ndarray, ln: np.ndarray) -> np.ndarray:
    """H(x) - ln x, H the running integral of the pulse train 1[Frac(x) < ln] (periodic)."""
    f = frac(x)
    return np.minimum(f, ln) - ln * f


def _d2(x: np.ndarray, ln: np.ndarray) -> np.ndarray:
    """H2(x) - ln x^2 / 2 - mu x, H2 = integral of H, mu = ln (1 - ln) / 2 (periodic)."""
    f = frac(x)
    m = np.where(f <= ln, f * f / 2, ln * f - ln * ln / 2)
    return m - ln * f * f / 2 - ln * (1 - ln) / 2 * f


def _ramp(start: np.ndarray, width: np.ndarray, ln: np.ndarray, sign: int) -> np.ndarray:
    """Integral over z in [0, width] of z * 1[Frac(start + sign z) < ln], for width < 1."""
    total = np.zeros(np.broadcast_shapes(start.shape, width.shape, ln.shape))
    base = np.floor(start)
    for dn in (-1.0, 0.0, 1.0):
        n = base + dn * sign
        # z-interval where start + sign z lies in the pulse [n, n + ln]
        if sign > 0:
            lo, hi = n - start, n + ln - start
        else:
            lo, hi = start - n - ln, start - n
        lo = np.clip(lo, 0, width)
        hi = np.clip(hi, 0, width)
        total = total + (hi - lo) * (hi + lo) / 2
    return total


def _pulse_box(u: np.ndarray, a: np.ndarray, b: np.ndarray, ln: np.ndarray) -> np.ndarray:
    """E[1[Frac(u + a X + b Y) < ln]] for X, Y ~ U(-1/2, 1/2) and a >= b >= 0, a > 0.

    The density of u + a X + b Y is a trapezoid: ramps of width b at both ends of a plateau
    1 / a. For b >= 1 the second antiderivative gives ln + (second difference of a periodic
    function) / (a b); for b < 1 the plateau is integrated through the running integral and each
    ramp, which then meets at most three pulses, term by term (stable for small footprints).
    """
    u = frac(u)
    wide = b >= 1
    safe_a = np.where(a > 0, a, 1.0)
    safe_b = np.where(b > 0, b, 1.0)
    # b >= 1: closed form
    ha, hb = a / 2, b / 2
    dd = _d2(u + ha + hb, ln) - _d2(u + ha - hb, ln) - _d2(u - ha + hb, ln) + _d2(u - ha - hb, ln)
    closed = ln + dd / (safe_a * safe_b)
    # b < 1: plateau + two ramps
    half = (a - b) / 2
    plateau = (ln * (a - b) + _h(u + half, ln) - _h(u - half, ln)) / safe_a
    width = np.where(wide, 0.0, b)
    left = _ramp(u - (a + b) / 2, width, ln, +1)
    right = _ramp(u + (a + b) / 2, width, ln, -1)
    ramps = np.where(b > 0, (left + right) / (safe_a * safe_b), 0.0)
    return np.where(wide, closed, plateau + ramps)


def line_coverage(v, s, intensity, dv_dx, dv_dy, *, uniform: bool = False) -> np.ndarray:
    """Analytic box filter of a thresholded line texture over the pixel footprint (Veryovka sec. 4).

    The fraction of the pixel square where ``line_threshold(v, s) <= intensity`` (white), with v
    linear over the pixel, ``v(x, y) = v + dv_dx x + dv_dy y`` for x, y in [-1/2, 1/2], and s held
    at its pixel value. Exact: per period the white set is a union of intervals (F is piecewise
    linear and increasing on each piece), and the distribution of v over the footprint is a
    trapezoid (two box filters), so the fraction is a sum of integrals of piecewise polynomials.
    Zero derivatives give the point sample ``step(intensity, line_threshold(v, s))``; an infinite
    footprint gives the tone, ``multiscale_line_cdf(intensity, t)`` (or ``intensity`` with
    ``uniform=True``).

    Parameters
    ----------
    v : (...) array
        Line coordinate at the pixel centre.
    s : (...) array
        Dyadic scale at the pixel centre.
    intensity : (...) array
        Continuous shading value thresholded against the lines.
    dv_dx, dv_dy : (...) arrays
        Screen derivatives of v (per pixel).
    uniform : bool, keyword-only
        Filter the tone-preserving line function instead of the paper's.

    Returns
    -------
    (...) ndarray in [0, 1]; computed in float64, returned as float32 if every input is float32.
    The absolute error is about 1e-16 (1 + |v 2**floor(s)|) / (|dv_dx| + |dv_dy|) 2**-floor(s),
    the conditioning of locating a line edge inside a footprint that small.
    """
    dt = result_dtype(v, s, intensity, dv_dx, dv_dy)
    f64 = np.dtype(np.float64)
    v = real("v", v, f64)
    s = real("s", s, f64)
    x = real("intensity", intensity, f64)
    gx = real("dv_dx", dv_dx, f64)
    gy = real("dv_dy", dv_dy, f64)
    shape = broadcast(v=v, s=s, intensity=x, dv_dx=gx, dv_dy=gy)
    v, s, x, gx, gy = np.broadcast_arrays(v, s, x, gx, gy)
    k, t = scale_split(s)
    vr = scaled_frac(v, k)  # eq. 6: position within the line period
    with np.errstate(over="ignore"):
        a = np.ldexp(np.maximum(np.abs(gx), np.abs(gy)), k)  # footprint in line periods
        b = np.ldexp(np.minimum(np.abs(gx), np.abs(gy)), k)
    # footprints below 1e-100 periods: no float input locates v that well, point sample
    point = a < 1e-100
    huge = ~(a < 1e15)  # the box average equals the tone to < 1e-15 (also catches inf)
    a_ok = np.where(point | huge, 1.0, a)
    b_ok = np.where(point | huge | (b < 1e-200), 0.0, b)  # b / a < 1e-100: box of width a
    cover = np.zeros(shape)
    tone = np.zeros(shape)
    for c, ln in _pieces(x, t, uniform):
        cover = cover + _pulse_box(vr - c, a_ok, b_ok, ln)
        tone = tone + ln
    sample = step_kernel(x, multiscale_kernel(vr, t, uniform), 1)
    cover = np.where(point, sample, np.where(huge, tone, cover))
    cover = np.where(x >= 1, 1.0, np.where(x < 0, 0.0, cover))  # F takes values in [0, 1)
    return np.asarray(np.clip(cover, 0, 1), dtype=dt)
