"""Smooth shading: the continuous illumination of Veryovka 2002 eq. 1 (the reference tone)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._common import check_choice, lit_rgba, needs_position
from .base import ShadeContext, Style, register

__all__ = ["SmoothStyle"]


@register
class SmoothStyle(Style):
    """``I = m_a l_a + sum_i m_d f_d(N, L_i) l_i + sum_i m_s f_s(N, L_i, V) l_i`` (Veryovka eq. 1).

    Parameters
    ----------
    specular : bool
        Include the specular sum (needs the ``position`` channel for V).
    model : {"blinn-phong", "phong"}
        Specular model of f_s.
    """

    name = "smooth"
    description = "continuous ambient + diffuse + specular shading (Veryovka eq. 1)"

    def __init__(self, *, specular: bool = True, model: str = "blinn-phong") -> None:
        if not isinstance(specular, (bool, np.bool_)):  # 1 and 0 are not flags
            raise TypeError(f"specular: expected a bool, got {specular!r}")
        self.specular = bool(specular)
        self.model = check_choice("model", model, ("blinn-phong", "phong"))
        self._params = {"specular": self.specular, "model": self.model}

    def requires(self, scene: Any) -> frozenset[str]:
        req = {"normal", "mesh_id"}
        if needs_position(scene, self.specular):
            req.add("position")
        return frozenset(req)

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return lit_rgba(  # eq. 1 in one numba pass over the samples
            ctx, mode="smooth", specular=self.specular, model=self.model
        )
