"""Texture sampling at an explicit LOD (GL_REPEAT wrapping, GL texel-centre convention).

See :mod:`refnpr.texture.pyramid` for the texture-space convention (u along columns, v along
rows, texel centres at (i + 0.5) / size).
"""

from __future__ import annotations

import numpy as np

from refnpr._jit import readonly
from refnpr.device import sampling
from refnpr.formulas._face import elementwise

from . import _kernels as K
from .pyramid import MipPyramid

__all__ = ["sample_trilinear", "sample_level", "level_weights", "texture_lod"]


def _uv_and_shape(uv, name: str = "uv") -> tuple[np.ndarray, tuple[int, ...]]:
    a = np.asarray(uv)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"{name}: expected a float array, got dtype {a.dtype}")
    if a.ndim < 1 or a.shape[-1] != 2:
        raise ValueError(f"{name}: expected shape (..., 2), got {a.shape}")
    flat = readonly(np.ascontiguousarray(a.reshape(-1, 2), dtype=np.float64))
    if not np.all(np.isfinite(flat)):
        raise ValueError(f"{name}: contains NaN or inf; mask empty samples before sampling")
    return flat, a.shape[:-1]


def _check_pyramid(pyramid) -> None:
    if not isinstance(pyramid, MipPyramid):
        raise TypeError(
            f"pyramid: expected refnpr.texture.MipPyramid (build_pyramid / clahe_pyramid), "
            f"got {type(pyramid).__name__}"
        )


def _run(kernel, pyramid: MipPyramid, flat: np.ndarray, shape, per_sample, dtype) -> np.ndarray:
    """``kernel`` over the samples, reshaped to ``shape`` (+ (C,) for several channels)."""
    pyr = pyramid.packed()
    channels = pyr[0].shape[1]
    out = np.empty((flat.shape[0], channels), dtype=np.float64)
    kernel(pyr, flat, per_sample, out)
    return out.reshape(shape + ((channels,) if channels > 1 else ())).astype(dtype, copy=False)


def sample_trilinear(pyramid: MipPyramid, uv, lod, *, dtype=np.float32) -> np.ndarray:
    """Trilinear (GL_LINEAR_MIPMAP_LINEAR) samples of a pyramid.

    Parameters
    ----------
    pyramid : MipPyramid
    uv : (..., 2) float
        Texture coordinates (wrapped, GL_REPEAT).
    lod : (...) float
        Level of detail lambda (the rasterizer's ``lod`` channel), clamped to [0, L - 1].

    Returns
    -------
    (...) or (..., C) float32 (or ``dtype``)
    """
    _check_pyramid(pyramid)
    flat, shape = _uv_and_shape(uv)
    lam = np.asarray(lod, dtype=np.float64)
    if lam.shape != shape:
        raise ValueError(f"lod: expected shape {shape} (uv's leading shape), got {lam.shape}")
    if not np.all(np.isfinite(lam)):
        raise ValueError("lod: contains NaN or inf")
    lam = readonly(np.ascontiguousarray(lam.ravel()))
    return _run(K.sample_trilinear, pyramid, flat, shape, lam, dtype)


def sample_level(pyramid: MipPyramid, uv, level, *, dtype=np.float32) -> np.ndarray:
    """Bilinear samples of integer mip ``level`` (scalar or (...) int array, clamped to the
    pyramid): the per-level lookups Veryovka's two-level filtered thresholding weights."""
    _check_pyramid(pyramid)
    flat, shape = _uv_and_shape(uv)
    lv = np.asarray(level)
    if lv.dtype.kind not in "iu":
        raise TypeError(f"level: expected integer level indices, got dtype {lv.dtype}")
    lv = readonly(np.ascontiguousarray(np.broadcast_to(lv, shape).ravel(), dtype=np.int64))
    return _run(K.sample_level, pyramid, flat, shape, lv, dtype)


def level_weights(pyramid: MipPyramid, lod) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The two levels trilinear filtering blends and their weights, per sample:
    (k0, k1, w1), (...) int64, int64, float64, with lambda clamped to [0, L - 1], k0 = floor,
    k1 = min(k0 + 1, L - 1), w1 = frac (:func:`refnpr.device.sampling.level_weights`, the
    function the kernels run)."""
    _check_pyramid(pyramid)
    lam = np.asarray(lod, dtype=np.float64)
    if not np.all(np.isfinite(lam)):
        raise ValueError("lod: contains NaN or inf")
    kkw = elementwise(sampling.level_weights, np.float64, pyramid.n_levels, lam)
    return kkw[..., 0].astype(np.int64), kkw[..., 1].astype(np.int64), kkw[..., 2]


def texture_lod(pyramid: MipPyramid, dx, dy) -> np.ndarray:
    """The GL isotropic LOD lambda of per-sample uv derivatives in ``pyramid``'s texels
    (OpenGL 4.x sec. 8.14; :func:`refnpr.device.sampling.gl_lod`, the function the kernels
    run): log2(max(rho, 2^-64)), rho = max(|d(u,v)/dx|, |d(u,v)/dy|) in texels.

    Parameters
    ----------
    pyramid : MipPyramid
        Its base level's size gives the texel scale.
    dx, dy : (..., 2) float
        ``(du/dx, dv/dx)`` and ``(du/dy, dv/dy)`` per sample.

    Returns
    -------
    (...) float64
    """
    _check_pyramid(pyramid)
    gx, shape = _uv_and_shape(dx, "dx")
    gy, shape_y = _uv_and_shape(dy, "dy")
    if shape_y != shape:
        raise ValueError(f"dy: expected shape {shape + (2,)} (dx's shape), got {shape_y + (2,)}")
    cols, rows = pyramid.size
    lod = elementwise(
        sampling.gl_lod,
        np.float64,
        (gx[:, 0], gx[:, 1]),
        (gy[:, 0], gy[:, 1]),
        float(cols),
        float(rows),
    )
    return lod.reshape(shape)
