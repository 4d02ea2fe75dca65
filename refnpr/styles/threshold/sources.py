"""Threshold sources of the ``threshold`` style and their filtered thresholding (Veryovka sec. 3-4).

A source turns the covered samples' texture coordinates into a *thresholder*: an object whose
``apply(x, n)`` returns the (filtered) step ``T_n(x, t)`` of eq. 4 for a continuous shading term
x, per sample. The texture samples are taken once per frame and reused for every term (diffuse
and specular, every light).

Filtering (sec. 4) thresholds *several* texture samples and averages the results (the
percentage-closer analogue), or, for procedural lines, integrates the thresholded line texture
over the footprint analytically. The footprint of a sample is its share of the pixel: with
``spp = k * k`` the pixel derivatives divided by k. Scales (the dyadic scale of eq. 5, the mip LOD)
are per *pixel* whatever the supersampling, so that supersampling converges to the box filter of
the one-sample-per-pixel image of the same view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refnpr.formulas import threshold as thr

from .noise import value_noise
from .params import ThresholdParams

__all__ = [
    "Footprint",
    "SampledThresholds",
    "AnalyticLines",
    "grid_offsets",
    "line_layers",
    "constant_thresholds",
    "line_thresholds",
    "stipple_thresholds",
]


@dataclass(frozen=True)
class Footprint:
    """Texture coordinates of the M covered samples of a frame.

    Attributes
    ----------
    uv : (M, 2) float64
        Texture coordinates (already multiplied by the material's ``uv_scale`` and ``scale``).
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


class SampledThresholds:
    """Thresholds from K texture samples per shading sample, with weights (sec. 4, PCF analogue).

    ``apply(x, n) = sum_k w_k T_n(x, t_k) / sum_k w_k``: the thresholding results are filtered,
    not the thresholds. K = 1 without weights is the unfiltered (binary) step.

    Parameters
    ----------
    t : (M, K) float64
    weights : (M, K) float64 or None
    """

    def __init__(self, t: np.ndarray, weights: np.ndarray | None = None) -> None:
        self.t = t
        self.weights = weights

    def apply(self, x: np.ndarray, n: int) -> np.ndarray:
        """(M,) float64 filtered T_n(x, t) for x (M,) float64."""
        if self.t.shape[1] == 1 and self.weights is None:
            return thr.step_n(x, self.t[:, 0], n)  # eq. 4 (eq. 3 for n = 1)
        return thr.pcf_threshold(x, self.t, weights=self.weights, n=n)  # sec. 4


def constant_thresholds(m: int, t: float) -> SampledThresholds:
    """A constant threshold (the classic toon step of eqs. 3-4)."""
    return SampledThresholds(np.full((m, 1), float(t)))


# ------------------------------------------------------------------------- procedural lines


@dataclass(frozen=True)
class LineLayer:
    """One hatching direction: line coordinate, its pixel derivatives, its dyadic scale."""

    v: np.ndarray  # (M,) texture units
    dvx: np.ndarray  # (M,) per pixel
    dvy: np.ndarray  # (M,) per pixel
    s: np.ndarray  # (M,) eq. 5


def line_layers(fp: Footprint, p: ThresholdParams, s0: np.ndarray | None = None) -> list:
    """The hatching layers of ``p.directions`` (degrees in texture space; 0 = lines parallel to u).

    ``s0`` optionally gives angle 0's dyadic scale (the G-buffer ``dyadic_scale`` channel).
    Without ``p.multiscale`` the scale is floored: eq. 6 alone, which pops at integer scales.
    """
    layers = []
    for deg in p.directions:
        a = np.radians(deg)
        v = thr.hatch_coordinate(fp.uv, a)
        dvx = thr.hatch_coordinate(fp.gx, a)
        dvy = thr.hatch_coordinate(fp.gy, a)
        if deg == 0.0 and s0 is not None:
            s = s0
        else:
            s = thr.dyadic_scale_from_gradient(dvx, dvy, p.period)  # eq. 5
        if not p.multiscale:
            s = np.floor(s)  # eq. 6 at integer scales only (no eq. 7-8 transition)
        layers.append(LineLayer(v, dvx, dvy, s))
    return layers


def _noise(fp: Footprint, p: ThresholdParams) -> np.ndarray | None:
    if p.noise == 0.0:
        return None
    return p.noise * value_noise(fp.uv * p.noise_scale, seed=p.noise_seed)  # line periods


def line_thresholds(fp: Footprint, p: ThresholdParams, s0: np.ndarray | None = None):
    """Thresholder of the procedural line source (sec. 3.2) with the style's filter."""
    layers = line_layers(fp, p, s0)
    noise = _noise(fp, p)
    if p.filter == "analytic":
        onsets = p.onsets if p.onsets is not None else (1.0,) * len(layers)
        return AnalyticLines(layers, fp.n, onsets, p.uniform, noise)
    k = 1 if p.filter == "none" else int(round(p.samples**0.5))
    o = grid_offsets(k) / fp.n
    fs = []
    for layer in layers:
        v = (
            layer.v[:, None]
            + o[None, :, 0] * layer.dvx[:, None]
            + o[None, :, 1] * layer.dvy[:, None]
        )
        nz = None if noise is None else noise[:, None]
        fs.append(thr.line_threshold(v, layer.s[:, None], uniform=p.uniform, noise=nz))  # eqs. 6-8
    if len(fs) == 1:
        return SampledThresholds(fs[0])
    return SampledThresholds(thr.combine_thresholds(fs, onsets=p.onsets))


class AnalyticLines:
    """Analytic box filter of the thresholded lines over each sample's footprint (sec. 4).

    Single layer: exact (``line_coverage``; v linear over the footprint, s constant). Noise is
    held constant over the footprint: Frac(F + z) <= x on {F <= x - z} and
    {1 - z <= F <= x + 1 - z} (z = Frac(noise)), a difference of coverages. Several layers
    (cross-hatching): white is {F_i <= w_i(x) for all i} (``layer_whites``, the allocation of
    ``combine_thresholds``); the coverage is taken as the product of the layers' coverages, exact for a point footprint and for footprints spanning
    many lines of different directions (independent layers), approximate in between.
    """

    def __init__(self, layers, n: int, onsets, uniform: bool, noise) -> None:
        self.layers = layers
        self.n = n
        self.onsets = tuple(onsets)
        self.uniform = uniform
        self.z = None if noise is None else noise - np.floor(noise)

    def _cover(self, layer: LineLayer, y: np.ndarray) -> np.ndarray:
        def cov(level):
            return thr.line_coverage(
                layer.v,
                layer.s,
                level,
                layer.dvx / self.n,
                layer.dvy / self.n,
                uniform=self.uniform,
            )

        if self.z is None:
            return cov(y)
        z = self.z
        return cov(y - z) + cov(y + 1.0 - z) - cov(1.0 - z)

    def apply(self, x: np.ndarray, n: int) -> np.ndarray:
        """(M,) float64 box-filtered T_n(x, F) for x (M,) float64 (T_n via eq. 4's split)."""
        xn = x * n
        base = np.floor(xn)
        r = xn - base  # eq. 4: T_n = (floor(x n) + T(Frac(x n), t)) / n
        ws = thr.layer_whites(r, self.onsets) if len(self.layers) > 1 else r[None]
        cover = np.ones_like(x)
        for layer, w in zip(self.layers, ws, strict=True):
            cover = cover * self._cover(layer, w)  # white: F_i <= w_i(x) in every layer
        cover = np.where(r >= 1.0, 1.0, np.clip(cover, 0.0, 1.0))
        return np.minimum(base + cover, np.ceil(xn)) / n


# --------------------------------------------------------------------------------- stippling


def stipple_thresholds(fp: Footprint, p: ThresholdParams, tone_table) -> SampledThresholds:
    """Thresholder of the multi-scale dot texture (Fig. 4, stippling), point or PCF samples.

    Dots round in screen space with one dyadic scale per texture axis and, with ``p.jitter``,
    random row phases (:func:`refnpr.formulas.threshold.stipple_threshold`).
    """
    s_u, s_v = thr.stipple_scales(fp.gx, fp.gy, p.period)  # eq. 5 per axis
    if not p.multiscale:
        s_u, s_v = np.floor(s_u), np.floor(s_v)
    kw = {"jitter": p.jitter, "seed": p.noise_seed, "tone_table": tone_table}
    if p.filter == "none":
        return SampledThresholds(thr.stipple_threshold(fp.uv, s_u, s_v, **kw)[:, None])
    k = int(round(p.samples**0.5))
    uvk = fp.offsets_uv(k)
    t = thr.stipple_threshold(uvk, s_u[:, None], s_v[:, None], **kw)  # eqs. 5-8 per axis
    return SampledThresholds(t)
