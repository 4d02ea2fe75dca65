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

from .._declare import Values
from .aggregate import (
    AggregateHistory,
    Aggregates,
    aggregate_exact,
    aggregate_hashed,
)
from .field import StrokeField
from .gather import FieldInputs, Fragments, field_inputs, gather_fragments
from .params import PARAMS, resolve_field
from .raster import rasterize_strips
from .state import StrokeCoefficients, smooth_fit
from .strokes import (
    Strips,
    drawn_segments,
    extrude,
    fit_aggregates,
    keep_mask,
    mean_speed,
)

__all__ = ["TamissParams", "PipelineResult", "run_pipeline"]


class TamissParams:
    """Validated parameters of the TAMISS pipeline: the ``tamiss`` style's declaration
    (:data:`~refnpr.styles.tamiss.params.PARAMS`, tabled in ``docs/tamiss.md``) with
    ``layer_tones`` resolved, and the stroke field they give (``field``).

    Build with :meth:`from_params` from the style's keyword arguments; read a parameter as an
    attribute (``p.gather_width``); ``values`` are the validated values.
    """

    __slots__ = ("values", "field")

    def __init__(self, values: Values) -> None:
        values = resolve_field(values)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "field", StrokeField.of(values))

    @classmethod
    def from_params(cls, **params: Any) -> TamissParams:
        return cls(PARAMS.validate(params))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name in TamissParams.__slots__:
            raise AttributeError(name)
        return getattr(self.values, name)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("TamissParams are read-only")

    def __reduce__(self) -> tuple:
        return (TamissParams, (self.values,))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, TamissParams) and self.as_dict() == other.as_dict()

    __hash__ = None  # type: ignore[assignment]

    def as_dict(self) -> dict:
        """Every parameter as ``params()`` shows it (None values kept), in declaration order."""
        return self.values.as_dict(keep_none=True)

    def pick(self, *names: str) -> dict[str, Any]:
        """``{name: value}`` of the parameters ``names`` (a phase's keyword arguments)."""
        return {name: self.values[name] for name in names}

    def __repr__(self) -> str:
        return f"TamissParams({self.values!r})"


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
    p = params if params is not None else TamissParams.from_params()
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
    inp = field_inputs(src, scene, **p.pick("constant_tone", "derivatives", "orient_charts"))
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
        **p.pick("min_fragments", "min_t_span", "max_stretch"),
        px_per_fragment=1.0 / (p.gather_width * inp.n * inp.n),
        speed=speed,
    )
    t3 = time.perf_counter()
    timings["fit"] = t3 - t2
    segments, n_seg = drawn_segments(
        fit, p.extent, keep=keep, threshold=p.visibility_threshold, overdraw=p.overdraw, speed=speed
    )
    look = p.pick("width", "taper", "wobble", "wobble_frequency", "end_jitter", "samples")
    strips = extrude(fit, agg.stroke_ids, segments, p.field, **look, speed=speed)
    t4 = time.perf_counter()
    timings["extrude"] = t4 - t3
    out_shape = tuple(gb.sample_shape) if src is not gb else inp.shape
    ink, pieces = rasterize_strips(strips, out_shape, gb.n, **p.pick("aa", "brush", "opacity"))
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
