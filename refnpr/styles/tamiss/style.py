"""The ``tamiss`` style class: parameters, the per-frame pipeline call and compositing; the package
docstring (:mod:`refnpr.styles.tamiss`) describes the technique and the pipeline stages.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from refnpr.formulas.tamiss import StrokeHashTable
from refnpr.raster import rasterize

from ..base import ShadeContext, register
from .aggregate import AggregateHistory, aggregate_exact
from .compose import FieldStyle, keep_darkness
from .motion import MOTION_CHANNELS, stroke_anchors
from .params import PARAMS
from .pipeline import PipelineResult, TamissParams, run_pipeline
from .show import first_ids, show_layers
from .state import StrokeCoefficients, TamissState

__all__ = ["TamissStyle"]


@register
class TamissStyle(FieldStyle):
    """Hatching with image-space strokes fitted to stroke-ID TAM fragments (TAMISS).

    Parameters are declared once in :data:`refnpr.styles.tamiss.params.PARAMS` (their table is
    in ``docs/tamiss.md``): the stroke field (shared with ``tam``), gathering, aggregation, the
    fits and the drop rule, the drawn extent and the strokes' look, the raster, the tone, the
    ``show`` views, the jitter remedies of sequences and the colours.

    Sequences: :meth:`initial_state` / :meth:`shade_frame` carry a
    :class:`~refnpr.styles.tamiss.state.TamissState` (hash table, aggregate window, previous
    curves); :meth:`shade` is frame 0 of a one-frame sequence.
    """

    name = "tamiss"
    renamed = PARAMS.renamed  # fill: the halftone style's name for the paper colour
    description = "TAMISS: stroke-ID TAM fragments fitted to image-space strokes (Szécsi et al.)"
    PARAMS = PARAMS
    INTERMEDIATES = {
        "darkness": "the stroke field's darkness rho of the sample, in [0, 1]",
        "stroke_id": "the 64-bit id of the sample's first gathered fragment (fig. 6), -1: none",
    }

    def __init__(self, **params: Any) -> None:
        self.pipeline_params = p = TamissParams(PARAMS.validate(params))
        self.values = p.values
        self.ink, self.paper, self.base = p.ink, p.paper, p.base
        self._params = p.as_dict()

    def stroke_channels(self, scene: Any) -> set[str]:
        p = self.pipeline_params
        req = super().stroke_channels(scene)
        if p.average_frames > 1 and p.average_motion == "exact":
            req |= MOTION_CHANNELS  # what motion-compensated averaging reads
        return req

    def gather_gbuffer(self, ctx: ShadeContext) -> Any:
        """The G-buffer fragments are gathered from: ``ctx.gb``, or with ``gather_scale`` g (and
        g^2 != the G-buffer's spp) the scene rasterized again at g x g samples per pixel with
        the same channels (float64)."""
        g = self.pipeline_params.gather_scale
        gb = ctx.gb
        if g is None or g == gb.n:
            return gb
        channels = sorted(self.stroke_channels(ctx.scene))
        return rasterize(
            ctx.scene, gb.camera, gb.width, gb.height, channels, g * g, dtype=np.float64
        )

    def run(self, ctx: ShadeContext, **kwargs: Any) -> PipelineResult:
        """The pipeline on this frame (``kwargs``: ``table``, ``history``, ``previous``)."""
        if "gather_gb" not in kwargs:
            kwargs["gather_gb"] = self.gather_gbuffer(ctx)
        return run_pipeline(ctx.gb, ctx.scene, self.pipeline_params, **kwargs)

    def initial_state(self) -> TamissState | None:
        """Frame 0's state: None when nothing carries over (exact aggregation, no averaging, no
        smoothing), else an empty :class:`TamissState` (frame 0 then equals the still)."""
        p = self.pipeline_params
        if p.aggregation == "exact" and p.average_frames == 1 and p.smooth == 0.0:
            return None
        return TamissState()

    def state_frames(self) -> int | None:
        """``average_frames`` k with exact aggregation and no smoothing: the state at frame f is
        the sums of frames f - k + 1 .. f - 1, made alike from any start at least k frames
        before (the first frame of a run starts its window from its drawn strokes only, so
        one more). None otherwise: the hash table and the smoothed curves carry all history."""
        p = self.pipeline_params
        if p.aggregation == "exact" and p.smooth == 0.0 and p.average_frames > 1:
            return p.average_frames
        return None

    def run_frame(
        self, ctx: ShadeContext, state: TamissState | None, *, next_state: bool = True
    ) -> tuple[PipelineResult, Any]:
        """The pipeline on one frame of a sequence from ``state`` (not modified) and the state
        of the next frame (a new object; None when the style carries nothing, or when
        ``next_state`` is false: a still, whose next frame never comes, skips making it)."""
        if state is None:
            state = self.initial_state()
            if state is None:
                return self.run(ctx), None
        if not isinstance(state, TamissState):
            raise TypeError(
                f"state: expected a TamissState from initial_state() or the previous "
                f"shade_frame, got {type(state).__name__}"
            )
        p = self.pipeline_params
        table = None
        old = state.table
        if p.aggregation == "hashed" and old is not None:
            kind = (old.size, old.max_probes) if isinstance(old, StrokeHashTable) else None
            if kind != (p.table_size, p.max_probes):
                raise ValueError(
                    f"state: its hash table does not match table_size={p.table_size}, "
                    f"max_probes={p.max_probes}; start the sequence from initial_state()"
                )
            table = copy.deepcopy(old)  # routed in place below; the state stays as is
        gather_gb = self.gather_gbuffer(ctx)
        moving = p.average_motion == "exact"
        anchors = tuple(state.anchors) if moving else ()
        past = tuple(state.window)
        if moving and len(anchors) != len(past):
            past, anchors = (), ()  # a window without anchors (plain averaging before): restart
        history = None
        if p.average_frames > 1 and past:
            size = (ctx.gb.width, ctx.gb.height)
            carried = anchors if moving else None
            history = AggregateHistory(
                p.average_frames, past, anchors=carried, scene=ctx.scene, size=size
            )
        previous = state.coefficients if p.smooth > 0.0 else None
        result = self.run(ctx, table=table, history=history, previous=previous, gather_gb=gather_gb)
        if not next_state:
            return result, None
        window: tuple = ()
        if history is not None:
            window = history.window[1 - p.average_frames :]
        elif p.average_frames > 1:
            # the first frame of the window: drawn from its own sums (an average of one frame,
            # so the still is unchanged); its float64 sums start the window. Exact sums of the
            # strokes drawn are the hashed route's too (a valid slot holds one stroke's
            # fragments, summed in the same order)
            exact = aggregate_exact(result.fragments, dtype=np.float64)
            window = (exact.take(np.isin(exact.stroke_ids, result.stroke_ids)),)
        new_anchors: tuple = ()
        if window and moving:
            here = stroke_anchors(window[-1], gather_gb, ctx.scene)  # this frame's sums
            new_anchors = (*anchors, here)[-len(window) :]
        new = TamissState(
            frame=state.frame + 1,
            table=result.table if p.aggregation == "hashed" else None,
            window=window,
            anchors=new_anchors,
            coefficients=StrokeCoefficients.from_fit(result.stroke_ids, result.fit)
            if p.smooth > 0.0
            else None,
        )
        return result, new

    def shade_frame(self, ctx: ShadeContext, state: Any) -> tuple[np.ndarray, Any]:
        result, new = self.run_frame(ctx, state)
        return self._composite(ctx, result), new

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return self._composite(ctx, self.run_frame(ctx, self.initial_state(), next_state=False)[0])

    def _composite(self, ctx: ShadeContext, result: PipelineResult) -> np.ndarray:
        if ctx.wants_intermediates:
            keep_darkness(ctx, result.inputs)
            ctx.keep("stroke_id", first_ids(result))
        if self.pipeline_params.show == "color":
            return self.composite(ctx, result.ink, self.ink)
        return self.composite(ctx, *show_layers(result))
