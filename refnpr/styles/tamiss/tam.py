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

from ..base import ShadeContext, register
from .compose import FieldStyle, keep_darkness
from .field import StrokeField
from .gather import field_inputs, tam_ink
from .params import TAM_PARAMS, resolve_field

__all__ = ["TamStyle"]


@register
class TamStyle(FieldStyle):
    """Texture-space hatching with the RPTAM stroke field (the TAMISS paper's baseline).

    Parameters are declared once in :data:`refnpr.styles.tamiss.params.TAM_PARAMS` (their table
    is in ``docs/tamiss.md``): the stroke field, ``width``, ``constant_tone``, ``derivatives``,
    ``orient_charts``, ``ink``, ``paper`` and ``base`` as for the ``tamiss`` style, and the
    per-sample density decision (``density_mode``, ``fade``).
    """

    name = "tam"
    renamed = TAM_PARAMS.renamed  # fill: the halftone style's name for the paper colour
    description = "TAM/RPTAM texture-space hatching on the TAMISS stroke field (baseline)"
    PARAMS = TAM_PARAMS
    INTERMEDIATES = {"darkness": "the stroke field's darkness rho of the sample, in [0, 1]"}

    def __init__(self, **params: Any) -> None:
        self.values = p = resolve_field(TAM_PARAMS.validate(params))
        self.field = StrokeField.of(p)
        self.ink, self.paper, self.base = p.ink, p.paper, p.base
        self._params = p.as_dict(keep_none=True)

    def ink_coverage(self, ctx: ShadeContext) -> np.ndarray:
        """(nH, nW) float64 ink coverage of the texture-space strokes."""
        v = self.values
        inp = field_inputs(
            ctx.gb,
            ctx.scene,
            constant_tone=v.constant_tone,
            derivatives=v.derivatives,
            orient_charts=v.orient_charts,
        )
        keep_darkness(ctx, inp)
        return tam_ink(inp, self.field, width=v.width, density_mode=v.density_mode, fade=v.fade)

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return self.composite(ctx, self.ink_coverage(ctx), self.ink)
