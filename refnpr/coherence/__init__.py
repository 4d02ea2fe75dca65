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

import importlib
from typing import Any

#: Public name -> submodule. Imported on first use, so that ``refnpr coherence --help`` (and
#: every other ``refnpr`` command, whose parser imports ``refnpr.coherence.cli``) does not pay
#: for the renderer.
_EXPORTS = {
    "measure": "driver",
    "render_frame": "driver",
    "InkFloor": "floor",
    "carry_strips": "floor",
    "ink_floor": "floor",
    "ink_image": "floor",
    "INK_THRESHOLD": "metrics",
    "LUMA": "metrics",
    "PairMetrics": "metrics",
    "luminance": "metrics",
    "pair_metrics": "metrics",
    "DEPTH_RTOL": "motion",
    "MOTION_CHANNELS": "motion",
    "SNAP_PX": "motion",
    "MotionField": "motion",
    "bilinear_taps": "motion",
    "motion_field": "motion",
    "METRICS": "report",
    "STROKE_METRICS": "report",
    "CoherenceReport": "report",
    "STROKE_CHANNELS": "strokes",
    "StrokeEnds": "strokes",
    "StrokePairMetrics": "strokes",
    "measure_strokes": "strokes",
    "stroke_ends": "strokes",
    "stroke_pair_metrics": "strokes",
    "warp": "resample",
}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


__all__ = [
    "DEPTH_RTOL",
    "INK_THRESHOLD",
    "LUMA",
    "METRICS",
    "MOTION_CHANNELS",
    "SNAP_PX",
    "STROKE_CHANNELS",
    "STROKE_METRICS",
    "CoherenceReport",
    "InkFloor",
    "MotionField",
    "PairMetrics",
    "StrokeEnds",
    "StrokePairMetrics",
    "bilinear_taps",
    "carry_strips",
    "ink_floor",
    "ink_image",
    "luminance",
    "measure",
    "measure_strokes",
    "motion_field",
    "pair_metrics",
    "render_frame",
    "stroke_ends",
    "stroke_pair_metrics",
    "warp",
]
