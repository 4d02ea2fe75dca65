"""Smooth shading: the continuous illumination of Veryovka 2002 eq. 1 (the reference tone)."""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr.formulas import lighting

from ._common import check_choice, needs_position, scatter_rgba, specular_field
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
        mask = ctx.mask  # shade only covered samples: (K, ...) arrays below
        n = ctx.gb["normal"][mask].astype(np.float64)
        v = ctx.view_dir(mask) if self.specular else None
        m_d = ctx.material_field("diffuse", mask)
        m_s = ctx.material_field("specular", mask)
        rgb = ctx.material_field("ambient", mask) * np.asarray(ctx.scene.ambient, float)  # eq. 1
        for light_dir, color in ctx.light_dirs(mask):
            f_d = lighting.diffuse(n, light_dir, normalize=False)  # eq. 1: f_d (unit inputs)
            rgb = rgb + m_d * f_d[:, None] * color
            if self.specular:
                f_s = specular_field(ctx, n, light_dir, v, self.model, mask)
                rgb = rgb + m_s * f_s[:, None] * color  # eq. 1: f_s
        return scatter_rgba(rgb, mask)
