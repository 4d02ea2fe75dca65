"""Smooth shading: the continuous illumination of Veryovka 2002 eq. 1 (the reference tone)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._common import needs_position
from .base import ShadeContext, Style, register
from .lit.params import SMOOTH
from .lit.shading import lit_rgba

__all__ = ["SmoothStyle"]


@register
class SmoothStyle(Style):
    """``I = m_a l_a + sum_i m_d f_d(N, L_i) l_i + sum_i m_s f_s(N, L_i, V) l_i`` (Veryovka eq. 1).

    Parameters: :data:`refnpr.styles.lit.params.SMOOTH` (``refnpr styles smooth``).
    """

    name = "smooth"
    description = "continuous ambient + diffuse + specular shading (Veryovka eq. 1)"
    PARAMS = SMOOTH

    def __init__(self, **params: Any) -> None:
        p = SMOOTH.validate(params)
        self.p = p
        self.specular, self.model = p.specular, p.model
        self._params = p.as_dict()

    def requires(self, scene: Any) -> frozenset[str]:
        req = {"normal", "mesh_id"}
        if needs_position(scene, self.specular):
            req.add("position")
        return frozenset(req)

    def shade(self, ctx: ShadeContext, out: np.ndarray | None = None) -> np.ndarray:
        return lit_rgba(ctx, SMOOTH.record(self.p), smooth=True, out=out)  # eq. 1, one pass
