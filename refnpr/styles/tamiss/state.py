"""TAMISS state across the frames of a sequence, and refnpr's smoothing of fitted coefficients.

A still is frame 0 of a one-frame sequence (DESIGN, "Frames, state and speed"): the ``tamiss``
style's ``initial_state()`` is a :class:`TamissState` of frame 0 and ``shade_frame(ctx, state)``
returns the state of the next frame as a *new* object, so a state may be reused (shading it twice
gives the same frame twice) and nothing is kept in globals. What a state holds and why:
:class:`TamissState` and ``docs/tamiss.md``, "Sequences".

Coefficient smoothing (refnpr's remedy, not the paper's): a stroke present in the previous frame
draws the blend (1 - w) r(t) + w r_prev(t) of this frame's fit r and the previous frame's
(smoothed) fit r_prev, for x(t), y(t) and the visibility v(t) alike, over this frame's range
[t_min, t_max]: exponential smoothing by stroke id with weight w = ``smooth``. Both are cubics in
t, so the blend is one; the previous coefficients are re-expressed in this frame's normalized
parameter first (:func:`reexpress`). New strokes start fresh (w = 0 for them).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from math import comb

import numpy as np

from refnpr.formulas.tamiss import StrokeFit, StrokeHashTable

__all__ = ["StrokeCoefficients", "TamissState", "reexpress", "smooth_fit"]


@dataclass(frozen=True, eq=False)
class StrokeCoefficients:
    """Fitted curves of one frame by stroke id (float64; what coefficient smoothing remembers).

    Attributes
    ----------
    stroke_ids : (S,) int64, sorted ascending
    c_x, c_y, c_v : (S, 4) float64, monomial coefficients in s = (t - c) / h over [t_min, t_max]
    t_min, t_max : (S,) float64
    """

    stroke_ids: np.ndarray
    c_x: np.ndarray
    c_y: np.ndarray
    c_v: np.ndarray
    t_min: np.ndarray
    t_max: np.ndarray

    def __len__(self) -> int:
        return int(self.stroke_ids.shape[0])

    @classmethod
    def from_fit(cls, stroke_ids: np.ndarray, fit: StrokeFit) -> StrokeCoefficients:
        """The finite fits of ``fit`` (batch (S,), centred basis) for ``stroke_ids`` (S,) sorted."""
        ids = np.asarray(stroke_ids, dtype=np.int64).reshape(-1)
        cs, lo, hi, ok = _curves(fit)
        return cls(ids[ok], cs[0][ok], cs[1][ok], cs[2][ok], lo[ok], hi[ok])


def _curves(fit: StrokeFit) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, np.ndarray]:
    """c_x, c_y, c_v (S, 4), t_min, t_max (S,) of a batch of fits in float64, and which are finite."""
    cs = [np.asarray(c, dtype=np.float64).reshape(-1, 4) for c in (fit.c_x, fit.c_y, fit.c_v)]
    lo = np.asarray(fit.t_min, dtype=np.float64).reshape(-1)
    hi = np.asarray(fit.t_max, dtype=np.float64).reshape(-1)
    ok = np.isfinite(lo) & np.isfinite(hi)
    for c in cs:
        ok &= np.all(np.isfinite(c), axis=1)
    return cs, lo, hi, ok


def rescale(t_min, t_max, new_t_min, new_t_max) -> tuple[np.ndarray, np.ndarray]:
    """(alpha, beta), float64, of s' = alpha s + beta for s normalized over [t_min, t_max] and s'
    over [new_t_min, new_t_max]: alpha = h / h', beta = (c - c') / h' (c, h: centre and
    half-width); 0 where h' = 0."""
    lo, hi = np.asarray(t_min, np.float64), np.asarray(t_max, np.float64)
    lo2, hi2 = np.asarray(new_t_min, np.float64), np.asarray(new_t_max, np.float64)
    c, h = 0.5 * (lo + hi), 0.5 * (hi - lo)
    c2, h2 = 0.5 * (lo2 + hi2), 0.5 * (hi2 - lo2)
    ok = h2 > 0
    alpha = np.where(ok, h / np.where(ok, h2, 1.0), 0.0)
    return alpha, np.where(ok, (c - c2) / np.where(ok, h2, 1.0), 0.0)


def reexpress(c, t_min, t_max, new_t_min, new_t_max) -> np.ndarray:
    """Coefficients of the same cubics in the normalized parameter of another range.

    With t = c0 + h s (c0, h: centre and half-width of [t_min, t_max]) and s = alpha s' + beta,
    alpha = h' / h, beta = (c0' - c0) / h, sum_m a_m s^m = sum_j s'^j sum_{m >= j} a_m C(m, j)
    alpha^j beta^(m - j). A degenerate old range (h = 0: the curve is constant a_0 in s = 0)
    gives the constant a_0.

    Parameters
    ----------
    c : (S, 4) float64 monomial coefficients in s
    t_min, t_max, new_t_min, new_t_max : (S,) float64

    Returns
    -------
    (S, 4) float64 coefficients in s'
    """
    a = np.asarray(c, dtype=np.float64)
    alpha, beta = rescale(new_t_min, new_t_max, t_min, t_max)
    out = np.zeros_like(a)
    for j in range(4):
        for m in range(j, 4):
            out[:, j] += a[:, m] * comb(m, j) * alpha**j * beta ** (m - j)
    return out


def smooth_fit(
    fit: StrokeFit, stroke_ids: np.ndarray, previous: StrokeCoefficients | None, weight: float
) -> StrokeFit:
    """``fit`` with the strokes found in ``previous`` blended towards their previous curves.

    Parameters
    ----------
    fit : StrokeFit, batch (S,), centred basis (this frame's fits)
    stroke_ids : (S,) int64 sorted, the ids of ``fit``'s strokes
    previous : StrokeCoefficients or None (no previous frame: ``fit`` unchanged)
    weight : float in [0, 1), w of (1 - w) r + w r_prev

    Returns
    -------
    StrokeFit in ``fit``'s dtype; strokes absent from ``previous``, and non-finite fits, unchanged.
    """
    ids = np.asarray(stroke_ids, dtype=np.int64).reshape(-1)
    if previous is None or weight == 0.0 or len(previous) == 0 or ids.size == 0:
        return fit
    pos = np.minimum(np.searchsorted(previous.stroke_ids, ids), len(previous) - 1)
    hit = previous.stroke_ids[pos] == ids
    cur, lo, hi, finite = _curves(fit)
    sel = np.flatnonzero(hit & finite)
    if sel.size == 0:
        return fit
    p = pos[sel]
    out = []
    dt = np.asarray(fit.c_x).dtype
    for c_now, c_prev in zip(cur, (previous.c_x, previous.c_y, previous.c_v), strict=True):
        prev_s = reexpress(c_prev[p], previous.t_min[p], previous.t_max[p], lo[sel], hi[sel])
        blended = c_now.copy()
        blended[sel] = (1.0 - weight) * c_now[sel] + weight * prev_s
        out.append(blended.astype(dt))
    return replace(fit, c_x=out[0], c_y=out[1], c_v=out[2])


@dataclass(frozen=True, eq=False)
class TamissState:
    """What one frame of TAMISS hands to the next. Never mutated: the style copies the table
    before routing a frame through it.

    Attributes
    ----------
    frame : int, frames shaded before the one this state is for (0: a still / frame 0)
    table : StrokeHashTable or None, the paper's read-only table for this frame (hashed
        aggregation after frame 0; frame 0 warms a fresh one up with ``warmup_frames`` routings)
    window : tuple of Aggregates (float64), the last ``average_frames - 1`` frames' sums
    anchors : tuple of StrokeAnchors, one per ``window`` entry (``average_motion="exact"``):
        where that frame's strokes lay on the surface, to move its sums to a later frame
    coefficients : StrokeCoefficients or None (``smooth`` > 0 after frame 0)
    """

    frame: int = 0
    table: StrokeHashTable | None = None
    window: tuple = ()
    anchors: tuple = ()
    coefficients: StrokeCoefficients | None = None
