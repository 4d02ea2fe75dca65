"""TAMISS: per-stroke cubic least squares over stroke fragments (Szécsi, Szirányi, Kacsó).

*Tonal Art Maps with Image Space Strokes*. Fragments of TAM/RPTAM strokes carry a stroke id, screen
position (x_i, y_i) and stroke parameter t_i. Per stroke, a cubic r(t) = (c_x . t, c_y . t),
t = (1, t, t^2, t^3), is fitted by ordinary least squares, b = A c with A = sum t_i t_i^T (eq. 1),
solved by four conjugate-gradient iterations; a cubic visibility v(t) fitted against evenly spread
zero-visibility points gives up to two visible segments, which are extruded to triangle strips.

Numerics (see ``docs/paper-notes.md``, "Szécsi et al. (TAMISS)"). The paper's claim that four
float32 CG iterations suffice fails on its literal formulation (raw monomials of t: pixels off on
narrow t ranges) and still fails, by up to a few pixels, when t is only centred and scaled. The
default fit therefore (1) sums the moments in s = (2 t - t_min - t_max) / (t_max - t_min) in
[-1, 1], with [t_min, t_max] from a first min/max pass, (2) sums x and y relative to the centre of
the stroke's fragment bounding box (found in the same pass), and (3) runs the four CG iterations
in the Legendre basis P_0..P_3 with diagonal scaling, a fixed 4 x 4 change of basis applied to the
paper's 15 sums (so the aggregate layout is the paper's). ``basis="monomial"`` and ``basis="raw"``
(with ``centre_xy=False``) keep the weaker variants to show where they break.

Pipeline: ``fit_fragments(ids, t, x, y)`` = min/max of t, x, y per stroke -> ``normalize_t`` ->
``fragment_regressors`` -> sum per stroke (``aggregate``) -> ``fit_strokes`` (the batched fit the
renderer calls) -> ``StrokeFit.visible_segments`` -> ``extrude_stroke``. The GPU's double-hashed
routing of fragments to aggregate texels is modelled separately by :class:`StrokeHashTable`.

The package is split by stage: ``field`` (the RPTAM stroke field the fragments are gathered
from: ids, hashes, levels, the TAM baseline's coverage, the darkness), ``moments`` (regressors,
aggregation), ``solve`` (CG, visibility prior), ``curve`` (the cubic and its slope), ``fit``
(fits), ``segments`` (visible segments, extrusion) and ``hashing`` (double hashing); this
module re-exports their public API. Per-sample formulas are scalar device functions
(``f.scalar``) that the ``tam`` and ``tamiss`` kernels call, ``f`` their numpy faces; the
per-stroke solves (CG, visibility prior, visible segments) are batched numpy host steps.
"""

from __future__ import annotations

from .curve import cubic, cubic_slope
from .field import (
    born_at,
    darkness,
    dyadic_scale,
    fade_in,
    hash01,
    ink_over,
    key32,
    layer_density,
    layer_frame,
    level_rule,
    pack_id,
    row_distance,
    splitmix64,
    stroke_length,
    stroke_param,
    stroke_start,
    tam_coverage,
    tam_opacity,
    unpack_id,
    width_factor,
)
from .fit import LEGENDRE, StrokeFit, fit_fragments, fit_stroke, fit_strokes
from .hashing import (
    CLAIM,
    EMPTY,
    FOUND,
    LOST,
    RouteResult,
    StrokeHashTable,
    hash_slot,
    probe_table,
)
from .moments import N_REGRESSORS, aggregate, fragment_regressors, normalize_t
from .segments import StrokeStrip, extrude_stroke, visible_segments
from .solve import cg_solve, moment_matrix, visibility_prior

__all__ = [
    "N_REGRESSORS",
    "fragment_regressors",
    "normalize_t",
    "aggregate",
    "moment_matrix",
    "cg_solve",
    "visibility_prior",
    "StrokeFit",
    "LEGENDRE",
    "fit_strokes",
    "fit_fragments",
    "fit_stroke",
    "visible_segments",
    "StrokeStrip",
    "extrude_stroke",
    "hash_slot",
    "probe_table",
    "StrokeHashTable",
    "RouteResult",
    "EMPTY",
    "FOUND",
    "CLAIM",
    "LOST",
    "cubic",
    "cubic_slope",
    "splitmix64",
    "hash01",
    "key32",
    "pack_id",
    "unpack_id",
    "born_at",
    "layer_frame",
    "dyadic_scale",
    "level_rule",
    "fade_in",
    "layer_density",
    "row_distance",
    "stroke_length",
    "stroke_start",
    "stroke_param",
    "width_factor",
    "tam_opacity",
    "tam_coverage",
    "ink_over",
    "darkness",
]
