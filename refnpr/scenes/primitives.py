"""Closed primitives: UV sphere, icosphere and torus (y is the polar axis). Seams and poles use
duplicated vertices with bitwise-equal positions, so merging vertices by exact position gives a
watertight, consistently oriented manifold; normals point outward, faces are counter-clockwise
seen from outside.
"""

from __future__ import annotations

import numpy as np

from ..raster import Mesh
from ._params import check_grid, check_int, check_real, positives
from ._topology import split_u_seam
from .revolution import revolve

__all__ = ["uv_sphere", "icosphere", "torus", "spherical_uv"]


def uv_sphere(radius: float = 1.0, n_u: int = 64, n_v: int = 32) -> Mesh:
    """Latitude-longitude sphere about the y axis.

    Parameters
    ----------
    radius : float
        Sphere radius (> 0).
    n_u, n_v : int
        Segments in longitude (>= 3) and latitude (>= 2).

    Returns
    -------
    Mesh
        ``2 * n_u * (n_v - 1)`` triangles. uv: u = longitude / 2 pi in [0, 1] (counter-clockwise
        seen from +y, starting at +x), v = latitude / pi + 1/2 in [0, 1] (0 at the south pole).
    """
    radius = check_real("radius", radius, positive=True)
    n_u, n_v = check_int("n_u", n_u, minimum=3), check_int("n_v", n_v, minimum=2)
    check_grid((n_u + 1) * (n_v + 1), {"n_u": n_u, "n_v": n_v})
    k = np.arange(n_v + 1)
    lat = np.pi * k / n_v - np.pi / 2.0
    nr, ny = np.cos(lat), np.sin(lat)
    nr[0] = nr[-1] = 0.0  # exact poles
    ny[0], ny[-1] = -1.0, 1.0
    positions, faces, normals, uv = revolve(radius * nr, radius * ny, nr, ny, k / n_v, n_u)
    return Mesh(positions, faces, normals, uv, name="uv_sphere")


def _icosahedron() -> tuple[np.ndarray, np.ndarray]:
    """Unit icosahedron with vertices at the poles (0, +-1, 0); faces counter-clockwise outside."""
    ring_y = 1.0 / np.sqrt(5.0)
    ring_r = 2.0 / np.sqrt(5.0)
    a_up = 2.0 * np.pi * np.arange(5) / 5.0
    a_dn = a_up + np.pi / 5.0
    up = np.stack([ring_r * np.cos(a_up), np.full(5, ring_y), -ring_r * np.sin(a_up)], axis=1)
    dn = np.stack([ring_r * np.cos(a_dn), np.full(5, -ring_y), -ring_r * np.sin(a_dn)], axis=1)
    verts = np.concatenate([[[0.0, 1.0, 0.0]], up, dn, [[0.0, -1.0, 0.0]]]) + 0.0
    faces = []
    for i in range(5):
        u0, u1 = 1 + i, 1 + (i + 1) % 5
        d0, d1 = 6 + i, 6 + (i + 1) % 5
        faces += [(0, u0, u1), (u0, d0, u1), (u1, d0, d1), (d0, 11, d1)]
    f = np.array(faces, dtype=np.int64)
    tri = verts[f]
    outward = np.einsum(
        "ij,ij->i", np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), tri.sum(1)
    )
    f[outward < 0] = f[outward < 0][:, ::-1]
    return verts, f


def _subdivide(verts: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One 1-to-4 split; each edge midpoint is computed once and projected to the unit sphere."""
    n = verts.shape[0]
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    lo, hi = edges.min(axis=1), edges.max(axis=1)
    keys, inverse = np.unique(lo * n + hi, return_inverse=True)
    a, b = keys // n, keys % n
    mid = verts[a] + verts[b]
    mid /= np.linalg.norm(mid, axis=1, keepdims=True)
    m = (n + inverse.reshape(-1, 3)).astype(np.int64)  # midpoints of edges (01, 12, 20)
    (v0, v1, v2), (m01, m12, m20) = faces.T, m.T
    corners = [v0, m01, m20, m01, v1, m12, m20, m12, v2, m01, m12, m20]  # 4 triangles per face
    new = np.stack(corners, axis=1).reshape(-1, 3)
    return np.concatenate([verts, mid]), new


def spherical_uv(unit_dirs: np.ndarray) -> np.ndarray:
    """Longitude/latitude texture coordinates of unit directions (y is the polar axis).

    Parameters
    ----------
    unit_dirs : (N, 3) float64

    Returns
    -------
    uv : (N, 2) float64
        u = atan2(-z, x) / 2 pi wrapped to [0, 1]; v = latitude / pi + 1/2 in [0, 1].
    """
    x, y, z = unit_dirs[:, 0], unit_dirs[:, 1], unit_dirs[:, 2]
    u = np.arctan2(-z, x) / (2.0 * np.pi)
    u = np.where(u < 0.0, u + 1.0, u) + 0.0  # + 0.0 turns -0.0 into +0.0
    v = np.arctan2(y, np.hypot(x, z)) / np.pi + 0.5
    return np.stack([u, v], axis=1)


def icosphere(subdivisions: int = 3, radius: float = 1.0) -> Mesh:
    """Geodesic sphere: an icosahedron (a vertex at each pole of y) split 1-to-4 ``subdivisions``
    times, new vertices projected to the sphere.

    Parameters
    ----------
    subdivisions : int
        0..9; the mesh has ``20 * 4**subdivisions`` triangles (6 -> 81,920; 8 -> 1,310,720).
    radius : float
        Sphere radius (> 0).

    Returns
    -------
    Mesh
        Normals = unit positions. uv as :func:`spherical_uv`; triangles that straddle the u seam
        use duplicated vertices with u + 1, so u lies in [0, 1 + w) with w below one triangle's
        width in u (wrap-around sampling sees no jump). The poles are split per triangle with u at
        the triangle's centre. Vertices are numbered in order of first use by the faces (good
        locality for per-triangle vertex gathers).
    """
    subdivisions = check_int("subdivisions", subdivisions, minimum=0, maximum=9)
    radius = check_real("radius", radius, positive=True)
    verts, faces = _icosahedron()
    for _ in range(subdivisions):
        verts, faces = _subdivide(verts, faces)
    source, uv, faces = split_u_seam(spherical_uv(verts), faces, verts)
    unit_pos = verts[source]
    # Number vertices in order of first use by the faces: subdivision appends midpoints far from
    # their triangles' other corners, and renderers gather per-triangle vertex data by index.
    _, first_use = np.unique(faces.ravel(), return_index=True)
    order = np.argsort(first_use, kind="stable")
    renumber = np.empty_like(order)
    renumber[order] = np.arange(order.size)
    return Mesh(
        unit_pos[order] * radius, renumber[faces], unit_pos[order], uv[order], name="icosphere"
    )


def torus(R: float = 1.0, r: float = 0.35, n_u: int = 64, n_v: int = 32) -> Mesh:
    """Ring torus about the y axis (lying in the xz plane).

    Parameters
    ----------
    R : float
        Distance from the axis to the centre of the tube (> 0).
    r : float
        Tube radius, ``0 < r < R``.
    n_u, n_v : int
        Segments around the axis and around the tube (each >= 3).

    Returns
    -------
    Mesh
        ``2 * n_u * n_v`` triangles. uv: u = angle about y / 2 pi; v = angle around the tube
        / 2 pi, 0 on the outer equator, increasing upward; both in [0, 1].
    """
    R, r = positives(R=R, r=r)
    if r >= R:
        raise ValueError(f"r: the tube radius must be smaller than R ({R}), got {r}")
    n_u, n_v = check_int("n_u", n_u, minimum=3), check_int("n_v", n_v, minimum=3)
    check_grid((n_u + 1) * (n_v + 1), {"n_u": n_u, "n_v": n_v})
    k = np.arange(n_v + 1)
    phi = 2.0 * np.pi * k / n_v
    nr, ny = np.cos(phi), np.sin(phi)
    nr[-1], ny[-1] = nr[0], ny[0]  # the tube's seam row repeats the first one bitwise
    positions, faces, normals, uv = revolve(R + r * nr, r * ny, nr, ny, k / n_v, n_u)
    return Mesh(positions, faces, normals, uv, name="torus")
