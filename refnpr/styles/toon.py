"""Classic toon shading: Veryovka 2002 eqs. 2-4 (multi-tone step) and Lake et al. 2000's ramp."""

from __future__ import annotations

from typing import Any

from .base import register
from .lit.params import TOON
from .lit.shading import LitStyle

__all__ = ["ToonStyle"]


@register
class ToonStyle(LitStyle):
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
    INTERMEDIATES = {
        "tone": "f_d of the first light (eq. 1)",
        "toon_tone": "the first light's toon tone: T_n(f_d, t) (eq. 4) or Lake's ramp at f_d",
    }

    @staticmethod
    def _settled(p: Any) -> Any:
        return p if p.mode == "step" else p.replace(specular=False)  # Lake's ramp: no specular
