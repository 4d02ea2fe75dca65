"""TAMISS (Szécsi, Szirányi, Kacsó): tonal art maps with image-space strokes.

The surfaces are hatched with an RPTAM stroke field (``field``), but instead of drawing the
strokes in texture space every covered sample emits a fragment (x, y, t, id) per stroke over it
(fragment gathering); fragments are summed per stroke id (exactly, or by the paper's double-hashed
table), a cubic x(t), y(t) and a visibility v(t) are fitted per stroke by four conjugate-gradient
iterations, and each stroke is extruded to an image-space triangle strip of constant pixel width,
with taper, per-stroke randomisation, an optional brush texture and a choice of extent (visible
segments, [t_min, t_max], the whole stroke, or visible segments run on over outlines), then drawn
anti-aliased over a background or any other style (``contours`` add outlines).

Parameters of both styles are declared once in :mod:`.params` (``PARAMS``, ``TAM_PARAMS``); the
per-sample formulas are the scalar device functions of :mod:`refnpr.formulas.tamiss`, which the
kernels (:mod:`._kernels`) call.

Public API: the style :class:`TamissStyle` (registered as ``"tamiss"``), and for inspecting the
phases :func:`run_pipeline` -> :class:`PipelineResult`, :class:`TamissParams`,
:class:`StrokeField`, :func:`stroke_geometry`, :class:`AggregateHistory`, the chart layout
(:func:`chart_layout`: orientation, atlas and smooth derivatives of patch-wise uv maps) and the
``show`` views of the stages (:func:`show_layers`); in sequences the state carried from frame
to frame (:class:`TamissState`: hash table, aggregate window, previous curves for
:func:`smooth_fit`). See ``docs/tamiss.md``.
"""

from __future__ import annotations

from refnpr.formulas.tamiss.field import key32, pack_id, seed_set, unpack_id

from . import aggregate, pipeline, raster, state, style, tam
from .aggregate import *  # noqa: F403
from .charts import ChartLayout, chart_layout, vertex_frames
from .field import StrokeField, StrokeGeometry, stroke_geometry
from .gather import FieldInputs, Fragments, field_inputs, gather_fragments, layer_scale, tam_ink
from .pipeline import *  # noqa: F403
from .raster import *  # noqa: F403
from .show import show_layers
from .state import *  # noqa: F403
from .strokes import EXTENTS, Strips, centreline, drawn_segments, extrude, keep_mask
from .style import *  # noqa: F403
from .tam import *  # noqa: F403

__all__ = [
    *style.__all__,
    *tam.__all__,
    *pipeline.__all__,
    "StrokeField",
    "StrokeGeometry",
    "stroke_geometry",
    "seed_set",
    "pack_id",
    "unpack_id",
    "key32",
    "FieldInputs",
    "Fragments",
    "field_inputs",
    "gather_fragments",
    "tam_ink",
    "layer_scale",
    *aggregate.__all__,
    "EXTENTS",
    "Strips",
    "keep_mask",
    "drawn_segments",
    "centreline",
    "extrude",
    *raster.__all__,
    "ChartLayout",
    "chart_layout",
    "vertex_frames",
    "show_layers",
    *state.__all__,
]
