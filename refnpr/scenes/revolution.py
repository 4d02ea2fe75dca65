"""Surfaces of revolution about the +y axis, and the vase built from them.

:func:`revolve` sweeps a polyline profile in the (r, y) half plane once around the y axis:
``theta = 2 pi u`` counter-clockwise seen from +y, ``x = r cos(theta)``, ``z = -r sin(theta)``.
The seam column (u = 1) copies the u = 0 column bitwise; profile points with r = 0 become poles
(one vertex per triangle, u centred).
"""

from __future__ import annotations

import numpy as np

from ..raster import Mesh
from ._params import check_grid, check_int, positives
from ._topology import compact, concat, drop_degenerate, grid_faces, pole_u, unit

__all__ = ["revolve", "vase", "vase_profile"]

Arrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def revolve(
    r: np.ndarray,
    y: np.ndarray,
    normal_r: np.ndarray,
    normal_y: np.ndarray,
    v: np.ndarray,
    n_u: int,
) -> Arrays:
    """Sweep a profile around the y axis.

    Parameters
    ----------
    r, y : (K,) float64
        Profile points (radius >= 0, height). The outward side is to the right of the direction
        of travel in the (r, y) plane: travel upward for an outer wall, downward for an inner one.
    normal_r, normal_y : (K,) float64
        Profile normal (unit) at each point.
    v : (K,) float64
        Texture coordinate v of each profile point.
    n_u : int
        Segments around the axis.

    Returns
    -------
    positions : (V, 3) float64
    faces : (F, 3) int64
        Counter-clockwise seen from the normal side; no degenerate triangles.
    normals : (V, 3) float64
    uv : (V, 2) float64
        ``u = j / n_u`` in [0, 1]; pole vertices get the centre of their triangle's u span.
    """
    k = r.shape[0]
    j = np.arange(n_u + 1)
    theta = 2.0 * np.pi * j / n_u
    c, s = np.cos(theta), np.sin(theta)
    c[-1], s[-1] = c[0], s[0]  # the seam column repeats the first one bitwise
    x = r[:, None] * c[None, :] + 0.0  # + 0.0 turns -0.0 into +0.0
    z = -(r[:, None] * s[None, :]) + 0.0
    yy = np.broadcast_to(y[:, None], x.shape)
    positions = np.stack([x, yy, z], axis=-1).reshape(-1, 3)
    nx = normal_r[:, None] * c[None, :]
    nz = -(normal_r[:, None] * s[None, :])
    ny = np.broadcast_to(normal_y[:, None], nx.shape)
    normals = np.stack([nx, ny, nz], axis=-1).reshape(-1, 3)
    uu = np.broadcast_to((j / n_u)[None, :], x.shape)
    vv = np.broadcast_to(v[:, None], x.shape)
    uv = np.stack([uu, vv], axis=-1).reshape(-1, 2).copy()
    faces = drop_degenerate(positions, grid_faces(k - 1, n_u))
    # poles: each pole vertex is now used by exactly one triangle; centre its u there
    pole = np.repeat(r == 0.0, n_u + 1)
    fi, ci = np.nonzero(pole[faces])
    if fi.size:
        uv[faces[fi, ci], 0] = pole_u(uv[:, 0], faces, pole[faces])[fi]
    keep, faces = compact(positions.shape[0], faces)
    return positions[keep], faces, normals[keep], uv[keep]


def vase_profile(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Default vase outline: radius and its derivative at height fraction ``s`` in [0, 1].

    ``f(s) = 0.5 + 0.22 sin(pi (1.8 s - 0.15)) + 0.1 s^8`` (a belly low down, a neck, a flared lip).
    """
    f = 0.5 + 0.22 * np.sin(np.pi * (1.8 * s - 0.15)) + 0.1 * s**8
    df = 0.22 * np.pi * 1.8 * np.cos(np.pi * (1.8 * s - 0.15)) + 0.8 * s**7
    return f, df


def vase(
    height: float = 2.0, radius: float = 1.0, thickness: float = 0.04, n_u: int = 64, n_v: int = 48
) -> Mesh:
    """A vase with walls of finite thickness: a closed (watertight) surface of revolution.

    One profile runs from the centre of the bottom (y = 0) out to the foot, up the outer wall
    (radius ``radius * f(y / height)``, :func:`vase_profile`), across the flat rim at ``y =
    height``, down the inner wall (``thickness`` further in) and across the inner floor at ``y =
    thickness`` back to the axis. Creases (foot, rim edges, inner floor) have duplicated
    vertices with bitwise-equal positions and different normals.

    Parameters
    ----------
    height, radius : float
        Overall height and radius scale (> 0).
    thickness : float
        Wall and floor thickness, ``0 < thickness < min outer radius`` and ``< height``.
    n_u, n_v : int
        Segments around the axis (>= 3) and along each wall (>= 1).

    Returns
    -------
    Mesh
        uv: u = angle / 2 pi in [0, 1]; v = arc length along the whole profile normalized to
        [0, 1] (outer wall in the lower middle, inner wall in the upper middle).
    """
    height, radius, thickness = positives(height=height, radius=radius, thickness=thickness)
    n_u, n_v = check_int("n_u", n_u, minimum=3), check_int("n_v", n_v, minimum=1)
    check_grid((n_u + 1) * (2 * n_v + 8), {"n_u": n_u, "n_v": n_v})  # two walls, three rims
    if thickness >= height:
        raise ValueError(f"thickness: must be smaller than height ({height}), got {thickness}")
    s_out = np.linspace(0.0, 1.0, n_v + 1)
    f, df = vase_profile(s_out)
    r_out = radius * f
    if thickness >= r_out.min():
        raise ValueError(
            f"thickness: must be smaller than the narrowest outer radius ({r_out.min():.4g}), "
            f"got {thickness}; use a thinner wall or a larger radius"
        )
    n_out = unit(np.stack([np.full_like(s_out, height), -radius * df], axis=1))  # (dy, -dr)
    s_in = np.linspace(1.0, thickness / height, n_v + 1)
    f_in, df_in = vase_profile(s_in)
    r_in = radius * f_in - thickness
    n_in = -unit(np.stack([np.full_like(s_in, height), -radius * df_in], axis=1))
    y_out, y_in = height * s_out, height * s_in
    y_in[0] = y_out[-1]  # the rim is flat: both top rings at exactly y = height
    r_in[0] = r_out[-1] - thickness  # the rim's inner ring, bitwise the inner wall's first
    zero, one = np.zeros(2), np.ones(2)
    pieces = [  # (r, y, normal_r, normal_y)
        (np.array([0.0, r_out[0]]), zero, zero, -one),  # bottom
        (r_out, y_out, n_out[:, 0], n_out[:, 1]),  # outer wall
        (np.array([r_out[-1], r_in[0]]), np.full(2, y_out[-1]), zero, one),  # rim
        (r_in, y_in, n_in[:, 0], n_in[:, 1]),  # inner wall
        (np.array([r_in[-1], 0.0]), np.full(2, y_in[-1]), zero, one),  # inner floor
    ]
    # v: normalized arc length along the whole profile
    lengths = [np.hypot(np.diff(p[0]), np.diff(p[1])) for p in pieces]
    total = sum(float(seg.sum()) for seg in lengths)
    parts, start = [], 0.0
    for (r, y, nr, ny), seg in zip(pieces, lengths, strict=True):
        v = (start + np.concatenate([[0.0], np.cumsum(seg)])) / total
        start += float(seg.sum())
        parts.append(revolve(r, y, nr, ny, np.minimum(v, 1.0), n_u))
    positions, faces, normals, uv = concat(parts)
    return Mesh(positions, faces, normals, uv, name="vase")
