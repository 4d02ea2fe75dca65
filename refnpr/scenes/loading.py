"""User meshes through trimesh: OBJ, PLY, STL, OFF, GLB/glTF (and whatever else trimesh reads)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..raster import Mesh
from .uv_projection import UV_PROJECTIONS, project_uv

__all__ = ["load_mesh", "from_trimesh"]


def from_trimesh(tm, *, name: str = "mesh") -> Mesh:
    """Convert a ``trimesh.Trimesh`` to a :class:`~refnpr.raster.Mesh`.

    Positions and faces are taken as they are; normals are trimesh's ``vertex_normals`` (the
    file's normals when it has them, else area-weighted face normals); uv are the texture
    coordinates of a ``TextureVisuals`` when present (one row per vertex), else ``None``.
    """
    positions = np.asarray(tm.vertices, dtype=np.float64)
    faces = np.asarray(tm.faces, dtype=np.int64)
    if faces.ndim != 2 or faces.shape[0] == 0:
        raise ValueError(f"{name}: the geometry has no triangles (a point cloud or a path?)")
    uv = getattr(getattr(tm, "visual", None), "uv", None)
    if uv is not None:
        uv = np.asarray(uv, dtype=np.float64)
        if uv.shape != (positions.shape[0], 2):
            uv = None  # per-corner or malformed uv: treat as missing (see require_uv)
    normals = np.asarray(tm.vertex_normals, dtype=np.float64)
    return Mesh(positions, faces, normals, uv, name=name)


def load_mesh(path: str | Path, *, uv_projection: str | None = None) -> Mesh | list[Mesh]:
    """Read a mesh file with trimesh.

    Parameters
    ----------
    path : str or Path
        OBJ, PLY, STL, OFF, GLB/glTF, ... (anything ``trimesh.load`` reads). trimesh merges
        vertices that agree in position, uv and normal, keeping uv seams.
    uv_projection : {"planar", "box", "spherical", "cylindrical"}, optional
        Compute texture coordinates by :func:`~refnpr.scenes.project_uv` (replacing the file's).
        Without it a mesh may have ``uv=None``; styles that need uv then fail with the message of
        :func:`~refnpr.scenes.require_uv`.

    Returns
    -------
    Mesh or list of Mesh
        One Mesh for a single geometry; a list for a multi-geometry scene (glTF), each with its
        node transform applied, in the file's order. Names are the file stem (or the geometry
        names of a scene).

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        If the file cannot be read as triangles, or ``uv_projection`` is unknown.
    """
    import trimesh  # deferred: trimesh pulls in a lot at import time

    path = Path(path)
    if uv_projection is not None and uv_projection not in UV_PROJECTIONS:
        raise ValueError(
            f"uv_projection: unknown projection {uv_projection!r}; expected one of {UV_PROJECTIONS}"
        )
    if not path.is_file():
        raise FileNotFoundError(f"path: mesh file {str(path)!r} does not exist")
    try:
        loaded = trimesh.load(path, process=True)
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise ValueError(f"path: trimesh could not read {str(path)!r}: {exc}") from exc
    if isinstance(loaded, trimesh.Scene):
        geometries = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        names = [
            str(g.metadata.get("name") or f"{path.stem}[{i}]") for i, g in enumerate(geometries)
        ]
    else:
        geometries, names = [loaded], [path.stem]
    if not geometries or not all(isinstance(g, trimesh.Trimesh) for g in geometries):
        raise ValueError(f"path: {str(path)!r} contains no triangle mesh")
    meshes = [from_trimesh(g, name=n) for g, n in zip(geometries, names, strict=True)]
    if uv_projection is not None:
        meshes = [project_uv(m, uv_projection) for m in meshes]
    return meshes[0] if len(meshes) == 1 else meshes
