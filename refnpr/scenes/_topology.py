"""Index-buffer helpers shared by the mesh builders (private).

Conventions: a *vertex grid* of ``(rows + 1) x (cols + 1)`` vertices is stored row-major; its
triangles are counter-clockwise seen from the side the normal ``d/dcol x d/drow`` points to.
Seams are made by duplicating vertices whose positions are bitwise copies, so the rasterizer
(watertight for identical positions) sees no cracks while uv may differ across the seam.
"""

from __future__ import annotations

import numpy as np

__all__ = ["grid_faces", "drop_degenerate", "compact", "concat", "pole_u", "split_u_seam", "unit"]


def unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (..., 3) scaled to unit length (zero rows stay zero)."""
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


def grid_faces(rows: int, cols: int, offset: int = 0) -> np.ndarray:
    """(2 rows cols, 3) int64 triangles of a ``(rows + 1) x (cols + 1)`` vertex grid: per quad
    ``(r,c), (r,c+1), (r+1,c+1)`` and ``(r,c), (r+1,c+1), (r+1,c)``, normal along d/dcol x d/drow."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = (r * (cols + 1) + c).ravel() + offset
    b = a + 1
    d = a + cols + 1
    e = d + 1
    tri1 = np.stack([a, b, e], axis=1)
    tri2 = np.stack([a, e, d], axis=1)
    return np.stack([tri1, tri2], axis=1).reshape(-1, 3).astype(np.int64)


def drop_degenerate(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``faces`` without triangles that have two corners at bitwise-equal positions
    (they arise where a grid row collapses to a point, e.g. at a pole)."""
    p = positions[faces]  # (M, 3, 3)
    same = (
        np.all(p[:, 0] == p[:, 1], axis=1)
        | np.all(p[:, 1] == p[:, 2], axis=1)
        | np.all(p[:, 2] == p[:, 0], axis=1)
    )
    return faces[~same]


def compact(n_vertices: int, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Remove unused vertices: ``(keep, faces)``, the old index of each kept vertex (index the
    per-vertex arrays with it) and the faces renumbered to them."""
    used = np.zeros(n_vertices, dtype=bool)
    used[faces.ravel()] = True
    keep = np.flatnonzero(used)
    remap = np.full(n_vertices, -1, dtype=np.int64)
    remap[keep] = np.arange(keep.size)
    return keep, remap[faces]


def pole_u(u: np.ndarray, faces: np.ndarray, fpole: np.ndarray) -> np.ndarray:
    """Per face, the mean ``u`` of its corners that are not poles (``fpole`` (M, 3) bool), where
    a pole vertex of that face gets its ``u``."""
    return np.where(fpole, 0.0, u[faces]).sum(axis=1) / np.maximum((~fpole).sum(axis=1), 1)


def split_u_seam(
    uv: np.ndarray, faces: np.ndarray, dirs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Make a periodic ``u = uv[:, 0]`` in ``[0, 1]`` continuous inside every triangle of ``faces``.

    A triangle whose non-pole corners span more than half a period straddles the seam: its
    corners with ``u < 0.5`` get duplicates with ``u + 1``. Pole vertices (``dirs`` (N, 3) on the
    y axis, where ``u`` is undefined) get one duplicate per incident triangle, with
    :func:`pole_u`. Returns ``(source, uv_out, faces_out)``: the original vertex of each output
    vertex (index positions and normals with it), its uv, and the renumbered faces.
    """
    u = uv[:, 0]
    pole = (dirs[:, 0] == 0.0) & (dirs[:, 2] == 0.0)
    n = u.shape[0]
    fu = u[faces]
    fpole = pole[faces]
    hi = np.where(fpole, -np.inf, fu).max(axis=1)
    lo = np.where(fpole, np.inf, fu).min(axis=1)
    crossing = (hi - lo) > 0.5
    shift = crossing[:, None] & ~fpole & (fu < 0.5)
    faces_out = faces.copy()
    # duplicates of seam vertices: one per distinct vertex that needs u + 1
    seam_vertices = np.unique(faces[shift])
    new_index = np.full(n, -1, dtype=np.int64)
    new_index[seam_vertices] = n + np.arange(seam_vertices.size)
    faces_out[shift] = new_index[faces[shift]]
    source = np.concatenate([np.arange(n), seam_vertices])
    u_out = np.concatenate([u, u[seam_vertices] + 1.0])
    # poles: one duplicate per incident triangle
    fi, ci = np.nonzero(fpole)
    if fi.size:
        start = source.size
        source = np.concatenate([source, faces[fi, ci]])
        u_out = np.concatenate([u_out, pole_u(u_out, faces_out, fpole)[fi]])
        faces_out[fi, ci] = start + np.arange(fi.size)
    keep, faces_out = compact(source.size, faces_out)
    source = source[keep]
    return source, np.stack([u_out[keep], uv[source, 1]], axis=1), faces_out


def concat(
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Join ``(positions, faces, normals, uv)`` parts into one set of arrays (faces renumbered)."""
    offsets = np.cumsum([0] + [p[0].shape[0] for p in parts[:-1]])
    positions = np.concatenate([p[0] for p in parts])
    faces = np.concatenate([p[1] + o for p, o in zip(parts, offsets, strict=True)])
    normals = np.concatenate([p[2] for p in parts])
    uv = np.concatenate([p[3] for p in parts])
    return positions, faces, normals, uv
