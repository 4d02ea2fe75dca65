"""TAM/RPTAM baseline: the TAMISS stroke field drawn in texture space (Figure 1 left, Figure 3).

Every covered sample is inked by the strokes of the RPTAM field over it (``field``: nested
seeds, levels from the dyadic scale with a fade-in of the next level, per-stroke tone thresholds),
anti-aliased across the stroke at a pixel width and at its ends. Density is decided per sample, so
a stroke is clipped (``density_mode="clip"``: binary test tau < rho) or faded
(``"fade"``: opacity clip((rho - tau) / fade, 0, 1)) where the tone changes along it, and strokes
are clipped at silhouettes and uv seams: the artefacts TAMISS removes. Same parameters as the
``tamiss`` style's stroke field, so a pair of renders compares like with like.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._common import check_choice, check_number
from ..base import ShadeContext, Style, register
from .compose import base_style, check_color, composite_ink, field_channels
from .field import DEFAULT_DENSITY, StrokeField
from .gather import DERIVATIVES, field_inputs, tam_ink

__all__ = ["TamStyle"]


@register
class TamStyle(Style):
    """Texture-space hatching with the RPTAM stroke field (the TAMISS paper's baseline).

    Parameters
    ----------
    directions, layer_tones, period, length, length_jitter, width_jitter, density, max_level :
        the stroke field, as for the ``tamiss`` style
    width : float, stroke width in pixels (1.5)
    density_mode : 'clip' | 'fade' (per-sample binary or smooth density decision)
    fade : float, threshold range of the smooth decision (0.15)
    constant_tone : float or None, darkness to use instead of lighting
    derivatives, orient_charts : as for the ``tamiss`` style
    ink, paper, base : as for the ``tamiss`` style
    """

    name = "tam"
    renamed = {"fill": "paper"}  # the halftone style's name for the same colour
    description = "TAM/RPTAM texture-space hatching on the TAMISS stroke field (baseline)"

    def __init__(
        self,
        *,
        directions: Any = ("u", "v"),
        layer_tones: Any = None,
        period: float = 4.0,
        length: float = 1.0,
        length_jitter: float = 0.3,
        width_jitter: float = 0.2,
        density: float = DEFAULT_DENSITY,
        max_level: int = 10,
        width: float = 1.5,
        density_mode: str = "fade",
        fade: float = 0.15,
        constant_tone: float | None = None,
        derivatives: str = "smooth",
        orient_charts: bool = True,
        ink: Any = (0.0, 0.0, 0.0),
        paper: Any = None,
        base: Any = None,
    ) -> None:
        self.field = StrokeField.from_params(
            directions=directions,
            layer_tones=layer_tones,
            period=period,
            length=length,
            length_jitter=length_jitter,
            width_jitter=width_jitter,
            density=density,
            max_level=max_level,
        )
        self.width = check_number("width", width, lo=0.0, lo_open=True, hi=64.0)
        self.density_mode = check_choice("density_mode", density_mode, ("clip", "fade"))
        self.fade = check_number("fade", fade, lo=0.0, lo_open=True, hi=1.0)
        self.constant_tone = (
            None
            if constant_tone is None
            else check_number("constant_tone", constant_tone, lo=0.0, hi=1.0)
        )
        self.derivatives = check_choice("derivatives", derivatives, DERIVATIVES)
        if not isinstance(orient_charts, (bool, np.bool_)):
            raise TypeError(f"orient_charts: expected a bool, got {orient_charts!r}")
        self.orient_charts = bool(orient_charts)
        self.ink = check_color("ink", ink, optional=False)
        self.paper = check_color("paper", paper)
        self.base = base_style(base)
        self._params = self.field.as_dict() | {
            "width": self.width,
            "density_mode": self.density_mode,
            "fade": self.fade,
            "constant_tone": self.constant_tone,
            "derivatives": self.derivatives,
            "orient_charts": self.orient_charts,
            "ink": list(self.ink),
            "paper": None if self.paper is None else list(self.paper),
            "base": None if self.base is None else self.base.params() | {"name": self.base.name},
        }

    def requires(self, scene: Any) -> frozenset[str]:
        req = field_channels(scene, self.constant_tone, self.derivatives)
        if self.base is not None:
            req |= set(self.base.requires(scene))
        return frozenset(req)

    def raster_options(self, scene: Any) -> dict[str, Any]:
        opts = dict(self.base.raster_options(scene)) if self.base is not None else {}
        opts["dtype"] = np.float64
        return opts

    def ink_coverage(self, ctx: ShadeContext) -> np.ndarray:
        """(nH, nW) float64 ink coverage of the texture-space strokes."""
        inp = field_inputs(
            ctx.gb,
            ctx.scene,
            constant_tone=self.constant_tone,
            derivatives=self.derivatives,
            orient_charts=self.orient_charts,
        )
        return tam_ink(
            inp, self.field, width=self.width, density_mode=self.density_mode, fade=self.fade
        )

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return composite_ink(
            ctx, self.ink_coverage(ctx), self.ink, base=self.base, paper=self.paper
        )
