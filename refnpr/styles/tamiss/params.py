"""The parameters of the ``tamiss`` and ``tam`` styles, each declared once.

The stroke field, the tone and the colours are shared: ``tam`` (:data:`TAM_PARAMS`) and
``tamiss`` (:data:`PARAMS`) list the same :class:`~refnpr.styles._declare.Param` objects, so a
pair of renders compares like with like. Checks between parameters (``layer_tones`` against
the number of layers) are :func:`resolve_field`'s.
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any

from .._declare import Param, Params, Values
from .compose import base_style, check_color

__all__ = [
    "DEFAULT_DENSITY",
    "DEFAULT_AVERAGE_FRAMES",
    "MAX_PRIOR_WEIGHT",
    "MAX_GATHER_SCALE",
    "EXTENTS",
    "SHOW",
    "DERIVATIVES",
    "AVERAGE_MOTIONS",
    "FIELD",
    "FIELD_PARAMS",
    "PARAMS",
    "TAM_PARAMS",
    "SALTS",
    "resolve_field",
]

#: Default ``density``: each layer is complete halfway from its starting darkness to black, so
#: that the darkest tones are fully cross-hatched (strokes of ``width`` 1.5 px every 4 px cover
#: at most about 37 % per layer; with density 1 a drawing stays pale: ink about a quarter of the
#: darkness, see ``docs/tamiss.md``, "Defaults").
DEFAULT_DENSITY = 2.0
#: Default ``average_frames``: in a sequence, each frame's aggregates are averaged with the three
#: frames before, moved along the exact motion (docs/tamiss.md "Sequences": E / D of the
#: ``tamiss-knot-pen`` orbit 0.663 -> 0.633, its floor with exactly carried strokes 0.608;
#: stroke ends jitter 0.85 -> 0.26 px; no lag; 1.1x the frame). A still, frame 0, is unchanged.
DEFAULT_AVERAGE_FRAMES = 4
#: Largest ``prior_weight`` (zero-visibility points per fragment): the prior's moment sums are
#: float32 in the default precision, and a larger weight drowns every fragment anyway.
MAX_PRIOR_WEIGHT = 1e6
#: Largest ``gather_scale`` (gather samples per pixel along an axis): 16 x 16 per pixel.
MAX_GATHER_SCALE = 16
#: How much of a fitted stroke is drawn (``extent``; ``strokes.drawn_segments``).
EXTENTS = ("visible", "range", "stroke", "overdraw")
#: What the ``tamiss`` style shows (``show``): the ink, or a stage of the pipeline (fig. 5)
#: false-coloured by stroke id: the gathered ids per sample (fig. 6), the fitted cubics over
#: [t_min, t_max] as thin lines, the extruded strokes; or the strokes coloured by their birth
#: level (the nesting of fig. 2).
SHOW = ("color", "ids", "fits", "strokes", "levels")
#: How the field takes d(uv)/d(x, y): "smooth" (continuous across triangle edges, from vertex
#: tangent frames; ``charts``) or "flat" (the rasterizer's per-triangle analytic derivatives).
DERIVATIVES = ("smooth", "flat")
#: How ``average_frames`` averages (``average_motion``): "exact" moves each earlier frame's sums
#: along the exact surface motion first (refnpr's; no lag), "none" averages them where they
#: were (the paper's proposal as written; lags (k - 1) / 2 frames).
AVERAGE_MOTIONS = ("exact", "none")
#: The built-in brushes (``raster.brush_texture``).
BRUSHES = ("solid", "pen", "pencil", "dry")
#: Salts of the per-stroke hashes: tone threshold, length, width factor.
SALTS = {"tone": 1, "length": 2, "width": 3}


def _finite(d: Any) -> bool:
    try:
        return math.isfinite(float(d))
    except (OverflowError, TypeError, ValueError):
        return False


def _angles(name: str, directions: Any) -> tuple[float, ...]:
    """'u', 'v', an angle in degrees or a list of 1 to 4 of them, as angles in degrees."""
    vals = directions if isinstance(directions, (list, tuple)) else [directions]
    if not 1 <= len(vals) <= 4:
        raise ValueError(
            f"{name}: expected 1 to 4 hatching layers, got {len(vals)} ({directions!r})"
        )
    out = []
    for d in vals:
        if isinstance(d, str) and d in ("u", "v"):
            out.append(0.0 if d == "u" else 90.0)
        elif isinstance(d, (int, float)) and not isinstance(d, bool) and _finite(d):
            out.append(float(d))
        else:
            raise ValueError(
                f"{name}: each layer is 'u', 'v' or an angle in degrees from u towards v, got {d!r}"
            )
    return tuple(out)


_TONE = Param("layer_tones", 0.0, "", lo=0.0, hi=0.999)


def _tones(name: str, value: Any) -> tuple[float, ...]:
    vals = value if isinstance(value, (list, tuple)) else [value]
    return tuple(_TONE.check(v) for v in vals)


def _base(name: str, value: Any) -> Any:
    return base_style(value)


def _brush(name: str, value: Any) -> Any:
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected None, {list(BRUSHES)} or a texture name, got {value!r}")
    return value


def _power_of_two(name: str, value: int) -> int:
    if value > 1 << 30:
        raise ValueError(f"{name}: expected an integer in [2, {1 << 30}], got {value}")
    if value & (value - 1):
        raise ValueError(
            f"{name}: expected a power of two, got {value}; use {1 << value.bit_length()}"
        )
    return value


#: The RPTAM stroke field (``field.StrokeField``), shared by both styles.
FIELD = (
    Param(
        "directions",
        ("u", "v"),
        "hatching layers: 'u', 'v' or an angle in degrees from u towards v, or a list of 1 to "
        "4 of them (one layer each)",
        kind="any",
        parse=_angles,
        accepts="str, float or list",
    ),
    Param(
        "layer_tones",
        None,
        "darkness in [0, 0.999] at which each layer starts, one per layer (none: k / layers "
        "for layer k): cross-hatching in the darker tones",
        kind="any",
        parse=_tones,
        accepts="list of float",
    ),
    Param(
        "period",
        4.0,
        "target spacing of stroke rows (w of the dyadic scale)",
        lo=0.0,
        lo_open=True,
        unit="px",
    ),
    Param(
        "length",
        1.0,
        "stroke length in cells of its birth level",
        lo=0.0,
        lo_open=True,
        hi=8.0,
        unit="cells",
    ),
    Param("length_jitter", 0.3, "relative per-stroke length jitter", lo=0.0, hi=0.9),
    Param("width_jitter", 0.2, "relative per-stroke width jitter", lo=0.0, hi=0.9),
    Param(
        "density",
        DEFAULT_DENSITY,
        "scales the fraction of a layer's strokes drawn: rho = clip(density (d - d_k) / "
        "(1 - d_k), 0, 1) at darkness d",
        lo=0.0,
    ),
    Param("max_level", 10, "deepest level of the field", kind="int", lo=0, hi=12),
)
#: Stroke width, in pixels on the image (before the taper in ``tamiss``).
WIDTH = Param("width", 1.5, "stroke width", lo=0.0, lo_open=True, hi=64.0, unit="px")
#: The tone and the uv derivatives the field reads.
TONE = (
    Param(
        "constant_tone",
        None,
        "darkness in [0, 1] to draw everywhere instead of the lit tone (none: 1 - Rec. 709 "
        "luminance of the diffuse lighting)",
        lo=0.0,
        hi=1.0,
        optional=True,
    ),
    Param(
        "derivatives",
        "smooth",
        "d(uv)/d(x, y) for the field's levels: smooth (continuous across triangle edges, from "
        "vertex tangent frames) or flat (the rasterizer's per-triangle values)",
        kind="choice",
        choices=DERIVATIVES,
    ),
    Param(
        "orient_charts",
        True,
        "orient each uv chart (and join continuing charts) so that directions agree across "
        "chart borders",
        kind="bool",
    ),
)
#: Ink, paper and what is drawn under the strokes.
COLOURS = (
    Param(
        "ink",
        (0.0, 0.0, 0.0),
        "colour of the strokes (linear RGB, or one grey)",
        kind="any",
        parse=partial(check_color, optional=False),
        accepts="3 floats or float",
    ),
    Param(
        "paper",
        None,
        "colour of the paper under the strokes on the objects (none: the background shows)",
        kind="any",
        parse=check_color,
        accepts="3 floats or float",
    ),
    Param(
        "base",
        None,
        "a style drawn under the strokes (a name, a table or a Style; overrides paper)",
        kind="any",
        parse=_base,
        summary=lambda s: s.params() | {"name": s.name},
        accepts="str, table or Style",
    ),
)
_FRAME = ("salt_tone", "salt_length", "salt_width")
#: The stroke field alone (``field.StrokeField.from_params``).
FIELD_PARAMS = Params(
    "stroke_field", *FIELD, module=__name__, name="FIELD_PARAMS", where="stroke field"
)

PARAMS = Params(
    "tamiss",
    *FIELD,
    Param(
        "gather_width",
        1.0,
        "pixel width of the band across a stroke that gathers its fragments",
        lo=0.0,
        lo_open=True,
        hi=16.0,
        unit="px",
    ),
    Param(
        "aggregation",
        "exact",
        "exact: sums grouped by the 64-bit stroke id; hashed: the paper's double-hashed table "
        "(sec. 4)",
        kind="choice",
        choices=("exact", "hashed"),
    ),
    Param(
        "table_size",
        1 << 16,
        "slots of the hashed table, a power of two up to 2^30",
        kind="int",
        lo=2,
        parse=_power_of_two,
    ),
    Param("max_probes", 32, "probes of the hashed table before a stroke is lost", kind="int", lo=1),
    Param(
        "warmup_frames",
        2,
        "routings of a still's own ids that warm a fresh hashed table",
        kind="int",
        lo=0,
        hi=16,
    ),
    Param(
        "dtype",
        "float32",
        "precision of the sums and the CG solves",
        kind="choice",
        choices=("float32", "float64"),
    ),
    Param("iterations", 4, "CG iterations of the fits (sec. 3.2: 4)", kind="int", lo=0, hi=64),
    Param(
        "prior_weight",
        1.0,
        "zero-visibility points per fragment spread over [t_min, t_max] for v(t)",
        lo=0.0,
        hi=MAX_PRIOR_WEIGHT,
    ),
    Param(
        "visibility_threshold",
        None,
        "v(t) at or above which a stroke is drawn (none: 1 / (2 (1 + prior_weight)))",
        optional=True,
    ),
    Param(
        "min_fragments",
        6,
        "drop rule: fewest fragments of a drawn stroke (at least 4)",
        kind="int",
        lo=4,
    ),
    Param("min_t_span", 0.05, "drop rule: least t_max - t_min of a drawn stroke", lo=0.0, hi=1.0),
    Param(
        "max_stretch",
        3.0,
        "drop rule: a fit at most this many times as long as the pixels its fragments cover, "
        "plus 4 px (none: off)",
        lo=1.0,
        optional=True,
    ),
    Param(
        "extent",
        "overdraw",
        "what is drawn: visible (v >= threshold), range ([t_min, t_max]), stroke ([0, 1]) or "
        "overdraw (visible, the outer ends run on by overdraw px; Fig. 4)",
        kind="choice",
        choices=EXTENTS,
    ),
    Param("overdraw", 6.0, "run-on of the outer ends with extent overdraw", lo=0.0, unit="px"),
    WIDTH,
    Param("taper", 0.2, "fraction of each end over which the width ramps from 0", lo=0.0, hi=0.5),
    Param(
        "wobble",
        0.0,
        "amplitude of a perpendicular sine wobble per stroke",
        lo=0.0,
        hi=64.0,
        unit="px",
    ),
    Param("wobble_frequency", 1.5, "cycles of the wobble per unit t", lo=0.0),
    Param(
        "end_jitter",
        0.0,
        "fraction of the drawn length by which the outer ends may move",
        lo=0.0,
        hi=1.0,
    ),
    Param("samples", 16, "vertex pairs per drawn interval", kind="int", lo=2, hi=256),
    Param("aa", 4, "sub-samples per axis of the strip raster", kind="int", lo=1, hi=8),
    Param(
        "brush",
        None,
        "alpha texture along the stroke: solid, pen, pencil, dry, or a texture name or image "
        "path (dark = ink); none: solid",
        kind="any",
        parse=_brush,
        accepts="str",
    ),
    Param("opacity", 1.0, "opacity of every stroke", lo=0.0, hi=1.0),
    *TONE,
    Param(
        "show",
        "color",
        "color: the drawing; ids, fits, strokes, levels: a stage of the pipeline (Figs. 5, 6) "
        "coloured by stroke id, or the strokes by birth level",
        kind="choice",
        choices=SHOW,
    ),
    Param(
        "gather_scale",
        None,
        "gather on gather_scale x gather_scale samples per pixel, independent of spp (none: "
        "the G-buffer's samples)",
        kind="int",
        lo=1,
        hi=MAX_GATHER_SCALE,
        optional=True,
    ),
    Param(
        "average_frames",
        DEFAULT_AVERAGE_FRAMES,
        "in a sequence, average the aggregates over this many frames (1: off; sec. 4.1)",
        kind="int",
        lo=1,
        hi=16,
    ),
    Param(
        "average_motion",
        "exact",
        "exact: earlier frames' sums moved along the exact surface motion first (no lag); none: "
        "averaged where they were (the paper's proposal; lags (k - 1) / 2 frames)",
        kind="choice",
        choices=AVERAGE_MOTIONS,
    ),
    Param(
        "smooth",
        0.0,
        "in a sequence, weight of the previous frame's curve of a stroke (0: off)",
        lo=0.0,
        hi=1.0,
        hi_open=True,
        hint="1 would freeze every stroke forever",
    ),
    *COLOURS,
    renamed={"fill": "paper"},  # the halftone style's name for the same colour
    frame=_FRAME,
    module=__name__,
)

TAM_PARAMS = Params(
    "tam",
    *FIELD,
    WIDTH,
    Param(
        "density_mode",
        "fade",
        "the per-sample density decision: clip (tau < rho, binary) or fade (clip((rho - tau) "
        "/ fade, 0, 1))",
        kind="choice",
        choices=("clip", "fade"),
    ),
    Param("fade", 0.15, "threshold range of the fade decision", lo=0.0, lo_open=True, hi=1.0),
    *TONE,
    *COLOURS,
    renamed={"fill": "paper"},
    frame=_FRAME,
    module=__name__,
    name="TAM_PARAMS",
)


def resolve_field(values: Values) -> Values:
    """``values`` with ``layer_tones`` resolved: k / layers for layer k when not given, else
    checked to give one darkness per layer."""
    n = len(values.directions)
    tones = values.layer_tones
    if tones is None:
        return values.replace(layer_tones=tuple(k / n for k in range(n)))
    if len(tones) != n:
        raise ValueError(f"layer_tones: expected one darkness per layer ({n}), got {list(tones)!r}")
    return values


def salts() -> dict[str, Any]:
    """The record's hash offsets (``salt_offset`` of :data:`SALTS`)."""
    from refnpr.formulas.tamiss.field import salt_offset

    return {f"salt_{k}": salt_offset(v) for k, v in SALTS.items()}
