"""Image threshold textures of the ``threshold`` style (Veryovka sec. 3.1 and sec. 4), and the
footprint of the covered samples in texture space.

The footprint of a sample is its share of the pixel: with ``spp = k * k`` the pixel derivatives
divided by k. Scales (the dyadic scale of eq. 5, the mip LOD) are per *pixel* whatever the
supersampling, so that supersampling converges to the box filter of the one-sample-per-pixel
image of the same view. The LOD is the GL isotropic one from the analytic uv derivatives (per
pixel), so one pyramid serves objects with different ``uv_scale``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.texture import (
    MipPyramid,
    build_pyramid,
    check_tiling,
    clahe_pyramid,
    level_weights,
    load_texture,
    sample_level,
    sample_trilinear,
    texture_lod,
)

__all__ = [
    "Footprint",
    "grid_offsets",
    "PyramidCache",
    "ToneMaps",
    "interpolation_quantiles",
    "image_thresholds",
]


@dataclass(frozen=True)
class Footprint:
    """Texture coordinates of the M covered samples of a frame.

    Attributes
    ----------
    uv : (M, 2) float64
        Texture coordinates (already multiplied by the style's or material's ``uv_scale``).
    gx, gy : (M, 2) float64
        Screen derivatives of ``uv`` per pixel (x to the right, y downward).
    n : int
        Samples per pixel along each axis: a sample covers ``1 / n`` of the pixel per axis.
    """

    uv: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    n: int

    def offsets_uv(self, k: int) -> np.ndarray:
        """(M, k*k, 2) texture coordinates of a k x k grid over each sample's footprint."""
        o = grid_offsets(k) / self.n  # (K, 2) in pixels
        return (
            self.uv[:, None, :]
            + o[None, :, 0:1] * self.gx[:, None, :]
            + o[None, :, 1:2] * self.gy[:, None, :]
        )


def grid_offsets(k: int) -> np.ndarray:
    """(k*k, 2) float64 offsets ((i + 0.5) / k - 0.5, (j + 0.5) / k - 0.5) in [-1/2, 1/2]^2."""
    g = (np.arange(k) + 0.5) / k - 0.5
    oy, ox = np.meshgrid(g, g, indexing="ij")
    return np.stack([ox.ravel(), oy.ravel()], axis=-1)


#: Quantiles kept per level for the interpolation tone correction.
_N_QUANTILES = 1024
#: Sub-texel phases per axis at which the bilinear interpolant's distribution is measured.
_PHASES = 4


def interpolation_quantiles(level: np.ndarray) -> np.ndarray:
    """(_N_QUANTILES + 1,) quantiles of a level's bilinear interpolant at uniform positions.

    Bilinear interpolation averages neighbouring thresholds, which narrows their distribution
    towards the middle: even an exactly uniform level gives too few thresholds near 0 and 1,
    so thresholding darkens light tones and lightens dark ones. The interpolant's CDF, measured
    on a ``_PHASES x _PHASES`` grid of sub-texel positions (GL_REPEAT), maps it back to uniform.
    """
    lv = level.astype(np.float64)
    right = np.roll(lv, -1, axis=1)
    down = np.roll(lv, -1, axis=0)
    diag = np.roll(right, -1, axis=0)
    phases = (np.arange(_PHASES) + 0.5) / _PHASES
    values = [
        (1 - a) * (1 - b) * lv + a * (1 - b) * right + (1 - a) * b * down + a * b * diag
        for b in phases
        for a in phases
    ]
    q = np.quantile(
        np.concatenate([v.ravel() for v in values]), np.linspace(0, 1, _N_QUANTILES + 1)
    )
    return np.maximum.accumulate(q)


class ToneMaps:
    """Per-level monotone maps t -> CDF_k(t) making bilinear threshold samples uniform."""

    def __init__(self, pyramid: MipPyramid) -> None:
        self.quantiles = [interpolation_quantiles(lv) for lv in pyramid.levels]
        self._p = np.linspace(0.0, 1.0, _N_QUANTILES + 1)

    def apply(self, t: np.ndarray, level: np.ndarray) -> np.ndarray:
        """``t`` (S, ...) float64 sampled at ``level`` (S,) int -> uniform-corrected thresholds."""
        out = np.empty_like(t)
        for k in np.unique(level):
            sel = level == k
            q = self.quantiles[int(k)]
            if q[-1] - q[0] <= 0.0:  # a constant level (1x1): its single value is the median
                out[sel] = 0.5
                continue
            out[sel] = np.interp(t[sel], q, self._p)
        return out


class PyramidCache:
    """Threshold pyramids by texture and CLAHE settings, owned by a style instance: ``get``
    builds a pyramid on first use only (never per frame)."""

    def __init__(self) -> None:
        self._pyramids: dict[tuple, MipPyramid] = {}
        self._tone_maps: dict[int, ToneMaps] = {}

    def tone_maps(self, pyramid: MipPyramid) -> ToneMaps:
        """The (cached) interpolation tone maps of ``pyramid``."""
        key = id(pyramid)
        if key not in self._tone_maps:
            self._tone_maps[key] = ToneMaps(pyramid)
        return self._tone_maps[key]

    def __len__(self) -> int:
        return len(self._pyramids)

    def get(self, texture: str, p: Any, *, tiling: str | None = None) -> MipPyramid:
        """The threshold pyramid of ``texture`` (built-in name or path) for ``p``'s CLAHE settings.

        ``clahe_levels``: "all" applies CLAHE to every mip level (sec. 3.1); "base" equalizes
        level 0 only and box-filters it down (the plain mip-map of Figure 3's right wall); "none"
        uses the raw image (Figure 2, top right).

        ``tiling`` ("none"/None or "periodic", :func:`refnpr.texture.load_texture`): how an
        image file is made to repeat before CLAHE; built-in textures tile already.
        """
        tiling = check_tiling(tiling)
        key = (texture, tiling, p.window, p.clip_limit, p.nbins, p.rank_equalize, p.clahe_levels)
        if key not in self._pyramids:
            image = load_texture(texture, tiling=tiling)
            if p.clahe_levels == "none":
                pyr = build_pyramid(image)
            else:
                pyr = clahe_pyramid(
                    image,
                    window=p.window,
                    clip_limit=p.clip_limit,
                    nbins=p.nbins,
                    uniform=p.rank_equalize,
                )
                if p.clahe_levels == "base":
                    pyr = build_pyramid(pyr.levels[0])
            self._pyramids[key] = pyr
        return self._pyramids[key]


def image_thresholds(
    fp: Footprint,
    pyramids: list[MipPyramid | None],
    group: np.ndarray,
    p: Any,
    tone_maps: list[ToneMaps | None] | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Threshold samples of image threshold textures (sec. 3.1) with the style's filter (sec. 4):
    ``(t, w)``, the (M, K) thresholds per covered sample and their weights (None: one threshold,
    unfiltered), thresholded in the kernel as ``pcf_threshold`` (or ``step_n`` for one).

    Parameters
    ----------
    fp : Footprint
    pyramids : list of MipPyramid or None
        One per group; None stands for the constant threshold ``p.t`` (untextured objects).
    group : (M,) int
        Index into ``pyramids`` of each sample.
    p : the style's parameter values
        ``filter="none"``: one trilinear threshold per sample. ``filter="pcf"``: K samples on a
        k x k grid over the footprint, each thresholded at the two mip levels that trilinear
        filtering would blend, weighted (1 - Frac(lambda)) / K and Frac(lambda) / K; K = 1 is the
        paper's two-level filtered thresholding. With ``p.mip == "trilinear"`` each footprint sample
        is one trilinear threshold instead (the PCF of the binary image itself).
    tone_maps : list of ToneMaps or None, optional
        Per group (``p.tone_correct``): each level's bilinear samples are mapped through that
        level's interpolant CDF before use (exactly uniform per level; trilinear blends the two
        corrected levels).
    """
    m = fp.uv.shape[0]
    pcf = p.filter == "pcf"
    k = int(round(p.samples**0.5)) if pcf else 1
    kk = k * k
    two = pcf and p.mip == "per_level"
    width = 2 * kk if two else kk
    t = np.full((m, width), p.t)
    w = np.full((m, width), 1.0 / width) if pcf else None
    for gi, pyr in enumerate(pyramids):
        sel = np.flatnonzero(group == gi)
        if pyr is None or sel.size == 0:
            continue
        lod = texture_lod(pyr, fp.gx[sel], fp.gy[sel]) + p.lod_bias
        tm = None if tone_maps is None else tone_maps[gi]
        sub = Footprint(fp.uv[sel], fp.gx[sel], fp.gy[sel], fp.n)
        uvk = sub.offsets_uv(k) if pcf else sub.uv[:, None, :]  # (S, kk, 2)
        if not two and tm is None:  # one trilinear threshold per footprint sample
            lods = np.broadcast_to(lod[:, None], uvk.shape[:2])
            t[sel] = sample_trilinear(pyr, uvk, lods, dtype=np.float64)
            continue
        k0, k1, f = level_weights(pyr, lod)
        t0 = sample_level(pyr, uvk, k0[:, None], dtype=np.float64)
        t1 = sample_level(pyr, uvk, k1[:, None], dtype=np.float64)
        if tm is not None:
            t0, t1 = tm.apply(t0, k0), tm.apply(t1, k1)
        if not two:  # trilinear from the two (tone-corrected) levels
            t[sel] = (1.0 - f)[:, None] * t0 + f[:, None] * t1
            continue
        t[sel, :kk], t[sel, kk:] = t0, t1
        w[sel, :kk] = ((1.0 - f) / kk)[:, None]  # sec. 4: weighted sum over two mip levels
        w[sel, kk:] = (f / kk)[:, None]
    return t, w
