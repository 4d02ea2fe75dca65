"""The ``threshold`` style class (Veryovka 2002): parameters, channels and per-sample shading;
the package docstring (:mod:`refnpr.styles.threshold`) describes the technique.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr.formulas import lighting, threshold
from refnpr.texture import MipPyramid

from .._common import needs_position, rgba_from, specular_field
from ..base import ShadeContext, Style, register
from .bump import BumpMap
from .fast import shade_fast
from .images import PyramidCache, image_thresholds
from .params import DEPRECATED, PARAMETERS, RENAMED, ThresholdParams, parse_params
from .sources import (
    Footprint,
    constant_thresholds,
    line_thresholds,
    stipple_thresholds,
)
from .strength import blend, facing_strength, tone_strength

__all__ = ["ThresholdStyle"]


@register
class ThresholdStyle(Style):
    """Discrete-tone shading against a threshold texture (Veryovka 2002 eqs. 2-8, secs. 3-5).

    ``I = m_a l_a + sum_i m_d B(f_d) l_i + sum_i m_s B(f_s) l_i`` with ``B(x) = x + st (T_n(x, t)
    - x)`` (eq. 2 at strength ``st = 1``) and t the threshold texture.

    Parameters (keyword-only, TOML-representable)
    ----------------------------------------------
    source : {"lines", "image", "stipple", "constant"}
        Where thresholds come from. "image" uses ``texture`` or each object's material texture
        (objects with neither get the constant ``t``).
    n : int >= 1
        Steps of T_n (eq. 4): n + 1 tones.
    t : float in [0, 1]
        Constant threshold (source "constant", and untextured objects of source "image").
    specular : bool
        Include the thresholded specular term (needs ``position``).
    specular_threshold : "texture" or float in [0, 1]
        Threshold the specular term against the same texture, or against a constant.
    filter : {"none", "pcf", "analytic"}
        "none": one threshold per shading sample (binary). "pcf": ``samples`` thresholds on a
        k x k grid over the sample's footprint, results averaged (images: each at the two mip
        levels, weighted by the LOD fraction; samples = 1 is the paper's two-level filter).
        "analytic": exact box filter of the thresholded lines (source "lines" only).
    samples : int, a square (1, 4, 9, 16, ...)
        K of "pcf".
    mip : {"per_level", "trilinear"}
        Image "pcf": threshold every footprint sample at the two mip levels and blend (sec. 4,
        default) or against one trilinear threshold (converges to the supersampled binary
        image). The same name and values as the ``halftone`` style's ``mip``. Deprecated:
        ``pcf_levels`` = 2 | 1.
    strength : float in [0, 1]
        Blend between eq. 1 (0) and eq. 2 (1) (sec. 5).
    facing_fade, facing_power : float
        Orientation fade: strength times ``1 - facing_fade |n.v|^facing_power`` (Fig. 5 centre).
    tone_fade : [dark, bright], widths in [0, 0.5]
        Illumination fade: no effect at x = 0 and x = 1, smoothstep over these widths (Fig. 5
        right).
    uv_scale : float > 0 or [su, sv], optional
        Multiplies texture coordinates in place of each material's ``uv_scale`` (as in every
        style). Deprecated: ``scale``, which multiplied the material's ``uv_scale``.
    texture : str or None
        Image threshold texture (built-in name or path) for every object; None: the materials'.
    window, clip_limit, nbins, rank_equalize : CLAHE settings (``refnpr.texture.clahe_pyramid``)
        ``window`` is the paper's w in texels; ``rank_equalize`` makes each level exactly uniform.
    tiling : {"none", "periodic"}
        How an image file is made to repeat before CLAHE (``refnpr.texture.load_texture``):
        "periodic" uses its periodic component (Moisan 2011) so that a photograph whose borders
        differ tiles without a seam; built-in textures tile already.
    clahe_levels : {"all", "base", "none"}
        CLAHE on every mip level (sec. 3.1), on level 0 only (plain mip-map, Fig. 3 right wall),
        or not at all (raw image, Fig. 2 top right).
    tone_correct : bool
        Map each level's bilinear threshold samples through that level's interpolant CDF, so
        that interpolation does not narrow the thresholds' distribution (refnpr's addition;
        exact tone per level, see docs/veryovka.md).
    lod_bias : float
        Added to the mip LOD.
    period : float > 0
        Line period w of eq. 5 in pixels (lines and dots; the screen period lies in [w, 2w)).
    directions : 'u', 'v', float, or a list of them
        Hatching directions in texture space, degrees; 0 or 'u' = lines parallel to u (functions
        of v), 'v' = 90. Several give cross-hatching (``combine_thresholds``). The same name and
        convention as the ``tam`` and ``tamiss`` styles. Deprecated: ``angles``.
    onsets : list of float or None
        Per-direction intensity below which that layer appears (the largest must be 1).
    uniform : bool
        Tone-preserving multi-scale blend (``multiscale_line(uniform=True)``; dots: tone table)
        instead of the paper's eq. 8, which drifts in tone between integer scales.
    multiscale : bool
        Use eqs. 7-8's transition between dyadic scales; False floors the scale (eq. 6 alone:
        lines pop where the scale crosses an integer).
    noise, noise_scale, noise_seed : line phase modulation
        Amplitude in line periods, value-noise cells per texture unit, seed (sec. 3.2);
        ``noise_seed`` also seeds the stipple's row phases.
    jitter : float in [0, 0.4]
        Stipple: dot offsets in tiles (rows of dots at random phases, each dot up to
        ``jitter`` tiles off its lattice point); 0 puts each level's dots on a rectangular
        lattice. Dots are round in screen space either way.
    bump : str or None
        A height texture (built-in name or path) bump-mapping the normals before shading: the
        alternative to threshold textures of Fig. 2 (top centre), usually with source
        "constant".
    bump_height : float
        World units per unit of bump texture value (negative: dents).
    pyramid : MipPyramid, optional (Python only)
        A prebuilt threshold pyramid used for every object (overrides ``texture``).
    """

    name = "threshold"
    renamed = RENAMED
    deprecated = DEPRECATED
    description = (
        "threshold-texture shading (Veryovka 2002): constant, CLAHE image pyramid, multi-scale "
        "lines/cross-hatching/stipple; filtered thresholding; strength blending"
    )

    @classmethod
    def parameters(cls) -> tuple[str, ...]:
        return tuple(sorted((*PARAMETERS, "pyramid")))

    def __init__(self, *, pyramid: MipPyramid | None = None, **params: Any) -> None:
        self.p: ThresholdParams = parse_params(**params)
        if pyramid is not None:
            if not isinstance(pyramid, MipPyramid):
                raise TypeError(
                    f"pyramid: expected a refnpr.texture.MipPyramid (clahe_pyramid(...)), "
                    f"got {type(pyramid).__name__}"
                )
            if pyramid.channels != 1:
                raise ValueError(
                    f"pyramid: threshold pyramids are gray, got {pyramid.channels} channels"
                )
        self.pyramid = pyramid
        self.pyramids = PyramidCache()
        self._tone_table = None
        self._bump = None if self.p.bump is None else BumpMap(self.p.bump, self.p.bump_height)
        self._params = self.p.as_dict() | ({"pyramid": "prebuilt"} if pyramid else {})

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
        p = self.p
        if p.uv_scale is None:
            uvs = ctx.material_field("uv_scale", mask)
        else:
            uvs = np.broadcast_to(np.asarray(p.uv_scale, dtype=np.float64), (int(mask.sum()), 2))
        return uvs if p.scale is None else uvs * p.scale

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

    def thresholder(self, ctx: ShadeContext, mask: np.ndarray):
        """The frame's threshold samples: an object with ``apply(x (M,), n) -> (M,)``."""
        p = self.p
        m = int(np.count_nonzero(mask))
        if p.source == "constant":
            return constant_thresholds(m, p.t)
        fp = self.footprint(ctx, mask)
        if p.source == "lines":
            s0 = None
            if self._channel_scale() and "dyadic_scale" in ctx.gb:
                sv = self.uv_scales(ctx, mask)[:, 1]
                s0 = ctx.gb["dyadic_scale"][mask].astype(np.float64) - np.log2(sv)  # eq. 5
            return line_thresholds(fp, p, s0)
        if p.source == "stipple":
            if p.uniform and self._tone_table is None:
                self._tone_table = threshold.stipple_tone_table(jitter=p.jitter)
            return stipple_thresholds(fp, p, self._tone_table if p.uniform else None)
        pyramids, keys = [], {}
        group_of_object = []
        for obj in ctx.scene.objects:
            tex = p.texture if p.texture is not None else obj.material.texture
            if self.pyramid is not None:
                tex = "<prebuilt>"
            if tex not in keys:
                keys[tex] = len(pyramids)
                if tex is None:
                    pyramids.append(None)
                elif self.pyramid is not None:
                    pyramids.append(self.pyramid)
                else:
                    pyramids.append(self.pyramids.get(tex, p, tiling=p.tiling))
            group_of_object.append(keys[tex])
        group = np.asarray(group_of_object, dtype=np.int64)[ctx.gb["mesh_id"][mask]]
        maps = None
        if p.tone_correct:
            maps = [None if q is None else self.pyramids.tone_maps(q) for q in pyramids]
        return image_thresholds(fp, pyramids, group, p, maps)

    def _term(self, x: np.ndarray, thr, orient: np.ndarray | float) -> np.ndarray:
        p = self.p
        tx = thr.apply(x, p.n)  # eq. 2: T_n(f) (filtered, sec. 4)
        st = p.strength * orient * tone_strength(x, *p.tone_fade)  # sec. 5
        return blend(x, tx, st)

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return shade_fast(self, ctx)  # one numba pass (refnpr.styles.threshold._kernels)

    def _shade_numpy(self, ctx: ShadeContext) -> np.ndarray:
        """The numpy shading path: whole-array formula calls (eqs. 1-8, sec. 4-5), kept as the
        tests' oracle of the kernel path (:func:`.fast.shade_fast`), the same image."""
        p = self.p
        gb = ctx.gb
        mask = ctx.mask
        n = gb["normal"][mask].astype(np.float64)
        if self._bump is not None:
            fp = self.footprint(ctx, mask)
            dpdx = gb["dposition_dx"][mask].astype(np.float64)
            dpdy = gb["dposition_dy"][mask].astype(np.float64)
            n = self._bump.normals(n, fp.uv, fp.gx, fp.gy, dpdx, dpdy)  # Fig. 2 top centre
        view = ctx.view_dir(mask) if (p.specular or p.facing_fade > 0.0) else None
        m_a = ctx.material_field("ambient", mask)
        m_d = ctx.material_field("diffuse", mask)
        m_s = ctx.material_field("specular", mask)
        rgb = m_a * np.asarray(ctx.scene.ambient, dtype=np.float64)  # eq. 2: ambient kept
        thr = self.thresholder(ctx, mask)
        if isinstance(p.specular_threshold, str):
            thr_s = thr
        else:
            thr_s = constant_thresholds(rgb.shape[0], p.specular_threshold)
        orient: np.ndarray | float = 1.0
        if p.facing_fade > 0.0:
            n_dot_v = np.sum(n * view, axis=-1)
            orient = facing_strength(n_dot_v, p.facing_fade, p.facing_power)  # sec. 5
        for light_dir, color in ctx.light_dirs(mask):
            f_d = lighting.diffuse(n, light_dir)  # eq. 1: f_d
            rgb = rgb + m_d * self._term(f_d, thr, orient)[:, None] * color  # eq. 2
            if p.specular:
                f_s = specular_field(ctx, n, light_dir, view, mask=mask)  # eq. 1: f_s
                rgb = rgb + m_s * self._term(f_s, thr_s, orient)[:, None] * color  # eq. 2
        out = np.zeros(mask.shape + (3,))
        out[mask] = rgb
        return rgba_from(out, mask)
