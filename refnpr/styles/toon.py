"""Classic toon shading: Veryovka 2002 eqs. 2-4 (multi-tone step) and Lake et al. 2000's ramp."""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr.formulas import lighting

from ._common import check_choice, check_count, check_number, lit_rgba, needs_position
from .base import ShadeContext, Style, register

__all__ = ["ToonStyle"]


@register
class ToonStyle(Style):
    """Discrete-tone shading.

    ``mode="step"`` (Veryovka eq. 2): ``I = m_a l_a + sum m_d T_n(f_d, t) l_i + sum m_s
    T_n(f_s, t) l_i`` with the multi-tone step T_n of eq. 4 and a constant threshold t.
    ``mode="lake"`` (Lake et al. 2000): ``I = m_a l_a + sum m_d ramp(N.L) l_i`` with a hard-edged
    ramp of ``n + 1`` tones ``0, 1/n, ..., 1`` split at ``(k + t) / n`` (nearest texel lookup).

    Parameters
    ----------
    n : int >= 1
        Steps: the diffuse term takes the n + 1 values k / n.
    t : float in [0, 1]
        Threshold within each step (eq. 3's t; 0.5 is Lake's suggestion).
    mode : {"step", "lake"}
    specular : bool
        Thresholded specular term ("step" mode only; needs ``position`` for V).
    """

    name = "toon"
    description = "n-tone toon shading (Veryovka eqs. 2-4 step, or Lake et al. 2000 ramp)"

    def __init__(
        self, *, n: int = 2, t: float = 0.5, mode: str = "step", specular: bool = True
    ) -> None:
        self.n = check_count("n", n, lo=1, hi=256)
        self.t = check_number("t", t, lo=0.0, hi=1.0)
        self.mode = check_choice("mode", mode, ("step", "lake"))
        if not isinstance(specular, (bool, np.bool_)):  # 1 and 0 are not flags
            raise TypeError(f"specular: expected a bool, got {specular!r}")
        self.specular = bool(specular) and self.mode == "step"
        self._params = {"n": self.n, "t": self.t, "mode": self.mode, "specular": self.specular}

    def requires(self, scene: Any) -> frozenset[str]:
        req = {"normal", "mesh_id"}
        if needs_position(scene, self.specular):
            req.add("position")
        return frozenset(req)

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        ramp = None
        if self.mode == "lake":
            bounds = (np.arange(self.n) + self.t) / self.n
            ramp = lighting.toon_ramp_texture(bounds, np.arange(self.n + 1) / self.n, size=1024)
        return lit_rgba(  # eq. 2 with eq. 4's T_n, or Lake's ramp: one numba pass
            ctx, mode=self.mode, specular=self.specular, n=self.n, t=self.t, ramp=ramp
        )
