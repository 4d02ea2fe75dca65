"""Texture coordinates for meshes that have none: planar, box, spherical, cylindrical projection.

Projections are opt-in (see :func:`require_uv` for the error a uv-less mesh raises). Where a
projection needs a uv seam (box faces, the wrap of an angle), vertices are duplicated with
bitwise-equal positions, so the mesh stays watertight for the rasterizer.
"""

from __future__ import annotations

import numpy as np

from ..raster import Mesh
from ._params import check_type
from ._topology import split_u_seam, unit
from .primitives import spherical_uv

__all__ = ["UV_PROJECTIONS", "project_uv", "require_uv"]

#: Accepted values of ``kind`` / ``uv_projection``.
UV_PROJECTIONS = ("planar", "box", "spherical", "cylindrical")

# rotations taking the named axis to +y (proper rotations, so angles keep their orientation)
_TO_Y = {
    "x": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    "y": np.eye(3),
    "z": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
}
# image axes (e_u, e_v) seen from outside along +-x, +-y, +-z: group = 2 * axis + (sign < 0)
_BOX = np.array(
    [
        [[0, 0, -1], [0, 1, 0]],  # +x
        [[0, 0, 1], [0, 1, 0]],  # -x
        [[1, 0, 0], [0, 0, -1]],  # +y
        [[1, 0, 0], [0, 0, 1]],  # -y
        [[1, 0, 0], [0, 1, 0]],  # +z
        [[-1, 0, 0], [0, 1, 0]],  # -z
    ],
    dtype=np.float64,
)


def require_uv(mesh: Mesh, *, needed_by: str = "this style") -> Mesh:
    """Return ``mesh`` if it has texture coordinates, else raise a ``ValueError`` naming the remedy."""
    check_type("mesh", mesh, Mesh, "a refnpr Mesh")
    if mesh.uv is None:
        raise ValueError(
            f"mesh {mesh.name!r} has no uv, which {needed_by} needs; "
            "pass uv_projection='planar'|'box'|'spherical'|'cylindrical' to load_mesh "
            '(or `uv_projection = "box"` in the scene file\'s [[object]]), '
            "or call refnpr.scenes.project_uv(mesh, kind)"
        )
    return mesh


def _normalize(values: np.ndarray, scale: float | None = None) -> np.ndarray:
    lo = values.min(axis=0)
    span = values.max(axis=0) - lo if scale is None else scale
    return np.divide(values - lo, span, out=np.zeros_like(values), where=np.asarray(span) > 0)


def _with(mesh: Mesh, source: np.ndarray, faces: np.ndarray, uv: np.ndarray) -> Mesh:
    normals = None if mesh.normals is None else mesh.normals[source]
    attributes = {k: v[source] for k, v in mesh.attributes.items()}
    return Mesh(mesh.positions[source], faces, normals, uv, attributes, mesh.name)


def project_uv(mesh: Mesh, kind: str, *, axis: str | None = None) -> Mesh:
    """Give ``mesh`` texture coordinates by projection (replacing any it has).

    Parameters
    ----------
    mesh : Mesh
    kind : {"planar", "box", "spherical", "cylindrical"}
        planar: orthographic along ``axis`` (default "z"), uv = the other two coordinates scaled
        together to [0, 1] (aspect kept). box: each triangle projects along the dominant axis of
        its normal (six images, seen from outside, one common scale); vertices on the cube's
        seams are duplicated. spherical: longitude/latitude about ``axis`` (default "y") through
        the bounding-box centre, u in [0, 1 + w) as in :func:`refnpr.scenes.icosphere`.
        cylindrical: u = angle about ``axis`` (default "y"), v = height along it in [0, 1].
    axis : {"x", "y", "z"}, optional
        Projection axis (not used by "box").

    Returns
    -------
    Mesh
        A copy with ``uv`` (N', 2) float64; positions, normals and attributes are carried to
        the duplicated vertices bitwise.
    """
    check_type("mesh", mesh, Mesh, "a refnpr Mesh")
    if kind not in UV_PROJECTIONS:
        raise ValueError(f"kind: unknown uv projection {kind!r}; expected one of {UV_PROJECTIONS}")
    if kind == "box":
        if axis is not None:
            raise ValueError(f"axis: the box projection uses all three axes, got axis={axis!r}")
    else:
        axis = {"planar": "z"}.get(kind, "y") if axis is None else axis
        if axis not in _TO_Y:
            raise ValueError(f"axis: expected 'x', 'y' or 'z', got {axis!r}")
    p = mesh.positions
    lo, hi = p.min(axis=0), p.max(axis=0)
    extent = float(np.max(hi - lo))
    if extent == 0.0:
        raise ValueError(f"mesh {mesh.name!r}: all vertices coincide; cannot project uv")
    if kind == "planar":
        rot = _TO_Y[axis].T  # columns: images of x, y, z; seen from +axis: u = x', v = -z'
        e_u, e_v = rot @ np.array([1.0, 0.0, 0.0]), rot @ np.array([0.0, 0.0, -1.0])
        q = np.stack([p @ e_u, p @ e_v], axis=1)
        span = float(np.max(q.max(axis=0) - q.min(axis=0)))
        return mesh.with_(uv=_normalize(q, span))
    if kind == "box":
        tri = p[mesh.faces]
        fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        dom = np.argmax(np.abs(fn), axis=1)
        group = 2 * dom + (fn[np.arange(fn.shape[0]), dom] < 0)
        keys, inverse = np.unique(mesh.faces * 6 + group[:, None], return_inverse=True)
        source, g = keys // 6, keys % 6
        e = _BOX[g]  # (K, 2, 3)
        q = np.einsum("kij,kj->ki", e, p[source])
        # a common origin per image direction keeps every image in [0, 1]
        origin = np.einsum("gij,j->gi", np.minimum(_BOX, 0.0), hi) + np.einsum(
            "gij,j->gi", np.maximum(_BOX, 0.0), lo
        )
        uv = (q - origin[g]) / extent
        faces = inverse.reshape(-1, 3).astype(np.int64)
        return _with(mesh, source, faces, uv)
    d = (p - 0.5 * (lo + hi)) @ _TO_Y[axis].T
    uv = spherical_uv(unit(d))
    if kind == "cylindrical":
        uv[:, 1] = _normalize(d[:, 1])
    source, uv, faces = split_u_seam(uv, mesh.faces, d)
    return _with(mesh, source, faces, uv)
