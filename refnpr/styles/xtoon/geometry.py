"""Per-vertex geometry of a scene for the X-Toon style: concatenated vertices, perspective-correct
interpolation from the G-buffer's ``tri_id`` and ``bary``, projections to pixels.

The rasterizer's ``bary`` channel holds the perspective-correct barycentrics of the original
(unclipped) triangle's three vertices, so ``sum_k bary_k f[face_k]`` is exactly the interpolation
it applies to a vertex attribute ``f`` (``interp_attr``): a per-vertex value computed here and
interpolated this way is what a vertex shader output becomes at a fragment.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.raster import Camera
from refnpr.raster.projection import project_points

__all__ = ["VertexGeometry", "project_pixels", "view_axis_depth"]


def view_axis_depth(points: np.ndarray, camera: Camera) -> np.ndarray:
    """(N,) distance along the view axis (the G-buffer ``depth``: w_clip) of ``points (N, 3)``."""
    v = camera.view_matrix()
    return -(np.asarray(points, dtype=np.float64) @ v[2, :3] + v[2, 3])


def project_pixels(
    points: np.ndarray, camera: Camera, width: int, height: int
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates ``(N, 2)`` (x right, y down, pixel centres at +0.5) and w_clip ``(N,)``
    of world ``points (N, 3)`` through ``camera`` for a ``width`` x ``height`` image, as the
    rasterizer projects vertices (``refnpr.raster.projection``).

    Points with w_clip <= 0 (behind the eye) get NaN coordinates.
    """
    vp = camera.view_projection(width, height)
    return project_points(np.asarray(points, dtype=np.float64).reshape(-1, 3), vp, width, height)


@dataclass(frozen=True, eq=False)
class VertexGeometry:
    """The world meshes of a scene concatenated in order (matching the G-buffer's ``tri_id``).

    Attributes
    ----------
    meshes : list of Mesh
    offsets : (n_meshes + 1,) int64, first vertex of each mesh
    faces : (M, 3) int64, global vertex indices
    positions : (N, 3) float64
    """

    meshes: list[Any]
    offsets: np.ndarray
    faces: np.ndarray
    positions: np.ndarray

    @classmethod
    def of(cls, meshes: list[Any]) -> VertexGeometry:
        counts = [m.n_vertices for m in meshes]
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets[:-1], strict=True)])
        positions = np.concatenate([m.positions for m in meshes])
        return cls(list(meshes), offsets, faces, positions)

    def normals(self) -> np.ndarray:
        """(N, 3) float64 vertex normals (as stored; need not be unit)."""
        missing = [m.name for m in self.meshes if m.normals is None]
        if missing:
            raise ValueError(
                f"detail_mode/shape: per-vertex shading needs vertex normals, but meshes "
                f"{missing} have none; give the meshes normals"
            )
        return np.concatenate([m.normals for m in self.meshes])

    def split(self, values: np.ndarray) -> list[np.ndarray]:
        """Per-mesh slices of a per-vertex array ``(N, ...)``."""
        return [values[a:b] for a, b in zip(self.offsets[:-1], self.offsets[1:], strict=True)]

    def interpolate(self, values: np.ndarray, tri: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """Perspective-correct interpolation of per-vertex ``values (N,) or (N, C)`` at samples
        with triangle ids ``tri (K,)`` and barycentrics ``bary (K, 3)``; float64 ``(K,)`` or
        ``(K, C)``."""
        idx = self.faces[tri]  # (K, 3)
        b = np.asarray(bary, dtype=np.float64)
        vals = np.asarray(values, dtype=np.float64)
        if vals.ndim == 1:
            return np.einsum("kj,kj->k", b, vals[idx])
        return np.einsum("kj,kjc->kc", b, vals[idx])
