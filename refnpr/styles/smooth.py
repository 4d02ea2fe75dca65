"""Smooth shading: the continuous illumination of Veryovka 2002 eq. 1 (the reference tone)."""

from __future__ import annotations

from .base import register
from .lit.params import SMOOTH
from .lit.shading import LitStyle

__all__ = ["SmoothStyle"]


@register
class SmoothStyle(LitStyle):
    """``I = m_a l_a + sum_i m_d f_d(N, L_i) l_i + sum_i m_s f_s(N, L_i, V) l_i`` (Veryovka eq. 1).

    Parameters: :data:`refnpr.styles.lit.params.SMOOTH` (``refnpr styles smooth``).
    """

    name = "smooth"
    description = "continuous ambient + diffuse + specular shading (Veryovka eq. 1)"
    PARAMS = SMOOTH
    INTERMEDIATES = {"tone": "f_d of the first light (eq. 1)"}
    smooth = True
