"""The coherence floor of a stroke image: its strokes carried exactly by the surface motion.

E / D is not 0 for a perfectly coherent sequence (the bilinear warp resamples frame t-1, and thin
strokes lose more to it than soft hatching), so a stroke style's E / D is judged against the E / D
of the same strokes moving exactly with the surface (docs/coherence.md, "The floor of a stroke
image"): :func:`carry_strips` moves frame t-1's extruded strokes to frame t, :func:`ink_floor`
rasterizes them as frame t-1 was drawn and measures both pairs on ink alone.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..styles.tamiss.raster import rasterize_strips
from .metrics import PairMetrics, pair_metrics
from .motion import MotionField, _check_gbuffer
from .strokes import STROKE_CHANNELS, carried_points

__all__ = ["InkFloor", "carry_strips", "ink_floor", "ink_image"]


@dataclass(frozen=True)
class InkFloor:
    """E / D of a stroke frame pair and of its floor (see the module docstring).

    Attributes
    ----------
    frame : int
        t.
    actual, floor : PairMetrics
        Frame t's ink, and frame t-1's strokes carried to t, each against frame t-1's ink.
    """

    frame: int
    actual: PairMetrics
    floor: PairMetrics

    @property
    def excess(self) -> float:
        """``actual.ratio - floor.ratio``: E / D due to strokes not moving with the surface."""
        return self.actual.ratio - self.floor.ratio

    def as_dict(self) -> dict:
        return {
            "frame": self.frame,
            "actual": self.actual.as_dict(),
            "floor": self.floor.as_dict(),
            "excess": None if np.isnan(self.excess) else float(self.excess),
        }


def ink_image(ink: np.ndarray, n: int) -> np.ndarray:
    """(H, W, 4) float64 grey image of ink coverage ``ink`` (nH, nW) at n x n samples per
    pixel: luminance 1 - coverage, box-resolved, alpha 1."""
    a = np.asarray(ink, dtype=np.float64)
    if a.ndim != 2 or a.shape[0] % n or a.shape[1] % n:
        raise ValueError(
            f"ink: expected an (nH, nW) coverage grid with {n} x {n} samples per pixel, got "
            f"shape {a.shape}"
        )
    h, w = a.shape[0] // n, a.shape[1] // n
    y = 1.0 - a.reshape(h, n, w, n).mean(axis=(1, 3))
    return np.stack([y, y, y, np.ones_like(y)], -1)


def _carry(points: np.ndarray, prev_gb: Any, scene: Any, prev_scene: Any) -> np.ndarray:
    """(P, K, 2) pixel coordinates of frame t-1 moved to frame t (see the module docstring)."""
    flat = points.reshape(-1, 2)
    now, ok = carried_points(prev_gb, flat, scene, prev_scene)
    d = np.where(ok[:, None], now - flat, np.nan).reshape(points.shape)
    per_strip = d.reshape(points.shape[0], -1, 2)
    seen = np.isfinite(per_strip[..., 0])
    count = seen.sum(axis=1)
    total = np.where(seen[..., None], per_strip, 0.0).sum(axis=1)
    mean = total / np.maximum(count, 1)[:, None]  # a strip with no vertex on the surface: 0
    d = np.where(np.isfinite(d), d, mean[:, None, :])
    return points + d


def carry_strips(strips: Any, prev_gb: Any, scene: Any, prev_scene: Any) -> Any:
    """Frame t-1's extruded strokes moved to frame t along the exact surface motion.

    Parameters
    ----------
    strips : refnpr.styles.tamiss.Strips
        Frame t-1's (``PipelineResult.strips``), vertices in pixels.
    prev_gb : GBuffer
        Frame t-1 at spp 1 with :data:`~refnpr.coherence.STROKE_CHANNELS` (float64
        recommended); its ``camera`` is frame t-1's.
    scene, prev_scene : Scene
        The still scenes of t and t-1.

    Returns
    -------
    Strips
        The same strips (ids, widths, t) with moved vertices.
    """
    _check_gbuffer("prev_gb", prev_gb, STROKE_CHANNELS)
    strip = strips.strip
    left = np.asarray(strip.left, dtype=np.float64)
    right = np.asarray(strip.right, dtype=np.float64)
    if left.size == 0:
        return strips
    moved = replace(
        strip,
        left=_carry(left, prev_gb, scene, prev_scene),
        right=_carry(right, prev_gb, scene, prev_scene),
    )
    return replace(strips, strip=moved)


def ink_floor(
    prev_result: Any,
    result: Any,
    prev_gb: Any,
    scene: Any,
    prev_scene: Any,
    motion: MotionField,
    *,
    frame: int = 1,
) -> InkFloor:
    """E / D of frame t's ink and of its floor, frame t-1's strokes carried exactly.

    Parameters
    ----------
    prev_result, result : refnpr.styles.tamiss.PipelineResult
        Frames t-1 and t (``TamissStyle.run_frame``), on the same sample grid.
    prev_gb : GBuffer
        Frame t-1 at spp 1 with :data:`~refnpr.coherence.STROKE_CHANNELS`.
    scene, prev_scene : Scene
        The still scenes of t and t-1.
    motion : MotionField
        ``motion_field`` of the pair at the image size.
    frame : int
        t, recorded in the result.

    Returns
    -------
    InkFloor
    """
    for name, r in (("prev_result", prev_result), ("result", result)):
        if not all(hasattr(r, a) for a in ("ink", "strips", "params", "n")):
            raise TypeError(
                f"{name}: expected a TAMISS PipelineResult (TamissStyle.run_frame), got "
                f"{type(r).__name__}"
            )
    if np.shape(prev_result.ink) != np.shape(result.ink) or prev_result.n != result.n:
        raise ValueError(
            f"result: its ink grid {np.shape(result.ink)} (n={result.n}) differs from "
            f"prev_result's {np.shape(prev_result.ink)} (n={prev_result.n}); run both frames "
            "at the same size and spp"
        )
    n = int(result.n)
    p = prev_result.params
    carried = carry_strips(prev_result.strips, prev_gb, scene, prev_scene)
    ink, _ = rasterize_strips(
        carried, np.shape(prev_result.ink), n, aa=p.aa, brush=p.brush, opacity=p.opacity
    )
    before = ink_image(prev_result.ink, n)
    actual = pair_metrics(ink_image(result.ink, n), before, motion, frame=frame)
    floor = pair_metrics(ink_image(ink, n), before, motion, frame=frame)
    return InkFloor(int(frame), actual, floor)
