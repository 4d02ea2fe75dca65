"""Bump mapping for the ``threshold`` style: Veryovka Fig. 2, top centre.

The paper contrasts threshold textures with the traditional alternative, a texture used as a
bump map under the same single-threshold shading (Fig. 2, top centre: the wrinkled paper as
bumps). The normal is perturbed with the screen-space surface gradient of Mikkelsen (2010,
*Bump mapping unparametrized surfaces on the GPU*), which needs no tangent frame: with
``sigma_x = dP/dx``, ``sigma_y = dP/dy`` (G-buffer ``dposition_dx/dy``), ``R1 = sigma_y x n``,
``R2 = n x sigma_x`` and ``det = sigma_x . R1``,
``n' = normalize(|det| n - sign(det) (dh/dx R1 + dh/dy R2))`` with h the height in world units.
The height derivatives per pixel are central differences of the (box-filtered mip) height over
the pixel footprint, ``h(uv + duv/2) - h(uv - duv/2)``.
"""

from __future__ import annotations

import numpy as np

from refnpr.texture import MipPyramid, build_pyramid, load_texture, sample_trilinear

__all__ = ["BumpMap", "bump_normals"]


def bump_normals(
    n: np.ndarray, dpdx: np.ndarray, dpdy: np.ndarray, dhdx: np.ndarray, dhdy: np.ndarray
) -> np.ndarray:
    """Perturbed unit normals (Mikkelsen 2010, surface gradient), ``(M, 3)`` float64.

    Parameters
    ----------
    n : (M, 3) float64
        Unit shading normals.
    dpdx, dpdy : (M, 3) float64
        Screen derivatives of the world position per pixel.
    dhdx, dhdy : (M,) float64
        Screen derivatives of the height (world units) per pixel.
    """
    r1 = np.cross(dpdy, n)
    r2 = np.cross(n, dpdx)
    det = np.sum(dpdx * r1, axis=-1)
    grad = np.sign(det)[:, None] * (dhdx[:, None] * r1 + dhdy[:, None] * r2)
    out = np.abs(det)[:, None] * n - grad
    length = np.linalg.norm(out, axis=-1, keepdims=True)
    return np.divide(out, length, out=n.copy(), where=length > 0)


class BumpMap:
    """A height texture (built-in name or image path) as a box-filtered mip pyramid.

    Parameters
    ----------
    texture : str
        The ``bump`` parameter.
    height : float
        World units per unit of texture value (the ``bump_height`` parameter).
    """

    def __init__(self, texture: str, height: float) -> None:
        self.pyramid: MipPyramid = build_pyramid(load_texture(texture, param="bump"))
        self.height = float(height)

    def _h(self, uv: np.ndarray, lod: np.ndarray) -> np.ndarray:
        s = sample_trilinear(self.pyramid, uv, lod, dtype=np.float64)
        return self.height * s.reshape(uv.shape[0])

    def normals(self, n, uv, gx, gy, dpdx, dpdy) -> np.ndarray:
        """Bumped normals at M samples: ``n``, ``dpdx``, ``dpdy`` (M, 3); ``uv``, ``gx``, ``gy``
        (M, 2) texture coordinates and their per-pixel derivatives (already uv-scaled)."""
        texels = np.asarray(self.pyramid.size, dtype=np.float64)  # (cols, rows)
        tx, ty = gx * texels, gy * texels
        rho = np.maximum(np.hypot(tx[:, 0], tx[:, 1]), np.hypot(ty[:, 0], ty[:, 1]))
        lod = np.log2(np.maximum(rho, 1e-12))  # GL LOD of the pixel footprint
        dhdx = self._h(uv + 0.5 * gx, lod) - self._h(uv - 0.5 * gx, lod)
        dhdy = self._h(uv + 0.5 * gy, lod) - self._h(uv - 0.5 * gy, lod)
        return bump_normals(n, dpdx, dpdy, dhdx, dhdy)
