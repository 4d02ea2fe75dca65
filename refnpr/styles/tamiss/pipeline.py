"""The TAMISS pipeline (Szécsi et al., fig. 5): gather -> aggregate -> fit -> extrude -> raster.

:func:`run_pipeline` runs every phase on a G-buffer and returns all intermediate results in a
:class:`PipelineResult` (fragments, aggregates, fits, drawn segments, strips, ink), so that tests
and notebooks can inspect each step; the ``tamiss`` style calls it and composites the ink.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from refnpr.formulas.tamiss import StrokeFit, StrokeHashTable

from .._common import check_choice, check_count, check_number
from .aggregate import (
    AggregateHistory,
    Aggregates,
    aggregate_exact,
    aggregate_hashed,
)
from .field import DEFAULT_DENSITY, StrokeField
from .gather import DERIVATIVES, FieldInputs, Fragments, field_inputs, gather_fragments
from .raster import BRUSHES, rasterize_strips
from .state import StrokeCoefficients, smooth_fit
from .strokes import (
    EXTENTS,
    Strips,
    drawn_segments,
    extrude,
    fit_aggregates,
    keep_mask,
    mean_speed,
    take_fit,
)

__all__ = ["AVERAGE_MOTIONS", "SHOW", "TamissParams", "PipelineResult", "run_pipeline"]

#: What the ``tamiss`` style shows (``show``): the ink, or a stage of the pipeline (fig. 5)
#: false-coloured by stroke id: the gathered ids per sample (fig. 6), the fitted cubics over
#: [t_min, t_max] as thin lines, the extruded strokes; or the strokes coloured by their birth
#: level (the nesting of fig. 2).
SHOW = ("color", "ids", "fits", "strokes", "levels")

#: Largest ``prior_weight`` (zero-visibility points per fragment): the prior's moment sums are
#: float32 in the default precision, and a larger weight drowns every fragment anyway.
MAX_PRIOR_WEIGHT = 1e6

#: Largest ``gather_scale`` (gather samples per pixel along an axis): 16 x 16 per pixel.
MAX_GATHER_SCALE = 16

#: Default ``average_frames``: in a sequence, each frame's aggregates are averaged with the three
#: frames before, moved along the exact motion (issue 12, docs/tamiss.md "Sequences": E / D of
#: the ``tamiss-knot-pen`` orbit 0.663 -> 0.633, its floor with exactly carried strokes 0.608;
#: stroke ends jitter 0.85 -> 0.26 px; no lag; 1.1x the frame). A still, frame 0, is unchanged.
DEFAULT_AVERAGE_FRAMES = 4

#: How ``average_frames`` averages (``average_motion``): "exact" moves each earlier frame's sums
#: along the exact surface motion first (refnpr's; no lag), "none" averages them where they
#: were (the paper's proposal as written; lags (k - 1) / 2 frames).
AVERAGE_MOTIONS = ("exact", "none")


def _check_bool(name: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):  # 1 and 0 are not flags
        raise TypeError(f"{name}: expected a bool, got {value!r}")
    return bool(value)


@dataclass(frozen=True)
class TamissParams:
    """Validated parameters of the TAMISS pipeline (see ``docs/tamiss.md`` for each).

    Build with :meth:`from_params` from the style's keyword arguments.
    """

    field: StrokeField = field(default_factory=StrokeField)
    gather_width: float = 1.0
    aggregation: str = "exact"
    table_size: int = 1 << 16
    max_probes: int = 32
    warmup_frames: int = 2
    dtype: str = "float32"
    iterations: int = 4
    prior_weight: float = 1.0
    visibility_threshold: float | None = None
    min_fragments: int = 6
    min_t_span: float = 0.05
    max_stretch: float | None = 3.0
    extent: str = "overdraw"
    overdraw: float = 6.0
    width: float = 1.5
    taper: float = 0.2
    wobble: float = 0.0
    wobble_frequency: float = 1.5
    end_jitter: float = 0.0
    samples: int = 16
    aa: int = 4
    brush: str | None = None
    opacity: float = 1.0
    constant_tone: float | None = None
    derivatives: str = "smooth"
    orient_charts: bool = True
    show: str = "color"
    gather_scale: int | None = None
    average_frames: int = DEFAULT_AVERAGE_FRAMES
    average_motion: str = "exact"
    smooth: float = 0.0

    @classmethod
    def from_params(
        cls,
        *,
        directions=("u", "v"),
        layer_tones=None,
        period: float = 4.0,
        length: float = 1.0,
        length_jitter: float = 0.3,
        width_jitter: float = 0.2,
        density: float = DEFAULT_DENSITY,
        max_level: int = 10,
        gather_width: float = 1.0,
        aggregation: str = "exact",
        table_size: int = 1 << 16,
        max_probes: int = 32,
        warmup_frames: int = 2,
        dtype: str = "float32",
        iterations: int = 4,
        prior_weight: float = 1.0,
        visibility_threshold: float | None = None,
        min_fragments: int = 6,
        min_t_span: float = 0.05,
        max_stretch: float | None = 3.0,
        extent: str = "overdraw",
        overdraw: float = 6.0,
        width: float = 1.5,
        taper: float = 0.2,
        wobble: float = 0.0,
        wobble_frequency: float = 1.5,
        end_jitter: float = 0.0,
        samples: int = 16,
        aa: int = 4,
        brush: str | None = None,
        opacity: float = 1.0,
        constant_tone: float | None = None,
        derivatives: str = "smooth",
        orient_charts: bool = True,
        show: str = "color",
        gather_scale: int | None = None,
        average_frames: int = DEFAULT_AVERAGE_FRAMES,
        average_motion: str = "exact",
        smooth: float = 0.0,
    ) -> TamissParams:
        fld = StrokeField.from_params(
            directions=directions,
            layer_tones=layer_tones,
            period=period,
            length=length,
            length_jitter=length_jitter,
            width_jitter=width_jitter,
            density=density,
            max_level=max_level,
        )
        table_size = check_count("table_size", table_size, lo=2, hi=1 << 30)
        if table_size & (table_size - 1):
            raise ValueError(
                f"table_size: expected a power of two, got {table_size}; "
                f"use {1 << table_size.bit_length()}"
            )
        if brush is not None and not isinstance(brush, str):
            raise TypeError(
                f"brush: expected None, {list(BRUSHES)} or a texture name, got {brush!r}"
            )
        if visibility_threshold is not None:
            visibility_threshold = check_number("visibility_threshold", visibility_threshold)
        if constant_tone is not None:
            constant_tone = check_number("constant_tone", constant_tone, lo=0.0, hi=1.0)
        if gather_scale is not None:
            gather_scale = check_count("gather_scale", gather_scale, lo=1, hi=MAX_GATHER_SCALE)
        smooth = check_number("smooth", smooth, lo=0.0, hi=1.0)
        if smooth >= 1.0:
            raise ValueError(
                f"smooth: expected a weight in [0, 1) (0: off; the previous frame's curve gets "
                f"weight smooth), got {smooth!r}; 1 would freeze every stroke forever"
            )
        return cls(
            field=fld,
            gather_width=check_number("gather_width", gather_width, lo=0.0, lo_open=True, hi=16.0),
            aggregation=check_choice("aggregation", aggregation, ("exact", "hashed")),
            table_size=table_size,
            max_probes=check_count("max_probes", max_probes, lo=1),
            warmup_frames=check_count("warmup_frames", warmup_frames, lo=0, hi=16),
            dtype=check_choice("dtype", dtype, ("float32", "float64")),
            iterations=check_count("iterations", iterations, lo=0, hi=64),
            prior_weight=check_number("prior_weight", prior_weight, lo=0.0, hi=MAX_PRIOR_WEIGHT),
            visibility_threshold=visibility_threshold,
            min_fragments=check_count("min_fragments", min_fragments, lo=4),
            min_t_span=check_number("min_t_span", min_t_span, lo=0.0, hi=1.0),
            max_stretch=None
            if max_stretch is None
            else check_number("max_stretch", max_stretch, lo=1.0),
            extent=check_choice("extent", extent, EXTENTS),
            overdraw=check_number("overdraw", overdraw, lo=0.0),
            width=check_number("width", width, lo=0.0, lo_open=True, hi=64.0),
            taper=check_number("taper", taper, lo=0.0, hi=0.5),
            wobble=check_number("wobble", wobble, lo=0.0, hi=64.0),
            wobble_frequency=check_number("wobble_frequency", wobble_frequency, lo=0.0),
            end_jitter=check_number("end_jitter", end_jitter, lo=0.0, hi=1.0),
            samples=check_count("samples", samples, lo=2, hi=256),
            aa=check_count("aa", aa, lo=1, hi=8),
            brush=brush,
            opacity=check_number("opacity", opacity, lo=0.0, hi=1.0),
            constant_tone=constant_tone,
            derivatives=check_choice("derivatives", derivatives, DERIVATIVES),
            orient_charts=_check_bool("orient_charts", orient_charts),
            show=check_choice("show", show, SHOW),
            gather_scale=gather_scale,
            average_frames=check_count("average_frames", average_frames, lo=1, hi=16),
            average_motion=check_choice("average_motion", average_motion, AVERAGE_MOTIONS),
            smooth=smooth,
        )

    def as_dict(self) -> dict:
        out = self.field.as_dict()
        out.update({k: v for k, v in self.__dict__.items() if k != "field"})
        return out


@dataclass(frozen=True, eq=False)
class PipelineResult:
    """Everything one frame of TAMISS produced.

    Attributes
    ----------
    params : TamissParams
    inputs : FieldInputs (per-sample uv, derivatives, darkness, chart)
    fragments : Fragments (x, y, t, id per fragment)
    aggregates : Aggregates (per-stroke sums; ``hash_stats`` for the hashed route)
    fit : StrokeFit of all S aggregated strokes
    keep : (S,) bool, the drop rule
    segments : (S, 2, 2) float64 drawn t intervals (NaN: none; dropped strokes have none)
    n_segments : (S,) int64
    strips : Strips of the drawn intervals
    ink : (nH, nW) float64 ink coverage on the sample grid
    pieces : (nH, nW) int32 pieces touching each sample
    timings : dict of seconds per phase: gather, aggregate, fit, extrude, raster, total
    table : StrokeHashTable or None, the table after this frame's routing (hashed route)
    n : int, samples per pixel along an axis of the output grid of ``ink`` (``inputs.n`` is the
        gather grid's, larger with ``gather_scale``)
    """

    params: TamissParams
    inputs: FieldInputs
    fragments: Fragments
    aggregates: Aggregates
    fit: StrokeFit
    keep: np.ndarray
    segments: np.ndarray
    n_segments: np.ndarray
    strips: Strips
    ink: np.ndarray
    pieces: np.ndarray
    timings: dict = field(default_factory=dict)
    table: StrokeHashTable | None = None
    n: int = 1

    @property
    def stroke_ids(self) -> np.ndarray:
        return self.aggregates.stroke_ids

    def stats(self) -> dict:
        """Counts of the frame: fragments, strokes, dropped, drawn, pieces (+ hash stats)."""
        out = {
            "fragments": len(self.fragments),
            "strokes": len(self.aggregates),
            "dropped": int(np.sum(~self.keep)),
            "drawn": int(np.sum(self.n_segments > 0)),
            "pieces": len(self.strips),
        }
        if self.aggregates.hash_stats is not None:
            out.update({f"hash_{k}": v for k, v in self.aggregates.hash_stats.as_dict().items()})
        return out


def run_pipeline(
    gb,
    scene,
    params: TamissParams | None = None,
    *,
    table: StrokeHashTable | None = None,
    history: AggregateHistory | None = None,
    previous: StrokeCoefficients | None = None,
    gather_gb=None,
) -> PipelineResult:
    """Run TAMISS on a G-buffer (channels uv, duv_dx, duv_dy, tri_id, mesh_id, normal).

    Parameters
    ----------
    gb : GBuffer of ``scene``
    scene : Scene
    params : TamissParams (default: defaults)
    table : StrokeHashTable, optional
        For ``aggregation="hashed"`` across frames: routed in place (the caller keeps it from frame
        to frame). Without it a fresh table is made and warmed up with ``warmup_frames`` routings
        of this frame's ids, as if the view had been still that long.
    history : AggregateHistory, optional
        Average aggregates over the last frames before fitting (sec. 4.1's proposal).
    previous : StrokeCoefficients, optional
        The previous frame's fitted curves by stroke id: with ``params.smooth`` > 0 this frame's
        fits are blended towards them (:func:`~refnpr.styles.tamiss.state.smooth_fit`).
    gather_gb : GBuffer, optional
        The G-buffer fragments are gathered from (same scene, camera and pixel size as ``gb``,
        more samples: ``gather_scale``); default ``gb``. The ink is drawn on ``gb``'s samples.
    """
    p = params if params is not None else TamissParams()
    if not isinstance(p, TamissParams):
        raise TypeError(f"params: expected TamissParams, got {type(p).__name__}")
    dtype = np.dtype(p.dtype)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    src = gb if gather_gb is None else gather_gb
    if src is not gb and (src.width, src.height) != (gb.width, gb.height):
        raise ValueError(
            f"gather_gb: expected the pixel size of gb ({gb.width}x{gb.height}), got "
            f"{src.width}x{src.height}; rasterize the gather grid at the image size, more spp"
        )
    inp = field_inputs(
        src,
        scene,
        constant_tone=p.constant_tone,
        derivatives=p.derivatives,
        orient_charts=p.orient_charts,
    )
    frags = gather_fragments(inp, p.field, gather_width=p.gather_width)
    t1 = time.perf_counter()
    timings["gather"] = t1 - t0
    sum_dtype = np.float64 if history is not None else dtype  # the history averages in float64
    if p.aggregation == "hashed":
        if table is None:
            table = StrokeHashTable(p.table_size, max_probes=p.max_probes)
            for _ in range(p.warmup_frames):
                aggregate_hashed(frags, table, dtype=dtype)
        agg = aggregate_hashed(frags, table, dtype=sum_dtype)
    else:
        agg = aggregate_exact(frags, dtype=sum_dtype)
    if history is not None:
        agg = history.push(agg).astype(dtype)
    t2 = time.perf_counter()
    timings["aggregate"] = t2 - t1
    fit = fit_aggregates(agg, iterations=p.iterations, prior_weight=p.prior_weight)
    if p.smooth > 0.0:
        fit = smooth_fit(fit, agg.stroke_ids, previous, p.smooth)  # refnpr's, not the paper's
    with np.errstate(invalid="ignore", over="ignore"):  # dropped (non-finite) fits
        speed = mean_speed(fit)  # once for the drop rule, the overdraw and the extrusion
    keep = keep_mask(
        agg,
        fit,
        min_fragments=p.min_fragments,
        min_t_span=p.min_t_span,
        max_stretch=p.max_stretch,
        px_per_fragment=1.0 / (p.gather_width * inp.n * inp.n),
        speed=speed,
    )
    t3 = time.perf_counter()
    timings["fit"] = t3 - t2
    S = len(agg)
    segments = np.full((S, 2, 2), np.nan)
    n_seg = np.zeros(S, dtype=np.int64)
    kept = np.flatnonzero(keep)
    if kept.size:
        seg_k, n_k = drawn_segments(
            take_fit(fit, kept),
            p.extent,
            threshold=p.visibility_threshold,
            overdraw=p.overdraw,
            speed=speed[kept],
        )
        segments[kept] = seg_k
        n_seg[kept] = n_k
    strips = extrude(
        fit,
        agg.stroke_ids,
        segments,
        p.field,
        width=p.width,
        taper=p.taper,
        wobble=p.wobble,
        wobble_frequency=p.wobble_frequency,
        end_jitter=p.end_jitter,
        samples=p.samples,
        speed=speed,
    )
    t4 = time.perf_counter()
    timings["extrude"] = t4 - t3
    out_shape = tuple(gb.sample_shape) if src is not gb else inp.shape
    ink, pieces = rasterize_strips(
        strips, out_shape, gb.n, aa=p.aa, brush=p.brush, opacity=p.opacity
    )
    t5 = time.perf_counter()
    timings["raster"] = t5 - t4
    timings["total"] = t5 - t0
    return PipelineResult(
        params=p,
        inputs=inp,
        fragments=frags,
        aggregates=agg,
        fit=fit,
        keep=keep,
        segments=segments,
        n_segments=n_seg,
        strips=strips,
        ink=ink,
        pieces=pieces,
        timings=timings,
        table=table,
        n=gb.n,
    )
