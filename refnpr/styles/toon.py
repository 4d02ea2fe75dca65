"""Classic toon shading: Veryovka 2002 eqs. 2-4 (multi-tone step) and Lake et al. 2000's ramp."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._common import needs_position
from .base import ShadeContext, Style, register
from .lit.params import TOON
from .lit.shading import lit_rgba

__all__ = ["ToonStyle"]


@register
class ToonStyle(Style):
    """Discrete-tone shading.

    ``mode="step"`` (Veryovka eq. 2): ``I = m_a l_a + sum m_d T_n(f_d, t) l_i + sum m_s
    T_n(f_s, t) l_i`` with the multi-tone step T_n of eq. 4 and a constant threshold t.
    ``mode="lake"`` (Lake et al. 2000): ``I = m_a l_a + sum m_d ramp(N.L) l_i`` with a hard-edged
    ramp of ``n + 1`` tones ``0, 1/n, ..., 1`` split at ``(k + t) / n`` (nearest texel lookup).
    Parameters: :data:`refnpr.styles.lit.params.TOON` (``refnpr styles toon``).
    """

    name = "toon"
    description = "n-tone toon shading (Veryovka eqs. 2-4 step, or Lake et al. 2000 ramp)"
    PARAMS = TOON

    def __init__(self, **params: Any) -> None:
        p = TOON.validate(params)
        if p.mode != "step":
            p = p.replace(specular=False)  # Lake's ramp has no specular term
        self.p = p
        self.n, self.t, self.mode, self.specular = p.n, p.t, p.mode, p.specular
        self._params = p.as_dict()

    def requires(self, scene: Any) -> frozenset[str]:
        req = {"normal", "mesh_id"}
        if needs_position(scene, self.specular):
            req.add("position")
        return frozenset(req)

    def shade(self, ctx: ShadeContext, out: np.ndarray | None = None) -> np.ndarray:
        # eq. 2 with eq. 4's T_n, or Lake's ramp: one numba pass
        return lit_rgba(ctx, TOON.record(self.p), smooth=False, out=out)
