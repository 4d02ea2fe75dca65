"""Per-stroke fits, the drop rule, drawn extents and image-space extrusion (TAMISS sec. 3.2, 4).

Fit: ``refnpr.formulas.tamiss.fit_strokes`` on the aggregates (four CG iterations, t centred and
scaled, float32 or float64), giving x(t), y(t) and the visibility v(t) with the zero prior.

Drop rule: :func:`keep_mask`.

Extent (:func:`drawn_segments`), in stroke parameter t:

* ``"visible"``: the (at most two) intervals where v(t) >= threshold, inside [t_min, t_max];
* ``"range"``: [t_min, t_max];
* ``"stroke"``: the whole stroke [0, 1] (overdraw across outlines and gaps, Figure 4);
* ``"overdraw"``: the visible intervals with the first start and the last end run on by up to
  ``overdraw`` pixels, within [0, 1] (strokes cross silhouettes, borders and density cuts a
  little, as a pen does, Figure 4; hidden gaps stay open).

Outside [t_min, t_max] the curve is continued along the end tangent at the mean speed of the fit
over [t_min, t_max] (a cubic extrapolated far from its data curls; a tangent line does not).

Extrusion (:func:`extrude`): ``samples`` vertex pairs per drawn interval, half width
w f / 2 * taper profile (f: the stroke's width factor from its id), a perpendicular wobble
A sin(2 pi (k t + phi)) with amplitude and phase from the stroke id, and an end jitter that moves
each outer end by up to ``end_jitter`` / 2 of the drawn length, also from the id: the same
stroke looks the same in every frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refnpr._jit import readonly
from refnpr.formulas.tamiss import StrokeFit, StrokeStrip, fit_strokes, hash01, width_factor

from . import _kernels as kernels
from .aggregate import Aggregates
from .field import SALT_WIDTH, StrokeField
from .params import EXTENTS

__all__ = [
    "EXTENTS",
    "SALT_WOBBLE_AMP",
    "SALT_WOBBLE_PHASE",
    "SALT_END_A",
    "SALT_END_B",
    "fit_aggregates",
    "keep_mask",
    "drawn_segments",
    "mean_speed",
    "centreline",
    "Strips",
    "extrude",
]

SALT_WOBBLE_AMP, SALT_WOBBLE_PHASE, SALT_END_A, SALT_END_B = 11, 12, 13, 14


def fit_aggregates(agg: Aggregates, *, iterations: int = 4, prior_weight: float = 1.0) -> StrokeFit:
    """Batched cubic fits of x(t), y(t) and v(t) (sec. 3.2, eq. 1) in the aggregates' dtype."""
    if len(agg) == 0:
        z = np.zeros((0, 4), dtype=agg.dtype)
        e = np.zeros(0, dtype=agg.dtype)
        return StrokeFit(z, z, z, e, e, e, prior_weight=prior_weight)
    return fit_strokes(
        agg.moments,
        agg.t_min,
        agg.t_max,
        origin=agg.origin,
        iterations=iterations,
        basis="legendre",
        prior_weight=prior_weight,
    )


def keep_mask(
    agg: Aggregates,
    fit: StrokeFit,
    *,
    min_fragments: int = 6,
    min_t_span: float = 0.05,
    max_stretch: float | None = None,
    px_per_fragment: float = 1.0,
    speed: np.ndarray | None = None,
) -> np.ndarray:
    """(S,) bool: count >= max(min_fragments, 4), t_max - t_min >= min_t_span, finite fit, and
    (with ``max_stretch``) a fitted curve no longer over [t_min, t_max] than ``max_stretch``
    times the length its fragments cover, count * ``px_per_fragment`` pixels, plus 4 px.

    The last test drops the fits that the fragments do not determine: a few fragments bunched
    at two values of t (a stroke seen only at the lip of the teapot's spout) let the cubic swing
    far past them, a line tens of pixels long where the stroke covers a few. A band
    ``gather_width`` pixels across on n x n samples per pixel emits about gather_width n^2
    fragments per pixel of stroke, so ``px_per_fragment = 1 / (gather_width n^2)``.
    ``speed`` (S,) float64: :func:`mean_speed` of ``fit`` if already known.
    """
    span = agg.t_max.astype(np.float64) - agg.t_min.astype(np.float64)
    finite = np.all(np.isfinite(fit.c_x), -1) & np.all(np.isfinite(fit.c_y), -1)
    keep = (agg.count >= max(int(min_fragments), 4)) & (span >= min_t_span) & finite
    if max_stretch is not None and keep.any():
        with np.errstate(invalid="ignore", over="ignore"):
            arc = (mean_speed(fit) if speed is None else speed) * span
        covered = agg.count * float(px_per_fragment)
        keep &= arc <= float(max_stretch) * covered + 4.0
    return keep


def _fit_arrays(fit: StrokeFit) -> tuple[np.ndarray, ...]:
    """c_x, c_y, t_min, t_max of a batch (S,) of centred-basis fits as the kernels take them:
    contiguous, in the coefficients' float type (as ``StrokeFit``'s methods compute)."""
    dt = fit.c_x.dtype if fit.c_x.dtype in (np.float32, np.float64) else np.dtype(np.float64)
    if fit.basis != "centred" or len(fit.batch_shape) != 1:
        raise ValueError(
            f"fit: expected a batch (S,) of centred-basis fits (fit_strokes' legendre or "
            f"monomial bases), got basis {fit.basis!r} with batch shape {fit.batch_shape}"
        )
    shapes = (fit.c_x.shape, fit.c_x.shape, fit.batch_shape, fit.batch_shape)
    out = tuple(  # read-only, whether or not broadcasting copied them: one kernel signature
        readonly(np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=dt), shape)))
        for a, shape in zip((fit.c_x, fit.c_y, fit.t_min, fit.t_max), shapes, strict=True)
    )
    if not (np.all(np.isfinite(out[2])) and np.all(np.isfinite(out[3]))):
        raise ValueError("fit: t_min, t_max: expected finite values")
    return out


def mean_speed(fit: StrokeFit) -> np.ndarray:
    """(S,) float64 pixels per unit t of the fitted curve over [t_min, t_max] (17-point polyline
    length / (t_max - t_min); 0 for a single t)."""
    arrays = _fit_arrays(fit)
    dt = arrays[0].dtype
    lo = arrays[2].astype(np.float64)[:, None]
    hi = arrays[3].astype(np.float64)[:, None]
    ts = lo + (hi - lo) * np.linspace(0.0, 1.0, 17)
    span, half, out = np.ascontiguousarray((hi - lo)[:, 0]), np.full(1, 0.5, dt), np.empty(len(ts))
    kernels.mean_speeds(ts.astype(dt), arrays, half, span, np.empty((len(ts), 16)), out)
    return out


def drawn_segments(
    fit: StrokeFit,
    extent: str = "visible",
    *,
    threshold: float | None = None,
    overdraw: float = 6.0,
    speed: np.ndarray | None = None,
    keep: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Drawn t intervals per stroke: ``(S, 2, 2)`` float64 (start, end), NaN if absent, and
    ``(S,)`` int64 counts (see module docstring for the extents). ``overdraw`` (pixels) bounds
    how far ``"overdraw"`` runs the outer ends on (converted to t with :func:`mean_speed`;
    ``speed`` (S,): its values if already known). ``keep`` (S,) bool: only those strokes get
    intervals (:func:`keep_mask`; the others' fits need not be finite)."""
    S = fit.batch_shape[0] if fit.batch_shape else 1
    if keep is not None:
        seg, count = np.full((S, 2, 2), np.nan), np.zeros(S, dtype=np.int64)
        kept = np.flatnonzero(keep)
        if kept.size:
            sub_speed = None if speed is None else np.asarray(speed)[kept]
            seg[kept], count[kept] = drawn_segments(
                fit.take(kept), extent, threshold=threshold, overdraw=overdraw, speed=sub_speed
            )
        return seg, count
    lo = np.asarray(fit.t_min, dtype=np.float64).reshape(S)
    hi = np.asarray(fit.t_max, dtype=np.float64).reshape(S)
    seg = np.full((S, 2, 2), np.nan)
    count = np.ones(S, dtype=np.int64)
    if extent == "range":
        seg[:, 0, 0], seg[:, 0, 1] = lo, hi
    elif extent == "stroke":
        seg[:, 0, 0], seg[:, 0, 1] = 0.0, 1.0
    else:
        vis, count = fit.visible_segments(threshold) if S else (seg, np.zeros(0, np.int64))
        seg = np.asarray(vis, dtype=np.float64).reshape(S, 2, 2).copy()
        count = np.asarray(count, dtype=np.int64).reshape(S)
        if extent == "overdraw":
            speed = mean_speed(fit) if speed is None else speed
            dt = np.where(speed > 0, overdraw / np.where(speed > 0, speed, 1.0), 0.0)
            rows = np.flatnonzero(count >= 1)
            last = count[rows] - 1
            seg[rows, 0, 0] = np.maximum(0.0, seg[rows, 0, 0] - dt[rows])
            seg[rows, last, 1] = np.minimum(1.0, seg[rows, last, 1] + dt[rows])
    return seg, count


def centreline(fit: StrokeFit, t, *, speed: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """Points and unit tangents of the drawn curve at t, ``(S, K)`` each: x, y, tx, ty (float64).

    r(t) from the fit on [t_min, t_max]; outside, the tangent line at the nearer end, traversed
    at the fit's mean speed over [t_min, t_max] (:func:`mean_speed`; ``speed`` (S,): its
    values if already known). The unit tangent is dr/dt normalized, the chord r(t_max) -
    r(t_min) where dr/dt vanishes, (1, 0) where that does too.
    """
    arrays = _fit_arrays(fit)
    t = np.ascontiguousarray(t, dtype=np.float64)
    if t.ndim != 2 or t.shape[0] != arrays[0].shape[0]:
        raise ValueError(f"t: expected shape ({arrays[0].shape[0]}, K), got {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("t: expected finite stroke parameters")
    lo = arrays[2].astype(np.float64)[:, None]
    hi = arrays[3].astype(np.float64)[:, None]
    speed = mean_speed(fit) if speed is None else np.asarray(speed, dtype=np.float64)
    dt = arrays[0].dtype
    consts = np.array([0.5, 2.0, 3.0, 0.0], dtype=dt)
    ext = (
        readonly(np.ascontiguousarray(np.broadcast_to(speed, lo.shape[:1]))),
        bool(np.any((t < lo) | (t > hi))),
    )
    out = tuple(np.empty(t.shape) for _ in range(4))
    kernels.centrelines(t, arrays, consts, ext, np.empty(t.shape, dtype=dt), out)
    return out


@dataclass(frozen=True, eq=False)
class Strips:
    """Image-space strokes: one triangle strip per drawn interval ("piece").

    Attributes
    ----------
    strip : StrokeStrip, ``left``/``right`` (P, K, 2) float64 pixels, ``t`` (P, K) stroke t
    stroke : (P,) int64, index of the piece's stroke in the fitted batch
    ids : (P,) int64, stroke id
    width : (P,) float64, full width in pixels (before taper)
    """

    strip: StrokeStrip
    stroke: np.ndarray
    ids: np.ndarray
    width: np.ndarray

    def __len__(self) -> int:
        return int(self.ids.shape[0])


def extrude(
    fit: StrokeFit,
    ids: np.ndarray,
    segments: np.ndarray,
    field: StrokeField,
    *,
    width: float = 1.5,
    taper: float = 0.2,
    wobble: float = 0.0,
    wobble_frequency: float = 1.5,
    end_jitter: float = 0.0,
    samples: int = 16,
    speed: np.ndarray | None = None,
) -> Strips:
    """Triangle strips of the drawn intervals (see module docstring).

    Parameters
    ----------
    fit : StrokeFit of S strokes; ids : (S,) int64; segments : (S, 2, 2) from
    :func:`drawn_segments` (NaN: no interval)
    field : StrokeField (its ``width_jitter`` sets the per-stroke width factor)
    width : px; taper : fraction of each end over which the width ramps from 0, [0, 0.5]
    wobble : amplitude in px; wobble_frequency : cycles per unit t
    end_jitter : fraction of the drawn length by which outer ends may move
    samples : vertex pairs per interval (>= 2)
    speed : (S,) float64, :func:`mean_speed` of ``fit`` if already known
    """
    S = int(np.asarray(ids).shape[0])
    ids = np.asarray(ids, dtype=np.int64)
    seg = np.asarray(segments, dtype=np.float64).reshape(S, 2, 2)
    has = ~np.isnan(seg[:, :, 0])
    # end jitter on the outermost ends of each stroke
    if end_jitter > 0 and S:
        n_seg = has.sum(axis=1)
        first_start = seg[:, 0, 0]
        last = np.maximum(n_seg - 1, 0)
        last_end = seg[np.arange(S), last, 1]
        span = np.where(n_seg > 0, last_end - first_start, 0.0)
        ja = end_jitter * (2.0 * hash01(ids, SALT_END_A) - 1.0) * 0.5 * span
        jb = end_jitter * (2.0 * hash01(ids, SALT_END_B) - 1.0) * 0.5 * span
        seg = seg.copy()
        seg[:, 0, 0] = np.minimum(first_start - ja, seg[:, 0, 1] - 1e-6)
        seg[np.arange(S), last, 1] = np.maximum(last_end + jb, seg[np.arange(S), last, 0] + 1e-6)
    stroke, slot = np.nonzero(has)
    P = stroke.size
    K = int(samples)
    u = np.linspace(0.0, 1.0, K)
    t0 = seg[stroke, slot, 0][:, None]
    t1 = seg[stroke, slot, 1][:, None]
    t = t0 + (t1 - t0) * u  # (P, K)
    sub = fit.take(stroke)
    sub_speed = None if speed is None else np.asarray(speed)[stroke]
    x, y, tx, ty = centreline(sub, t, speed=sub_speed) if P else (np.zeros((0, K)),) * 4
    nx, ny = -ty, tx  # left normal
    wf = width_factor(hash01(ids, SALT_WIDTH), field.width_jitter)
    w = width * wf[stroke]
    if taper > 0:
        profile = np.minimum(1.0, np.minimum(u, 1.0 - u) / taper)
    else:
        profile = np.ones_like(u)
    h = 0.5 * w[:, None] * profile[None, :]
    if wobble > 0 and P:
        amp = wobble * (0.5 + hash01(ids, SALT_WOBBLE_AMP))[stroke][:, None]
        phase = hash01(ids, SALT_WOBBLE_PHASE)[stroke][:, None]
        off = amp * np.sin(2.0 * np.pi * (wobble_frequency * t + phase))
        x = x + off * nx
        y = y + off * ny
    left, right = np.empty((P, K, 2)), np.empty((P, K, 2))
    x, y, nx, ny, h = (
        np.ascontiguousarray(np.broadcast_to(a, (P, K)), dtype=np.float64)
        for a in (x, y, nx, ny, h)
    )
    kernels.strip_sides((x, y), (nx, ny), h, (left, right))  # x + h n, x - h n
    return Strips(
        strip=StrokeStrip(left=left, right=right, t=t),
        stroke=stroke.astype(np.int64),
        ids=ids[stroke],
        width=w,
    )
