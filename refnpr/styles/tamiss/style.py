"""The ``tamiss`` style class: parameters, the per-frame pipeline call and compositing; the package
docstring (:mod:`refnpr.styles.tamiss`) describes the technique and the pipeline stages.
"""

from __future__ import annotations

import copy
import inspect
from typing import Any

import numpy as np

from refnpr.formulas.tamiss import StrokeHashTable
from refnpr.raster import rasterize

from ..base import ShadeContext, Style, register
from .aggregate import AggregateHistory, aggregate_exact
from .compose import base_style, check_color, composite_ink, field_channels
from .motion import MOTION_CHANNELS, stroke_anchors
from .pipeline import PipelineResult, TamissParams, run_pipeline
from .show import show_layers
from .state import StrokeCoefficients, TamissState

__all__ = ["TamissStyle"]


@register
class TamissStyle(Style):
    """Hatching with image-space strokes fitted to stroke-ID TAM fragments (TAMISS).

    Parameters (all keyword; TOML values; see ``docs/tamiss.md``)
    ----------
    directions : 'u', 'v', an angle in degrees, or a list of them (one per hatching layer)
    layer_tones : list of float, darkness at which each layer starts (default k / layers)
    period : float, stroke row spacing in pixels (4)
    length : float, stroke length in cells of its birth level (1)
    length_jitter, width_jitter : float, relative per-stroke jitter (0.3, 0.2)
    density : float, scales the fraction of strokes drawn (1)
    max_level : int, deepest RPTAM level (10, at most 12)
    gather_width : float, pixel width of the band that gathers fragments (1)
    aggregation : 'exact' | 'hashed'; table_size (65536), max_probes (32), warmup_frames (2)
    dtype : 'float32' | 'float64', precision of sums and CG; iterations (4); prior_weight (1)
    visibility_threshold : float or None (formula default 1 / (2 (1 + prior_weight)))
    min_fragments (6), min_t_span (0.05), max_stretch (3; None: off) : the drop rule (a fit may
    be at most max_stretch times as long as the pixels its fragments cover, plus 4 px)
    extent : 'overdraw' (default: visible segments run on over outlines, Fig. 4) | 'visible' |
    'range' | 'stroke'; overdraw : run-on in px (6)
    width (1.5 px), taper (0.2), wobble (0 px), wobble_frequency (1.5 per stroke),
    end_jitter (0), samples (16 per interval), aa (4 sub-samples per axis), brush (None),
    opacity (1)
    constant_tone : float or None, darkness to use instead of lighting
    derivatives : 'smooth' | 'flat', d(uv)/d(x, y) for the field's levels: continuous across
    triangle edges (default) or the rasterizer's per-triangle values
    orient_charts : bool, orient each uv chart so that directions agree across borders (True)
    show : 'color' | 'ids' | 'fits' | 'strokes' | 'levels', the drawing (default) or a pipeline stage (fig. 5, 6)
    false-coloured by stroke id
    ink : colour of the strokes (black); paper : colour of the paper under them on the object
    (None: the background shows); base : a style drawn under the strokes (overrides paper)
    gather_scale : int or None, gather fragments on a grid of gather_scale x gather_scale samples
    per pixel (its own rasterization), independent of spp (None: the G-buffer's samples)
    average_frames : int, average aggregates over this many frames in a sequence (4; 1: off;
    sec. 4.1's proposal); average_motion : 'exact' (default: earlier frames' sums moved along
    the exact surface motion first, no lag; refnpr's) | 'none' (averaged where they were, the
    paper's proposal as written: lags (k - 1) / 2 frames); smooth : float in [0, 1),
    exponential smoothing of the fitted curves by stroke id in a sequence (0: off; refnpr's
    remedy, not the paper's)

    Sequences: :meth:`initial_state` / :meth:`shade_frame` carry a
    :class:`~refnpr.styles.tamiss.state.TamissState` (hash table, aggregate window, previous
    curves); :meth:`shade` is frame 0 of a one-frame sequence.
    """

    name = "tamiss"
    renamed = {"fill": "paper"}  # the halftone style's name for the same colour
    description = "TAMISS: stroke-ID TAM fragments fitted to image-space strokes (Szécsi et al.)"

    @classmethod
    def parameters(cls) -> tuple[str, ...]:
        own = super().parameters()
        sig = inspect.signature(TamissParams.from_params)
        return tuple(sorted((*own, *(n for n in sig.parameters if n != "cls"))))

    def __init__(
        self,
        *,
        ink: Any = (0.0, 0.0, 0.0),
        paper: Any = None,
        base: Any = None,
        **params: Any,
    ) -> None:
        self.pipeline_params = TamissParams.from_params(**params)
        self.ink = check_color("ink", ink, optional=False)
        self.paper = check_color("paper", paper)
        self.base = base_style(base)
        self._params = self.pipeline_params.as_dict() | {
            "ink": list(self.ink),
            "paper": None if self.paper is None else list(self.paper),
            "base": None if self.base is None else self.base.params() | {"name": self.base.name},
        }

    def requires(self, scene: Any) -> frozenset[str]:
        p = self.pipeline_params
        req = field_channels(scene, p.constant_tone, p.derivatives) | self._motion_channels()
        if self.base is not None:
            req |= set(self.base.requires(scene))
        return frozenset(req)

    def _motion_channels(self) -> frozenset[str]:
        """What motion-compensated averaging reads (none for a still or plain averaging)."""
        p = self.pipeline_params
        if p.average_frames > 1 and p.average_motion == "exact":
            return MOTION_CHANNELS
        return frozenset()

    def raster_options(self, scene: Any) -> dict[str, Any]:
        opts = dict(self.base.raster_options(scene)) if self.base is not None else {}
        opts["dtype"] = np.float64  # uv to ~1e-12: cells of level 12 stay exact
        return opts

    def gather_gbuffer(self, ctx: ShadeContext) -> Any:
        """The G-buffer fragments are gathered from: ``ctx.gb``, or with ``gather_scale`` g (and
        g^2 != the G-buffer's spp) the scene rasterized again at g x g samples per pixel with
        the same channels (float64)."""
        g = self.pipeline_params.gather_scale
        gb = ctx.gb
        if g is None or g == gb.n:
            return gb
        p = self.pipeline_params
        channels = sorted(
            field_channels(ctx.scene, p.constant_tone, p.derivatives) | self._motion_channels()
        )
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
        if p.aggregation == "hashed" and state.table is not None:
            if not isinstance(state.table, StrokeHashTable) or (
                state.table.size,
                state.table.max_probes,
            ) != (p.table_size, p.max_probes):
                raise ValueError(
                    f"state: its hash table does not match table_size={p.table_size}, "
                    f"max_probes={p.max_probes}; start the sequence from initial_state()"
                )
            table = copy.deepcopy(state.table)  # routed in place below; the state stays as is
        gather_gb = self.gather_gbuffer(ctx)
        moving = p.average_motion == "exact"
        anchors = tuple(state.anchors) if moving else ()
        past = tuple(state.window)
        if moving and len(anchors) != len(past):
            past, anchors = (), ()  # a window without anchors (plain averaging before): restart
        history = None
        if p.average_frames > 1 and past:
            history = AggregateHistory(
                p.average_frames,
                window=past,
                **(
                    {"anchors": anchors, "scene": ctx.scene, "size": (ctx.gb.width, ctx.gb.height)}
                    if moving
                    else {}
                ),
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
        if self.pipeline_params.show == "color":
            return composite_ink(ctx, result.ink, self.ink, base=self.base, paper=self.paper)
        cover, rgb = show_layers(result)
        return composite_ink(ctx, cover, rgb, base=self.base, paper=self.paper)
