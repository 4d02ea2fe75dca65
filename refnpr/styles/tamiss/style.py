"""The ``tamiss`` style class: parameters, the per-frame pipeline call and compositing; the package
docstring (:mod:`refnpr.styles.tamiss`) describes the technique and the pipeline stages.
"""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np

from ..base import ShadeContext, Style, register
from .compose import base_style, check_color, composite_ink, field_channels
from .pipeline import PipelineResult, TamissParams, run_pipeline
from .show import show_layers

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
        req = field_channels(scene, p.constant_tone, p.derivatives)
        if self.base is not None:
            req |= set(self.base.requires(scene))
        return frozenset(req)

    def raster_options(self, scene: Any) -> dict[str, Any]:
        opts = dict(self.base.raster_options(scene)) if self.base is not None else {}
        opts["dtype"] = np.float64  # uv to ~1e-12: cells of level 12 stay exact
        return opts

    def run(self, ctx: ShadeContext, **kwargs: Any) -> PipelineResult:
        """The pipeline on this frame (``kwargs``: ``table``, ``history``)."""
        return run_pipeline(ctx.gb, ctx.scene, self.pipeline_params, **kwargs)

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        result = self.run(ctx)
        if self.pipeline_params.show == "color":
            return composite_ink(ctx, result.ink, self.ink, base=self.base, paper=self.paper)
        cover, rgb = show_layers(result)
        return composite_ink(ctx, cover, rgb, base=self.base, paper=self.paper)
