"""Flat pieces: a tiled ground plane and a room corner (floor and two walls)."""

from __future__ import annotations

import numpy as np

from ..raster import Mesh
from ._params import check_grid, check_int, positives
from ._topology import concat, grid_faces

__all__ = ["plane", "room"]


def _lerp_weights(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``s = (n - k) / n`` and ``t = k / n``, k = 0..n: exact at the ends and reversal-symmetric,
    so ``s p0 + t p1`` gives bitwise the same points whichever end an edge starts from."""
    k = np.arange(n + 1, dtype=np.float64)
    return (n - k) / n, k / n


def _quad_grid(
    corners: np.ndarray, n_u: int, n_v: int, tile: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A flat ``n_u x n_v`` grid on the rectangle ``corners = (p00, p10, p01, p11)``.

    Columns run from p00 to p10 (u), rows from p00 to p01 (v). Faces are counter-clockwise seen
    from ``(p10 - p00) x (p01 - p00)``; uv = (distance along u, distance along v) / tile. Edge
    points are bitwise equal to those of any other grid sharing that edge and segment count.
    """
    p00, p10, p01, p11 = (np.asarray(c, dtype=np.float64) for c in corners)
    su, tu = _lerp_weights(n_u)
    sv, tv = _lerp_weights(n_v)
    row0 = su[:, None] * p00 + tu[:, None] * p10  # (n_u + 1, 3)
    row1 = su[:, None] * p01 + tu[:, None] * p11
    positions = sv[:, None, None] * row0[None] + tv[:, None, None] * row1[None]
    du, dv = p10 - p00, p01 - p00
    normal = np.cross(du, dv)
    normal /= np.linalg.norm(normal)
    vv, uu = np.meshgrid(tv * np.linalg.norm(dv), tu * np.linalg.norm(du), indexing="ij")
    uv = np.stack([uu, vv], axis=-1) / tile
    n = (n_u + 1) * (n_v + 1)
    faces = grid_faces(n_v, n_u)  # normal along d/dcol x d/drow = du x dv
    return positions.reshape(-1, 3), faces, np.tile(normal, (n, 1)), uv.reshape(-1, 2)


def plane(width: float = 10.0, depth: float = 10.0, tile: float = 1.0, segments: int = 1) -> Mesh:
    """A horizontal rectangle at y = 0 centred on the origin, facing +y.

    Parameters
    ----------
    width, depth : float
        Extent along x and along z (> 0).
    tile : float
        World size of one texture repeat (> 0): uv runs over [0, width / tile] x [0, depth / tile].
    segments : int
        Grid segments along each side (>= 1).

    Returns
    -------
    Mesh
        u grows with x, v grows towards -z (away from a camera on +z). Not closed.
    """
    width, depth, tile = positives(width=width, depth=depth, tile=tile)
    segments = check_int("segments", segments, minimum=1)
    check_grid((segments + 1) ** 2, {"segments": segments})
    x0, x1, z0, z1 = -width / 2.0, width / 2.0, -depth / 2.0, depth / 2.0
    corners = np.array([[x0, 0.0, z1], [x1, 0.0, z1], [x0, 0.0, z0], [x1, 0.0, z0]])
    positions, faces, normals, uv = _quad_grid(corners, segments, segments, tile)
    return Mesh(positions, faces, normals, uv, name="plane")


def room(
    width: float = 8.0,
    depth: float = 8.0,
    height: float = 4.0,
    tile: float = 1.0,
    segments: int = 4,
) -> Mesh:
    """A room corner: floor (y = 0), back wall (z = -depth/2) and left wall (x = -width/2).

    The three rectangles face into the room (+y, +z, +x) and share their corner edges with
    bitwise-equal positions (duplicated vertices, different normals). Not closed.

    Parameters
    ----------
    width, depth, height : float
        Extent along x, z and y (> 0); the floor is centred on the origin.
    tile : float
        World size of one texture repeat (> 0); uv = distance / tile, so textures tile.
    segments : int
        Grid segments along each side of each rectangle (>= 1).

    Returns
    -------
    Mesh
        uv on the floor: u with x, v towards -z; on the back wall: u with x, v up; on the left
        wall: u towards -z (the back corner), v up. Ranges [0, extent / tile].
    """
    width, depth, height, tile = positives(width=width, depth=depth, height=height, tile=tile)
    n = check_int("segments", segments, minimum=1)
    check_grid((n + 1) ** 2, {"segments": n}, copies=3)  # the floor and two walls
    x0, x1, z0, z1 = -width / 2.0, width / 2.0, -depth / 2.0, depth / 2.0
    # floor corners front-left, front-right, back-left, back-right, and the tops of the walls'
    # vertical edges; rectangles that meet share these exact values
    fl, fr, bl, br = [x0, 0.0, z1], [x1, 0.0, z1], [x0, 0.0, z0], [x1, 0.0, z0]
    fl_top, bl_top, br_top = [x0, height, z1], [x0, height, z0], [x1, height, z0]
    floor = _quad_grid([fl, fr, bl, br], n, n, tile)
    back = _quad_grid([bl, br, bl_top, br_top], n, n, tile)
    left = _quad_grid([fl, bl, fl_top, bl_top], n, n, tile)
    positions, faces, normals, uv = concat([floor, back, left])
    return Mesh(positions, faces, normals, uv, name="room")
