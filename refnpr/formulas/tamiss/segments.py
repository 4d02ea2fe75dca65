"""Visible segments of a stroke and its image-space extrusion (TAMISS sec. 3.2 and sec. 4).

Private helper of :mod:`refnpr.formulas.tamiss` (which re-exports the public names).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refnpr._jit import njit

from .._face import elementwise
from .._validate import as_float, check_int, check_scalar, describe, result_dtype
from .curve import cubic

_cubic_s = cubic.scalar

__all__ = ["visible_segments", "StrokeStrip", "extrude_stroke"]


def _cubic(c: np.ndarray, s):
    """The cubic of the float64 coefficients ``c`` (..., 4) at ``s`` (:func:`.curve.cubic`)."""
    return elementwise(cubic.scalar, np.float64, tuple(c[..., k] for k in range(4)), s)


@njit
def _crossing(c, left, right, f_left):
    """The zero of the cubic ``c`` on its monotone piece [left, right] (``f_left`` its value at
    left; the signs at the ends differ): 64 bisection steps, to full precision."""
    for _ in range(64):
        mid = 0.5 * (left + right)
        f_mid = _cubic_s(c, mid)
        if (f_mid < 0) == (f_left < 0):
            left = mid
            f_left = f_mid
        else:
            right = mid
    return 0.5 * (left + right)


def _critical_points(c: np.ndarray) -> np.ndarray:
    """Real roots of v'(s) = c1 + 2 c2 s + 3 c3 s^2, (..., 2), NaN where absent."""
    A, B, C = 3 * c[..., 3], 2 * c[..., 2], c[..., 1]
    disc = B * B - 4 * A * C
    sq = np.sqrt(np.maximum(disc, 0.0))
    q = -0.5 * (B + np.where(B >= 0, sq, -sq))  # stable quadratic formula
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # inf roots: outside
        r1 = np.where(A != 0, q / A, np.where(B != 0, -C / B, np.nan))
        r2 = np.where((A != 0) & (q != 0), C / q, np.nan)
    real = disc >= 0
    r1 = np.where(real | (A == 0), r1, np.nan)
    r2 = np.where(real, r2, np.nan)
    return np.stack([r1, r2], axis=-1)


def visible_segments(c_v, *, threshold: float = 0.25, lo=-1.0, hi=1.0):
    """Intervals of [lo, hi] where the cubic visibility v(s) = c_v . (1, s, s^2, s^3) >= threshold.

    A cubic crosses a level at most three times, so there are at most two intervals (sec. 3.2:
    "no more than two visible segments"). Crossings are found by bisection on the (at most three)
    monotone pieces between the critical points, to full precision.

    Parameters
    ----------
    c_v : (..., 4) float, visibility coefficients in the parameter s
    threshold : float
    lo, hi : float or (...) float, the parameter range (lo <= hi); [-1, 1] for centred fits

    Returns
    -------
    segments : (..., 2, 2) float, ``segments[..., j, :] = (start, end)``, NaN for absent segments
    count : (...) int, number of segments (0, 1 or 2)
    """
    c = as_float("c_v", c_v, finite=True)
    if c.ndim < 1 or c.shape[-1] != 4:
        raise ValueError(f"c_v: expected shape (..., 4) (cubic coefficients), got {describe(c)}")
    thr = check_scalar("threshold", threshold)
    lo_ = as_float("lo", lo, finite=True)
    hi_ = as_float("hi", hi, finite=True)
    if np.any(lo_ > hi_):
        raise ValueError(f"lo, hi: expected lo <= hi, got lo={describe(lo_)}, hi={describe(hi_)}")
    dt = result_dtype(c)
    c = c.astype(np.float64).copy()
    c[..., 0] -= thr
    scale = np.max(np.abs(c), axis=-1, keepdims=True)
    c = c / np.where(scale > 0, scale, 1.0)  # same roots and signs, no overflow below
    batch = c.shape[:-1]
    lo_ = np.broadcast_to(lo_.astype(np.float64), batch)
    hi_ = np.broadcast_to(hi_.astype(np.float64), batch)
    crit = _critical_points(c)
    inside = (crit > lo_[..., None]) & (crit < hi_[..., None])
    crit = np.sort(np.where(inside, crit, hi_[..., None]), axis=-1)
    knots = np.concatenate([lo_[..., None], crit, hi_[..., None]], axis=-1)  # (..., 4)
    a, b = knots[..., :-1], knots[..., 1:]
    fa, fb = _cubic(c[..., None, :], a), _cubic(c[..., None, :], b)
    cross = (fa < 0) != (fb < 0)  # v - threshold changes sign on a monotone piece
    # bisection on the crossing pieces only (the others' roots are hi): elementwise, the same
    # values as over every piece
    c_x = np.broadcast_to(c[..., None, :], a.shape + (4,))[cross]
    cols = tuple(c_x[:, k] for k in range(4))
    roots = np.broadcast_to(hi_[..., None], a.shape).copy()
    roots[cross] = elementwise(_crossing, np.float64, cols, a[cross], b[cross], fa[cross])
    bps = np.concatenate([lo_[..., None], np.sort(roots, axis=-1), hi_[..., None]], axis=-1)
    starts, ends = bps[..., :-1], bps[..., 1:]
    positive = _cubic(c[..., None, :], 0.5 * (starts + ends)) >= 0
    seg = np.full(batch + (2, 2), np.nan)
    count = np.zeros(batch, dtype=np.int64)
    open_ = np.zeros(batch, dtype=bool)
    for j in range(starts.shape[-1]):
        length = ends[..., j] > starts[..., j]
        pos = positive[..., j] & length
        neg = ~positive[..., j] & length
        new = pos & ~open_ & (count < 2)
        idx = np.minimum(count, 1)
        for slot in (0, 1):
            sel = new & (idx == slot)
            seg[..., slot, 0] = np.where(sel, starts[..., j], seg[..., slot, 0])
        count = count + new
        last = np.maximum(count - 1, 0)
        for slot in (0, 1):
            sel = pos & (last == slot)
            seg[..., slot, 1] = np.where(sel, ends[..., j], seg[..., slot, 1])
        open_ = (open_ | pos) & ~neg
    return seg.astype(dt, copy=False), count


@dataclass(frozen=True)
class StrokeStrip:
    """A stroke extruded to a triangle strip (TAMISS sec. 4).

    Attributes
    ----------
    left, right : (..., K, 2) float, vertex positions in pixels on either side of the curve
    t : (..., K) float, the curve parameter of each vertex pair
    """

    left: np.ndarray
    right: np.ndarray
    t: np.ndarray

    def triangle_strip(self):
        """Interleaved strip ``L0, R0, L1, R1, ...``.

        Returns
        -------
        vertices : (..., 2K, 2), positions
        coords : (..., 2K, 2), per-vertex (t, across) with across = 0 on the left, 1 on the right
        """
        v = np.stack([self.left, self.right], axis=-2)
        v = v.reshape(v.shape[:-3] + (-1, 2))
        t = np.repeat(self.t, 2, axis=-1)
        across = np.zeros_like(t)
        across[..., 1::2] = 1
        return v, np.stack([t, across], axis=-1)


def extrude_stroke(
    fit, t_start, t_end, *, width, samples: int = 16, taper: float = 0.0
) -> StrokeStrip:
    """Extrude a fitted stroke over [t_start, t_end] to a strip of the given pixel width.

    The K = ``samples`` vertex pairs sit at evenly spaced t; each pair is p(t) +/- w(u)/2 * n(t),
    with n the unit left normal (-dy/dt, dx/dt) / |dp/dt| and u in [0, 1] the position along the
    segment. With ``taper`` > 0 the width ramps linearly from 0 over the first and last ``taper``
    fraction of the segment: w(u) = width * min(1, u / taper, (1 - u) / taper). Where the tangent
    vanishes the chord direction p(t_end) - p(t_start) is used, and (1, 0) if that vanishes too.

    Parameters
    ----------
    fit : StrokeFit (from :func:`refnpr.formulas.tamiss.fit_stroke` or ``fit_strokes``)
    t_start, t_end : float or (...) float, finite, matching the fit's batch shape
    width : float or (...) float >= 0, pixels
    samples : int >= 2
    taper : float in [0, 0.5]

    Returns
    -------
    StrokeStrip with ``left``/``right`` (..., K, 2) and ``t`` (..., K), the fit's dtype.
    """
    samples = check_int("samples", samples, lo=2)
    taper = check_scalar("taper", taper, lo=0.0, hi=0.5)
    ts = as_float("t_start", t_start, finite=True)
    te = as_float("t_end", t_end, finite=True)
    w = as_float("width", width, finite=True)
    if np.any(w < 0):
        raise ValueError(f"width: expected a non-negative width in pixels, got {describe(w)}")
    dt = fit.c_x.dtype
    batch = fit.c_x.shape[:-1]
    try:
        ts, te, w = (np.broadcast_to(v.astype(dt), batch) for v in (ts, te, w))
    except ValueError:
        raise ValueError(
            f"t_start, t_end, width: expected scalars or arrays of the fit's batch shape {batch}, "
            f"got shapes {np.shape(t_start)}, {np.shape(t_end)}, {np.shape(width)}"
        ) from None
    u = np.linspace(0.0, 1.0, samples).astype(dt)
    t = ts[..., None] + (te - ts)[..., None] * u  # (..., K)
    x, y = fit.evaluate(t)
    dx, dy = fit.derivative(t)
    (x0, y0), (x1, y1) = fit.evaluate(ts[..., None]), fit.evaluate(te[..., None])
    cx, cy = x1 - x0, y1 - y0
    tiny = np.finfo(dt).tiny
    nd = np.hypot(dx, dy)
    nc = np.hypot(cx, cy)
    use_d = nd > tiny
    use_c = nc > tiny
    tx = np.where(
        use_d, dx / np.where(use_d, nd, 1), np.where(use_c, cx / np.where(use_c, nc, 1), 1)
    )
    ty = np.where(
        use_d, dy / np.where(use_d, nd, 1), np.where(use_c, cy / np.where(use_c, nc, 1), 0)
    )
    if taper > 0:
        profile = np.minimum(1.0, np.minimum(u, 1.0 - u) / dt.type(taper)).astype(dt)
    else:
        profile = np.ones_like(u)
    h = (w[..., None] * profile) * dt.type(0.5)  # half width with taper
    nx, ny = -ty, tx  # left normal
    left = np.stack([x + h * nx, y + h * ny], axis=-1)
    right = np.stack([x - h * nx, y - h * ny], axis=-1)
    return StrokeStrip(left=left.astype(dt), right=right.astype(dt), t=t.astype(dt))
