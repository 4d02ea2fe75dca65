"""User meshes through trimesh: OBJ, PLY, STL, OFF, GLB/glTF.

Before trimesh reads a file, :func:`load_mesh` checks it against its own format (a raw parse of
OBJ, PLY, STL and OFF, the GLB header), because trimesh silently drops non-finite vertices with
their faces, reads a truncated ASCII PLY as a partial mesh and reports a truncated binary STL with
an unrelated message. Every error names the file as the caller gave it. The file, and every
file it refers to (an OBJ's materials, a glTF's buffers), is read only if it is a regular file
of at most :data:`MAX_MESH_FILE_BYTES` (a FIFO would block, a device such as ``/dev/zero``
never end).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._reading import inside, read_regular
from ..raster import Mesh
from ._mesh_files import CHECKS, FIX, BadMeshFile, check_geometry
from .uv_projection import UV_PROJECTIONS, project_uv

__all__ = ["load_mesh", "from_trimesh", "MESH_EXTENSIONS", "MAX_MESH_FILE_BYTES"]

#: File extensions :func:`load_mesh` reads (case-insensitive).
MESH_EXTENSIONS = ("obj", "ply", "stl", "off", "glb", "gltf")
#: The largest mesh file read (bytes), and the largest file it refers to.
MAX_MESH_FILE_BYTES = 1 << 31


def from_trimesh(tm, *, name: str = "mesh") -> Mesh:
    """Convert a ``trimesh.Trimesh`` to a :class:`~refnpr.raster.Mesh`.

    Positions and faces are taken as they are; normals are trimesh's ``vertex_normals`` (the
    file's normals when it has them, else area-weighted face normals); uv are the texture
    coordinates of a ``TextureVisuals`` when present (one row per vertex), else ``None``.

    Raises
    ------
    ValueError
        If the geometry has no triangles, or the arrays fail :class:`~refnpr.raster.Mesh`'s checks.
    """
    positions = np.asarray(tm.vertices, dtype=np.float64)
    faces = np.asarray(tm.faces, dtype=np.int64)
    if faces.ndim != 2 or faces.shape[0] == 0:
        raise ValueError(
            f"faces: mesh {name!r} has no triangles (a point cloud or a path?); "
            "give a surface with at least one face"
        )
    uv = getattr(getattr(tm, "visual", None), "uv", None)
    if uv is not None:
        uv = np.asarray(uv, dtype=np.float64)
        if uv.shape != (positions.shape[0], 2) or not np.all(np.isfinite(uv)):
            uv = None  # per-corner, malformed or non-finite uv: treat as missing (see require_uv)
    normals = np.asarray(tm.vertex_normals, dtype=np.float64)
    if normals.shape != positions.shape or not np.all(np.isfinite(normals)):
        normals = None
    return Mesh(positions, faces, normals, uv, name=name)


def load_mesh(path: str | os.PathLike, *, uv_projection: str | None = None) -> Mesh | list[Mesh]:
    """Read a mesh file with trimesh, after checking it.

    Parameters
    ----------
    path : str or PathLike
        An OBJ, PLY (ASCII or binary), STL (ASCII or binary), OFF, GLB or glTF file (see
        :data:`MESH_EXTENSIONS`). trimesh merges vertices that agree in position, uv and normal,
        keeping uv seams.
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
        If ``path`` is a directory, not a regular file (a FIFO, a device), larger than
        :data:`MAX_MESH_FILE_BYTES` or has an unsupported extension; if the file is truncated or
        corrupt, holds non-finite vertices, faces that reference missing vertices or faces of
        fewer than 3 vertices, no triangles (or only zero-area ones), or coordinates beyond
        :data:`~refnpr.raster.mesh.MAX_COORDINATE`; or if ``uv_projection`` is unknown. The
        message names ``path`` as given.
    """
    given = os.fsdecode(path) if isinstance(path, (str, bytes, os.PathLike)) else path
    if not isinstance(given, str):
        raise TypeError(f"path: expected a file path (str or Path), got {type(path).__name__}")
    label = repr(given)
    if uv_projection is not None and uv_projection not in UV_PROJECTIONS:
        raise ValueError(
            f"uv_projection: unknown projection {uv_projection!r}; expected one of {UV_PROJECTIONS}"
        )
    p = Path(given)
    if not p.exists():
        raise FileNotFoundError(f"path: mesh file {label} does not exist")
    if p.is_dir():
        raise ValueError(
            f"path: {label} is a directory; expected a mesh file "
            f"({', '.join('.' + e for e in MESH_EXTENSIONS)})"
        )
    ext = p.suffix.lower().lstrip(".")
    if ext not in MESH_EXTENSIONS:
        raise ValueError(
            f"path: {label} has "
            + (f"the unsupported extension {p.suffix!r}" if ext else "no file extension")
            + f"; supported mesh formats: {', '.join('.' + e for e in MESH_EXTENSIONS)}"
        )
    what = f"path: mesh file {label}"
    try:
        data = read_regular(p.resolve(), what=what, max_bytes=MAX_MESH_FILE_BYTES)
    except (OSError, RuntimeError) as exc:  # resolve(): a symbolic link loop
        raise ValueError(f"{what}: cannot read it ({exc})") from None
    if not data.strip():
        raise ValueError(f"{what} is empty (0 bytes of geometry); {FIX}")
    check = CHECKS.get(ext)
    try:
        parsed = check(data) if check is not None else None
    except BadMeshFile as exc:
        raise ValueError(f"{what}: {exc}; {FIX}") from None
    del data

    import trimesh  # deferred: trimesh pulls in a lot at import time

    try:
        if parsed is not None:  # OFF: trimesh reads it line by line; the check read it whole
            loaded = trimesh.Trimesh(**parsed, process=False)
        else:
            loaded = trimesh.load(p, file_type=ext, process=False, resolver=_resolver(p))
    except Exception as exc:  # noqa: BLE001 -- trimesh raises many types for unreadable files
        raise ValueError(
            f"path: trimesh could not read {label} as {ext.upper()}: {type(exc).__name__}: "
            f"{' '.join(str(exc).split())[:200]}; {FIX}"
        ) from exc
    if isinstance(loaded, trimesh.Scene):
        try:
            dumped = loaded.dump()
        except Exception as exc:  # noqa: BLE001
            raise ValueError(f"{what}: its scene graph cannot be resolved ({exc}); {FIX}") from exc
        geometries = [g for g in dumped if isinstance(g, trimesh.Trimesh)]
        names = [str(g.metadata.get("name") or f"{p.stem}[{i}]") for i, g in enumerate(geometries)]
    else:
        geometries, names = [loaded], [p.stem]
    if not geometries or not all(isinstance(g, trimesh.Trimesh) for g in geometries):
        raise ValueError(f"path: {label} contains no triangle mesh (a point cloud or a path?)")
    meshes = []
    for g, n in zip(geometries, names, strict=True):
        try:
            check_geometry(g, f"geometry {n!r}" if len(geometries) > 1 else "the geometry")
            g.process()  # what trimesh.load(process=True) does: merge duplicate vertices
            meshes.append(from_trimesh(g, name=n))
        except BadMeshFile as exc:
            raise ValueError(f"{what}: {exc}; {FIX}") from None
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{what}: {exc}") from exc
    if uv_projection is not None:
        meshes = [project_uv(m, uv_projection) for m in meshes]
    return meshes[0] if len(meshes) == 1 else meshes


def _resolver(path: Path):
    """trimesh's resolver of the files that mesh file ``path`` refers to (inside its
    directory, as trimesh's own), reading each as :func:`load_mesh` reads ``path``."""
    from trimesh.resolvers import FilePathResolver  # deferred, as trimesh in load_mesh

    class RegularFiles(FilePathResolver):
        def get(self, name: str) -> bytes:
            root = Path(self.parent).resolve()
            what = f"{name!r} (a file that {self.file_name!r} refers to)"
            where = f"the directory of {self.file_name!r}"
            for candidate in (name.strip(), name.strip().lstrip("/"), os.path.split(name)[-1]):
                try:
                    full = inside(root, candidate, what=what, root_name=where)
                except ValueError:
                    continue
                if full.exists():
                    return read_regular(full, what=what, max_bytes=MAX_MESH_FILE_BYTES)
            inside(root, name.strip(), what=what, root_name=where)  # a name that leaves it
            raise FileNotFoundError(name)

    return RegularFiles(str(path))
