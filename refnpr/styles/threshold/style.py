"""The ``threshold`` style class (Veryovka 2002): parameters, channels and per-sample shading;
the package docstring (:mod:`refnpr.styles.threshold`) describes the technique.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr.formulas import threshold

from .._common import needs_position
from ..base import ShadeContext, Style, register
from .bump import BumpMap
from .images import Footprint, PyramidCache, image_thresholds
from .params import DEPRECATED, PARAMS, checked, deprecated_forms
from .shading import shade_rgba, uv_scale_table

__all__ = ["ThresholdStyle"]


@register
class ThresholdStyle(Style):
    """Discrete-tone shading against a threshold texture (Veryovka 2002 eqs. 2-8, secs. 3-5).

    ``I = m_a l_a + sum_i m_d B(f_d) l_i + sum_i m_s B(f_s) l_i`` with ``B(x) = x + st (T_n(x, t)
    - x)`` (eq. 2 at strength ``st = 1``) and t the threshold texture.

    Parameters are declared once in :data:`refnpr.styles.threshold.params.PARAMS` (their table
    is in ``docs/veryovka.md``); ``ThresholdStyle.PARAMS`` lists them with their defaults,
    types, ranges and the modes that read them. Deprecated: ``angles`` (``directions``),
    ``pcf_levels`` = 2 | 1 (``mip``), ``scale`` (multiplied each material's uv_scale; use
    ``uv_scale``, which replaces it).
    """

    name = "threshold"
    deprecated = DEPRECATED
    description = (
        "threshold-texture shading (Veryovka 2002): constant, CLAHE image pyramid, multi-scale "
        "lines/cross-hatching/stipple; filtered thresholding; strength blending"
    )
    PARAMS = PARAMS
    INTERMEDIATES = {
        "tone": "f_d of the first light (eq. 1), the tone thresholded by eqs. 2-4",
        "threshold": "the threshold t of the sample (eqs. 3-8; pcf: the weighted mean of its "
        "thresholds; the analytic filter: the lines' threshold at the sample)",
    }

    def __init__(self, **params: Any) -> None:
        kw, self.scale = deprecated_forms(params)
        self.p = checked(PARAMS.validate(kw))
        self.pyramid = self.p.pyramid
        self.pyramids = PyramidCache()
        self._tone_table = None
        self._bump = None if self.p.bump is None else BumpMap(self.p.bump, self.p.bump_height)
        shown = self.p.as_dict()
        if self.scale is not None:  # the deprecated multiplier, where uv_scale (None) would be
            items = list(shown.items())
            at = list(shown).index("tone_fade") + 1
            shown = dict(items[:at] + [("scale", self.scale)] + items[at:])
        self._params = shown

    # ------------------------------------------------------------------------- declarations

    def _channel_scale(self) -> bool:
        """Single unfiltered lines read eq. 5 from the G-buffer's ``dyadic_scale`` channel."""
        p = self.p
        return p.source == "lines" and p.filter == "none" and p.directions == (0.0,)

    def requires(self, scene: Any) -> frozenset[str]:
        p = self.p
        req = {"normal", "mesh_id"}
        if needs_position(scene, p.specular or p.facing_fade > 0.0):
            req.add("position")
        if p.bump is not None:
            req |= {"uv", "duv_dx", "duv_dy", "dposition_dx", "dposition_dy"}
        if p.source == "constant" or (p.source == "image" and not self._textured(scene)):
            return frozenset(req)  # constant thresholds: no uv
        if self._channel_scale():
            return frozenset(req | {"uv", "dyadic_scale"})
        return frozenset(req | {"uv", "duv_dx", "duv_dy"})

    def _textured(self, scene: Any) -> bool:
        """Whether source "image" reads a texture on some object of ``scene`` (else every
        object gets the constant ``t`` and uv is not needed)."""
        p = self.p
        if p.texture is not None or self.pyramid is not None:
            return True
        return any(obj.material.texture is not None for obj in scene.objects)

    def raster_options(self, scene: Any) -> dict[str, Any]:
        return {"line_period": self.p.period} if self._channel_scale() else {}

    # ----------------------------------------------------------------------------- per frame

    def uv_scales(self, ctx: ShadeContext, mask: np.ndarray) -> np.ndarray:
        """Per covered sample ``[su, sv]`` multiplying uv: the style's ``uv_scale`` or the
        material's (times the deprecated ``scale``), ``(M, 2)`` float64."""
        return uv_scale_table(self, ctx.scene)[np.maximum(ctx.gb["mesh_id"][mask], 0)]

    def footprint(self, ctx: ShadeContext, mask: np.ndarray) -> Footprint:
        """Scaled texture coordinates and per-pixel derivatives of the covered samples."""
        gb = ctx.gb
        uvs = self.uv_scales(ctx, mask)
        if "uv" not in gb:  # source "image" without textures: only the constant t is read
            zero = np.zeros_like(uvs)
            return Footprint(zero, zero, zero, gb.n)
        uv = gb["uv"][mask].astype(np.float64) * uvs
        if "duv_dx" in gb and "duv_dy" in gb:
            gx = gb["duv_dx"][mask].astype(np.float64) * uvs
            gy = gb["duv_dy"][mask].astype(np.float64) * uvs
        else:  # channel-scale path: no footprint is read
            gx = gy = np.zeros_like(uv)
        return Footprint(uv, gx, gy, gb.n)

    def stipple_tone_table(self) -> threshold.StippleToneTable:
        """The tone table of the uniform stipple (built on first use, kept)."""
        if self._tone_table is None:
            self._tone_table = threshold.stipple_tone_table(jitter=self.p.jitter)
        return self._tone_table

    def image_thresholds(
        self, ctx: ShadeContext, mask: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Image thresholds of the covered samples (source "image"): ``(t, w)``, (M, K) each
        (w None: one threshold per sample), from each object's pyramid (the style's
        ``pyramid``, ``texture``, or the material's; none: the constant ``t``)."""
        p = self.p
        pyramids, keys = [], {}
        group_of_object = []
        for obj in ctx.scene.objects:
            tex = obj.material.texture if p.texture is None else p.texture
            if self.pyramid is not None:
                tex = "<prebuilt>"
            if tex not in keys:
                keys[tex] = len(pyramids)
                if tex is None or self.pyramid is not None:  # None: the constant t
                    pyramids.append(self.pyramid)
                else:
                    pyramids.append(self.pyramids.get(tex, p, tiling=p.tiling))
            group_of_object.append(keys[tex])
        group = np.asarray(group_of_object, dtype=np.int64)[ctx.gb["mesh_id"][mask]]
        maps = None
        if p.tone_correct:
            maps = [None if q is None else self.pyramids.tone_maps(q) for q in pyramids]
        return image_thresholds(self.footprint(ctx, mask), pyramids, group, p, maps)

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return shade_rgba(self, ctx)  # one numba pass (refnpr.styles.threshold._kernels)
