"""Per-vertex geometry of a scene for the X-Toon style: concatenated vertices and their
perspective-correct interpolation from the G-buffer's ``tri_id`` and ``bary`` (the barycentrics
of the unclipped triangle, so ``sum_k bary_k f[face_k]`` is the rasterizer's own interpolation
of a vertex attribute: what a vertex shader output becomes at a fragment).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.raster import Camera

__all__ = ["VertexGeometry", "view_axis_depth"]


def view_axis_depth(points: np.ndarray, camera: Camera) -> np.ndarray:
    """(N,) distance along the view axis (the G-buffer ``depth``: w_clip) of ``points (N, 3)``."""
    v = camera.view_matrix()
    return -(np.asarray(points, dtype=np.float64) @ v[2, :3] + v[2, 3])


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
