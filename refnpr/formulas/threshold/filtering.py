"""Filtered thresholding of Veryovka sec. 4: percentage-closer filtering of thresholding results
and the analytic box filter of a thresholded multi-scale line texture."""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import clip, frac

from .._face import Whole, elementwise, face
from .._shading_checks import broadcast, check_range, real, reals
from .._validate import check_bool, result_dtype
from .lines import _dyadic_remap, _multiscale_line, _step, check_steps, ldexp, level, step_any

__all__ = ["pcf_threshold", "mip_threshold", "line_coverage"]

#: Terms of :func:`_psum`: a thresholding result, a weighted one, a weight.
_HIT, _WEIGHTED_HIT, _WEIGHT = 0, 1, 2


@njit
def _term(x, t, w, n, j, kind):
    if kind == _WEIGHT:
        return w[j]
    h = step_any(x, t[j], n)  # eq. 3 (n = 1) or eq. 4
    return h * w[j] if kind == _WEIGHTED_HIT else h


@njit
def _block(x, t, w, n, lo, count, kind):
    """numpy's pairwise sum of up to 128 terms ``lo .. lo + count - 1`` (:func:`_term`, formed
    as they are read): a plain sum below 8, else 8 accumulators."""
    if count < 8:
        res = 0.0
        for i in range(count):
            res += _term(x, t, w, n, lo + i, kind)
        return res
    r0 = _term(x, t, w, n, lo, kind)
    r1 = _term(x, t, w, n, lo + 1, kind)
    r2 = _term(x, t, w, n, lo + 2, kind)
    r3 = _term(x, t, w, n, lo + 3, kind)
    r4 = _term(x, t, w, n, lo + 4, kind)
    r5 = _term(x, t, w, n, lo + 5, kind)
    r6 = _term(x, t, w, n, lo + 6, kind)
    r7 = _term(x, t, w, n, lo + 7, kind)
    i = 8
    while i < count - (count % 8):
        r0 += _term(x, t, w, n, lo + i, kind)
        r1 += _term(x, t, w, n, lo + i + 1, kind)
        r2 += _term(x, t, w, n, lo + i + 2, kind)
        r3 += _term(x, t, w, n, lo + i + 3, kind)
        r4 += _term(x, t, w, n, lo + i + 4, kind)
        r5 += _term(x, t, w, n, lo + i + 5, kind)
        r6 += _term(x, t, w, n, lo + i + 6, kind)
        r7 += _term(x, t, w, n, lo + i + 7, kind)
        i += 8
    res = (r0 + r1) + (r2 + r3) + ((r4 + r5) + (r6 + r7))
    while i < count:
        res += _term(x, t, w, n, lo + i, kind)
        i += 1
    return res


@njit
def _psum(x, t, w, n, lo, count, kind):
    """numpy's pairwise sum (``np.add.reduce`` over a contiguous axis) of the terms ``lo ..
    lo + count - 1``: blocks of up to 128, halves (multiples of 8) above."""
    if count <= 128:
        return _block(x, t, w, n, lo, count, kind)
    half = count // 2
    half -= half % 8
    return _psum(x, t, w, n, lo, half, kind) + _psum(x, t, w, n, lo + half, count - half, kind)


@njit
def _pairwise(x, t, w, n, kind):
    """The pairwise sum of the K terms of ``kind`` of thresholds ``t`` and weights ``w``."""
    k = t.shape[0]
    if k <= 128:
        return _block(x, t, w, n, 0, k, kind)
    zero = k - k  # a run-time value: a recursive function typed for literals fails to link
    return _psum(x, t, w, n, zero, k, kind)


@njit
def _pcf_threshold(x, t, w, n):
    zero = t.shape[0] - t.shape[0]  # run-time kinds: one compilation, not one per literal
    if w.shape[0] == 0:  # sec. 4: the mean of the thresholding results
        return _pairwise(x, t, w, n, zero + _HIT) / t.shape[0]
    total = _pairwise(x, t, w, n, zero + _WEIGHT)
    return _pairwise(x, t, w, n, zero + _WEIGHTED_HIT) / total  # sec. 4: weighted


@njit
def _pcf_row(i, x, t, w, n):
    """:func:`_pcf_threshold` of row ``i`` of the face's ``(M, K)`` tables."""
    return _pcf_threshold(x, t[i], w[min(i, w.shape[0] - 1)], n)


@face(_pcf_threshold)
def pcf_threshold(x, t_samples, *, weights=None, n: int = 1) -> np.ndarray:
    """Percentage-closer filtered thresholding (Veryovka sec. 4): ``sum_k w_k T(x, t_k) / sum w``.

    The thresholding results are filtered, not the thresholds (filtering thresholds does not
    remove aliasing, sec. 4). T is eq. 3 for n = 1 and T_n of eq. 4 otherwise. Sums are formed
    in numpy's pairwise order. ``pcf_threshold.scalar(x, t, w, n)`` is the device function:
    ``t`` the (K,) samples, ``w`` their (K,) weights or an empty array (equal weights).

    Parameters
    ----------
    x : (...) array
        Continuous shading value.
    t_samples : (..., K) array
        K threshold-texture samples per pixel (last axis).
    weights : (K,) or (..., K) array >= 0, or None, keyword-only
        Finite filter weights with a positive sum per pixel (any magnitude: a pixel whose sums
        would overflow is scaled by a power of two first, which leaves the quotient unchanged);
        None weighs samples equally. ``x[..., None]``, ``t_samples`` and ``weights`` broadcast
        together.
    n : int in [1, 2**53], keyword-only
        Number of steps of T_n.

    Returns
    -------
    (...) ndarray in [0, 1] for x in [0, 1], the broadcast shape without K; float64, or float32
    if the inputs are float32.
    """
    n = check_steps(n)
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
    wts = np.zeros((1, 0))
    if weights is None:
        shape = broadcast(x=x[..., None], t_samples=ts)
    else:
        w = real("weights", weights, dt)
        if w.ndim > 0 and w.shape[-1] not in (1, ts.shape[-1]):
            raise ValueError(
                f"weights: expected shape (K,) or (..., K) with K = {ts.shape[-1]} (one weight "
                f"per threshold sample), got shape {w.shape}"
            )
        if np.any(w < 0):
            raise ValueError("weights: expected values >= 0, got a negative weight; use |w|")
        shape = broadcast(x=x[..., None], t_samples=ts, weights=w)
    rows = _rows(ts, shape)
    xs = np.broadcast_to(x, shape[:-1]).reshape(-1)
    if weights is not None:
        wts = _weight_rows(w, shape, xs)
    index = np.arange(rows.shape[0])
    out = elementwise(_pcf_row, dt, index, xs, Whole(rows), Whole(wts), n)
    return out.reshape(shape[:-1])


def _weight_rows(w: np.ndarray, shape: tuple[int, ...], xs: np.ndarray) -> np.ndarray:
    """The weights as (M, K) rows (:func:`_rows`) whose sums in the kernel stay finite.

    A row whose sum of weights, or the bound ``(1 + |x|)`` times it of the weighted results
    (|T_n(x, t)| <= 1 + |x|), overflows is scaled by a power of two so that its largest weight
    lies in [1/2, 1): exact, and the quotient of the two sums is unchanged (only weights under
    2^-1022 of the largest lose bits, far below the rounding of the sums). Every other row is
    passed as it is, so the face computes what the kernel does.
    """
    rows = _rows(w, shape)
    with np.errstate(over="ignore"):
        total = np.sum(rows, axis=-1)  # the kernel's pairwise order
        huge = ~np.isfinite(total * (1.0 + np.abs(xs)))
    if np.any(total <= 0):
        raise ValueError(
            "weights: the weights of some pixel sum to 0; give every pixel a positive weight"
        )
    if np.any(huge):
        _, e = np.frexp(np.max(rows[huge], axis=-1))
        rows = rows.copy()
        rows[huge] = np.ldexp(rows[huge], -e[:, None])
    return rows


def _rows(a: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``a`` broadcast to ``shape`` as contiguous, writable float64 rows ``(M, K)``: writable
    like the style kernel's scratch rows, so that :func:`_pcf_threshold` is compiled once for
    both (numba types an array's writability)."""
    full = np.broadcast_to(a.astype(np.float64, copy=False), shape)
    return np.array(full, dtype=np.float64, order="C").reshape(-1, shape[-1])


@njit
def _mip_threshold(x, t_fine, t_coarse, lod_frac, n):
    # sec. 4: the results at the two levels, blended with the trilinear weight
    return (1 - lod_frac) * step_any(x, t_fine, n) + lod_frac * step_any(x, t_coarse, n)


@face(_mip_threshold)
def mip_threshold(x, t_fine, t_coarse, lod_frac, *, n: int = 1) -> np.ndarray:
    """Two-mip-level weighted thresholding (Veryovka sec. 4, image textures).

    ``(1 - lod_frac) T(x, t_fine) + lod_frac T(x, t_coarse)``: the thresholding results at the
    two nearest mip levels of a (CLAHE) threshold pyramid are blended with the trilinear weight,
    instead of thresholding the blended threshold. ``mip_threshold.scalar(x, t_fine, t_coarse,
    lod_frac, n)`` is the device function.

    Parameters
    ----------
    x : (...) array
        Continuous shading value.
    t_fine, t_coarse : (...) arrays
        Threshold samples at mip levels floor(lambda) and floor(lambda) + 1.
    lod_frac : (...) array in [0, 1]
        Frac(lambda), the weight of the coarse level.
    n : int in [1, 2**53], keyword-only
        Number of steps of T_n.

    Returns
    -------
    (...) ndarray; float64, or float32 if the inputs are float32.
    """
    n = check_steps(n)
    dt, x, t0, t1, f = reals(x=x, t_fine=t_fine, t_coarse=t_coarse, lod_frac=lod_frac)
    check_range("lod_frac", f, 0.0, 1.0, "lod_frac is the fractional part of the mip LOD")
    return elementwise(mip_threshold.scalar, dt, x, t0, t1, f, n)


# ------------------------------------------------------------------ analytic box filter (lines)


@njit
def _h(x, ln):
    """H(x) - ln x, H the running integral of the pulse train 1[Frac(x) < ln] (periodic)."""
    f = frac(x)
    return (f if f <= ln else ln) - ln * f


@njit
def _d2(x, ln):
    """H2(x) - ln x^2 / 2 - mu x, H2 = integral of H, mu = ln (1 - ln) / 2 (periodic)."""
    f = frac(x)
    m = f * f / 2 if f <= ln else ln * f - ln * ln / 2
    return m - ln * f * f / 2 - ln * (1 - ln) / 2 * f


@njit
def _ramp(start, width, ln, sign):
    """Integral over z in [0, width] of z * 1[Frac(start + sign z) < ln], for width < 1."""
    total = 0.0
    base = np.floor(start)
    for dn in (-1.0, 0.0, 1.0):
        n = base + dn * sign
        # z-interval where start + sign z lies in the pulse [n, n + ln]
        if sign > 0:
            lo = n - start
            hi = n + ln - start
        else:
            lo = start - n - ln
            hi = start - n
        lo = clip(lo, 0.0, width)
        hi = clip(hi, 0.0, width)
        total = total + (hi - lo) * (hi + lo) / 2
    return total


@njit
def _pulse_box(u, a, b, ln):
    """E[1[Frac(u + a X + b Y) < ln]] for X, Y ~ U(-1/2, 1/2) and a >= b >= 0, a > 0.

    The density of u + a X + b Y is a trapezoid: ramps of width b at both ends of a plateau
    1 / a. For b >= 1 the second antiderivative gives ln + (second difference of a periodic
    function) / (a b); for b < 1 the plateau is integrated through the running integral and each
    ramp, which then meets at most three pulses, term by term (stable for small footprints).
    """
    u = frac(u)
    safe_a = a if a > 0 else 1.0
    safe_b = b if b > 0 else 1.0
    if b >= 1:  # closed form
        ha = a / 2
        hb = b / 2
        dd = (
            _d2(u + ha + hb, ln)
            - _d2(u + ha - hb, ln)
            - _d2(u - ha + hb, ln)
            + _d2(u - ha - hb, ln)
        )
        return ln + dd / (safe_a * safe_b)
    half = (a - b) / 2
    plateau = (ln * (a - b) + _h(u + half, ln) - _h(u - half, ln)) / safe_a
    left = _ramp(u - (a + b) / 2, b, ln, 1)
    right = _ramp(u + (a + b) / 2, b, ln, -1)
    ramps = (left + right) / (safe_a * safe_b) if b > 0 else 0.0
    return plateau + ramps


@njit
def _line_coverage(v, s, x, gx, gy, uniform):
    k = level(s)
    t = s - np.floor(s)
    vr = _dyadic_remap(v, s)  # eq. 6: position within the line period
    ax = abs(gx)
    ay = abs(gy)
    a = ldexp(ax if ax >= ay else ay, k)  # footprint in line periods
    b = ldexp(ax if ax <= ay else ay, k)
    # footprints below 1e-100 periods: no float input locates v that well, point sample
    point = a < 1e-100
    huge = not (a < 1e15)  # the box average equals the tone to < 1e-15 (also catches inf)
    a_ok = 1.0 if (point or huge) else a
    b_ok = 0.0 if (point or huge or b < 1e-200) else b  # b / a < 1e-100: box of width a
    # {v in [0, 1): F(v, t) <= x} as disjoint intervals [c_j, c_j + ln_j], each box-filtered
    cover = 0.0
    tone = 0.0
    if not uniform:  # F = (1 + t) v on [0, 1/2), (1 + t) v - t on [1/2, 1)
        ln = clip(x / (1 + t), 0.0, 0.5)
        cover = cover + _pulse_box(vr - 0.0, a_ok, b_ok, ln)
        tone = tone + ln
        ln = clip((x + t) / (1 + t) - 0.5, 0.0, 0.5)
        cover = cover + _pulse_box(vr - 0.5, a_ok, b_ok, ln)
        tone = tone + ln
    else:  # slopes 1, 2, 2, 1 on [0, ca), [ca, 1/2), [1/2, cb), [cb, 1)
        ca = (1 - t) / (2 * (1 + t))
        cb = 1 - ca
        ln = clip(x, 0.0, ca)
        cover = cover + _pulse_box(vr - 0.0, a_ok, b_ok, ln)
        tone = tone + ln
        ln = clip((x - ca) / 2, 0.0, 0.5 - ca)
        cover = cover + _pulse_box(vr - ca, a_ok, b_ok, ln)
        tone = tone + ln
        ln = clip((x + cb) / 2 - 0.5, 0.0, cb - 0.5)
        cover = cover + _pulse_box(vr - 0.5, a_ok, b_ok, ln)
        tone = tone + ln
        ln = clip(x - cb, 0.0, 1 - cb)
        cover = cover + _pulse_box(vr - cb, a_ok, b_ok, ln)
        tone = tone + ln
    if point:
        cover = _step(x, _multiscale_line(vr, t, uniform))  # the point sample
    elif huge:
        cover = tone
    if x >= 1:  # F takes values in [0, 1)
        cover = 1.0
    elif x < 0:
        cover = 0.0
    return clip(cover, 0.0, 1.0)


@face(_line_coverage)
def line_coverage(v, s, intensity, dv_dx, dv_dy, *, uniform: bool = False) -> np.ndarray:
    """Analytic box filter of a thresholded line texture over the pixel footprint (Veryovka sec. 4).

    The fraction of the pixel square where ``line_threshold(v, s) <= intensity`` (white), with v
    linear over the pixel, ``v(x, y) = v + dv_dx x + dv_dy y`` for x, y in [-1/2, 1/2], and s held
    at its pixel value. Exact: per period the white set is a union of intervals (F is piecewise
    linear and increasing on each piece), and the distribution of v over the footprint is a
    trapezoid (two box filters), so the fraction is a sum of integrals of piecewise polynomials.
    Zero derivatives give the point sample ``step(intensity, line_threshold(v, s))``; an infinite
    footprint gives the tone, ``multiscale_line_cdf(intensity, t)`` (or ``intensity`` with
    ``uniform=True``). ``line_coverage.scalar(v, s, intensity, dv_dx, dv_dy, uniform)`` is the
    device function.

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
    dt, v, s, x, gx, gy = reals(np.float64, v=v, s=s, intensity=intensity, dv_dx=dv_dx, dv_dy=dv_dy)
    return elementwise(line_coverage.scalar, dt, v, s, x, gx, gy, check_bool("uniform", uniform))
