"""Mesh specifications: a name and parameters (or a file path) -> Mesh. Used by the scene loader."""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from pathlib import Path

from ..raster import Mesh
from .knot import torus_knot
from .loading import load_mesh
from .primitives import icosphere, torus, uv_sphere
from .revolution import vase
from .room import plane, room
from .teapot import teapot
from .terrain import terrain
from .uv_projection import UV_PROJECTIONS, project_uv

__all__ = ["MESH_BUILDERS", "mesh_from_spec"]

#: Built-in mesh builders by the name a spec uses (``mesh = "teapot"``).
MESH_BUILDERS: Mapping[str, Callable[..., Mesh]] = {
    b.__name__: b
    for b in (teapot, uv_sphere, icosphere, torus, torus_knot, vase, plane, room, terrain)
}


def mesh_from_spec(spec: Mapping, *, base_dir: str | Path | None = None) -> Mesh | list[Mesh]:
    """Build or load the mesh a spec describes.

    Parameters
    ----------
    spec : mapping
        Either ``{"mesh": <name in MESH_BUILDERS>, <builder parameter>: value, ...}`` or
        ``{"path": <mesh file>}``; both may add ``"uv_projection": "planar" | "box" |
        "spherical" | "cylindrical"`` (replacing the mesh's uv, see :func:`project_uv`).
    base_dir : str or Path, optional
        Directory that a relative ``path`` is resolved against (default: the working directory).

    Returns
    -------
    Mesh, or a list of Mesh for a multi-geometry file.

    Raises
    ------
    ValueError
        Naming the offending key: unknown mesh name, unknown parameter, ``mesh`` and ``path``
        both or neither given, or a builder's own parameter error.
    """
    if not isinstance(spec, Mapping):
        raise TypeError(f"spec: expected a mapping such as {{'mesh': 'teapot'}}, got {spec!r}")
    spec = dict(spec)
    projection = spec.pop("uv_projection", None)
    if projection is not None and projection not in UV_PROJECTIONS:
        raise ValueError(
            f"uv_projection: unknown projection {projection!r}; expected one of {UV_PROJECTIONS}"
        )
    has_mesh, has_path = "mesh" in spec, "path" in spec
    if has_mesh == has_path:
        raise ValueError(
            "mesh/path: give exactly one of `mesh = <built-in name>` "
            f"({', '.join(MESH_BUILDERS)}) or `path = <mesh file>`, got "
            + ("both" if has_mesh else "neither")
        )
    if has_path:
        path = spec.pop("path")
        if spec:
            raise ValueError(
                f"{sorted(spec)[0]}: unknown key for a mesh file; a `path` object accepts only "
                "`path` and `uv_projection`"
            )
        if not isinstance(path, (str, Path)):
            raise TypeError(f"path: expected a file path string, got {path!r}")
        full = Path(path) if base_dir is None else Path(base_dir) / path
        return load_mesh(full, uv_projection=projection)
    name = spec.pop("mesh")
    if not isinstance(name, str) or name not in MESH_BUILDERS:
        raise ValueError(
            f"mesh: unknown built-in mesh {name!r}; valid names: {', '.join(MESH_BUILDERS)} "
            "(or use `path = <mesh file>`)"
        )
    builder = MESH_BUILDERS[name]
    valid = list(inspect.signature(builder).parameters)
    for key in spec:
        if key not in valid:
            raise ValueError(
                f"{key}: unknown parameter of mesh {name!r}; valid parameters: "
                f"{', '.join(valid) or '(none)'}"
            )
    mesh = builder(**spec)
    return mesh if projection is None else project_uv(mesh, projection)
