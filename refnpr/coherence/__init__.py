"""Temporal coherence of rendered sequences, measured with the exact motion field.

DESIGN.md ("Frames, state and speed"): G-buffer world positions re-projected through the
previous frame's camera and object transforms, never estimated optical flow. See
``docs/coherence.md`` for every number's definition and which goal of the temporal-coherence
literature it captures.

* :func:`motion_field` -- where each pixel of frame t was in frame t-1, and the valid mask M;
* :func:`warp` -- frame t-1 resampled (bilinear) onto frame t's pixels;
* :func:`pair_metrics` -- warping error, plain difference, their ratio, flip fraction;
* :func:`measure` -- render a sequence of still scenes and measure every pair
  (:class:`CoherenceReport`: rows, summary, JSON, plot);
* :func:`stroke_ends`, :func:`stroke_pair_metrics`, :func:`measure_strokes` -- stroke styles
  (TAMISS): endpoint jitter after removing the true motion, strokes appearing and vanishing;
* :func:`ink_floor`, :func:`carry_strips` -- a stroke image's E / D against its floor, the same
  strokes carried exactly by the surface motion.
"""

from __future__ import annotations

from refnpr import _lazy

#: Public name -> submodule. Imported on first use: ``import refnpr.coherence`` does not pay for
#: the renderer.
_EXPORTS = {
    name: module
    for module, names in {
        "driver": "measure render_frame",
        "floor": "InkFloor carry_strips ink_floor ink_image",
        "metrics": "INK_THRESHOLD LUMA PairMetrics luminance pair_metrics",
        "motion": "DEPTH_RTOL MOTION_CHANNELS SNAP_PX MotionField bilinear_taps motion_field",
        "report": "METRICS STROKE_METRICS CoherenceReport",
        "strokes": "STROKE_CHANNELS StrokeEnds StrokePairMetrics measure_strokes stroke_ends "
        "stroke_pair_metrics",
        "resample": "warp",
    }.items()
    for name in names.split()
}
__all__ = sorted(_EXPORTS)


__getattr__, __dir__ = _lazy(__name__, _EXPORTS)
