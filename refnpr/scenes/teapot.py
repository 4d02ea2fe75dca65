"""Newell's teapot: 32 bicubic Bezier patches tessellated with analytic normals.

The data file ``data/newell-teapot.bpt`` holds, one item per line, comma separated: the patch
count (32); per patch 16 one-based control-point indices, row-major as ``C[i, j]``; the
control-point count (306); then the points ``x, y, z`` (z up; the spout points to +x).

Checked against the data: columns ``j`` run around the body and rows ``i`` down the profile;
with ``u`` the column and ``v`` the row parameter the outward normal is ``dP/du x dP/dv``. The
lid-knob and bottom patches have a collapsed first row (four equal control points), where
``dP/du = 0`` and the normal is the limit ``v (d2P/du dv x dP/dv)`` as v -> 0 (likewise on other
collapsed edges). A collapsed edge is evaluated as exactly its control point (the Bernstein
weights do not sum to exactly 1 in floating point) and the triangles that degenerate there are
dropped. Shared patch edges are evaluated bitwise identically from both sides
(:func:`_bernstein`, :func:`_contract`), so no cracks open between patches. The classic teapot
is not closed (the lid sits in the rim, handle and spout pierce the body unstitched).
"""

from __future__ import annotations

from functools import cache
from importlib import resources

import numpy as np

from ..raster import Mesh
from ._params import check_int
from ._topology import compact, drop_degenerate, grid_faces, unit

__all__ = ["read_bpt", "teapot", "teapot_patches"]

_DATA = "newell-teapot.bpt"


def read_bpt(text: str, *, source: str = "<bpt>") -> np.ndarray:
    """Parse Bezier patch text (format above) into control nets.

    Returns
    -------
    nets : (P, 4, 4, 3) float64
        ``nets[k, i, j]`` is control point (row i, column j) of patch k.

    Raises
    ------
    ValueError
        Naming ``source`` and the line, on malformed counts, indices or coordinates.
    """
    lines = [(n + 1, ln.strip()) for n, ln in enumerate(text.splitlines()) if ln.strip()]

    def numbers(pos: int, kind: type, count: int) -> list:
        lineno, ln = lines[pos]
        try:
            vals = [kind(x) for x in ln.split(",")]
        except ValueError as exc:
            raise ValueError(f"{source}, line {lineno}: cannot parse {ln!r} ({exc})") from exc
        if len(vals) != count:
            raise ValueError(f"{source}, line {lineno}: expected {count} values, got {len(vals)}")
        return vals

    if not lines:
        raise ValueError(f"{source}: empty patch file")
    n_patches = numbers(0, int, 1)[0]
    if len(lines) < n_patches + 2:
        raise ValueError(f"{source}: expected {n_patches} patch lines and a point count")
    index = np.array([numbers(1 + k, int, 16) for k in range(n_patches)], dtype=np.int64)
    n_points = numbers(1 + n_patches, int, 1)[0]
    if len(lines) != n_patches + 2 + n_points:
        raise ValueError(
            f"{source}: expected {n_points} control points after line {lines[1 + n_patches][0]}, "
            f"found {len(lines) - n_patches - 2}"
        )
    points = np.array([numbers(2 + n_patches + k, float, 3) for k in range(n_points)])
    if index.size and (index.min() < 1 or index.max() > n_points):
        raise ValueError(
            f"{source}: control point indices must be one-based in [1, {n_points}], "
            f"got range [{index.min()}, {index.max()}]"
        )
    return points[index - 1].reshape(n_patches, 4, 4, 3)


@cache
def teapot_patches() -> np.ndarray:
    """The 32 control nets of Newell's teapot, (32, 4, 4, 3) float64, z up (read-only)."""
    text = resources.files(__package__).joinpath("data", _DATA).read_text(encoding="utf-8")
    nets = read_bpt(text, source=_DATA)
    nets.setflags(write=False)
    return nets


def _bernstein(level: int) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Bernstein values and derivatives, (level + 1, 4) float64 each, at t = k / level.

    ``t = k / L`` and ``s = (L - k) / L`` are both correctly rounded, and ``b0 = s (s s)``,
    ``b1 = 3 t (s s)``, ``b2 = 3 s (t t)``, ``b3 = t (t t)``, so the row for ``L - k`` is exactly
    the reversed row for ``k``.
    """
    k = np.arange(level + 1, dtype=np.float64)
    t = k / level
    s = (level - k) / level
    b = np.stack([s * (s * s), 3.0 * t * (s * s), 3.0 * s * (t * t), t * (t * t)], axis=1)
    db = np.stack(
        [-3.0 * (s * s), 3.0 * s * (s - 2.0 * t), 3.0 * t * (2.0 * s - t), 3.0 * (t * t)], axis=1
    )
    return b, db


def _contract(b: np.ndarray, c: np.ndarray, axis: int) -> np.ndarray:
    """Sum ``b[:, m] * c[..., m, ...]`` over m (``c`` has 4 entries along ``axis``, which
    becomes one of length L + 1) as ``(b0 c0 + b3 c3) + (b1 c1 + b2 c2)``: the grouping is
    unchanged when both the basis row and the points are reversed, so a shared patch edge
    evaluates to bitwise the same points from either side."""
    cs = [np.expand_dims(np.take(c, m, axis=axis), axis) for m in range(4)]
    shape = [1] * c.ndim
    shape[axis] = b.shape[0]
    bs = [b[:, m].reshape(shape) for m in range(4)]
    return (bs[0] * cs[0] + bs[3] * cs[3]) + (bs[1] * cs[1] + bs[2] * cs[2])


def _evaluate(nets: np.ndarray, level: int) -> tuple[np.ndarray, ...]:
    """Positions and derivatives ``p, p_u, p_v, p_uv``, each (P, level + 1, level + 1, 3)
    float64 indexed ``[patch, row (v), column (u)]``."""
    b, db = _bernstein(level)
    q = _contract(b, nets, axis=2)  # along u (columns): (P, 4, L+1, 3)
    q_u = _contract(db, nets, axis=2)
    p = _contract(b, q, axis=1)  # along v (rows): (P, L+1, L+1, 3)
    p_v = _contract(db, q, axis=1)
    p_u = _contract(b, q_u, axis=1)
    p_uv = _contract(db, q_u, axis=1)
    return p, p_u, p_v, p_uv


def _normals(p_u, p_v, p_uv, level: int) -> np.ndarray:
    """Unit normals ``p_u x p_v``; on collapsed edges (a zero tangent) the one-sided limit."""
    n = np.cross(p_u, p_v)
    scale = max(float(np.abs(p_u).max()), float(np.abs(p_v).max()), 1e-300)
    tiny = np.linalg.norm(n, axis=-1) <= 1e-12 * scale * scale
    if np.any(tiny):
        k = np.arange(level + 1)
        side = np.where(k < level / 2.0, 1.0, -1.0)  # +1 where the interior lies at larger t
        su = side[None, None, :, None]  # by column (u)
        sv = side[None, :, None, None]  # by row (v)
        u_zero = np.linalg.norm(p_u, axis=-1, keepdims=True) <= 1e-12 * scale
        # p_u -> 0 on a row: p_u ~ (v - v0) p_uv, so n ~ sign * (p_uv x p_v); likewise for p_v.
        alt = np.where(u_zero, sv * np.cross(p_uv, p_v), su * np.cross(p_u, p_uv))
        n = np.where(tiny[..., None], alt, n)
    return unit(n)


def _snap_collapsed_edges(p: np.ndarray, nets: np.ndarray) -> None:
    """Set boundary rows/columns of ``p`` whose four control points coincide exactly to that
    point (in place): the Bernstein weights do not sum to exactly 1 in floating point."""
    for i in (0, 3):
        row = np.all(nets[:, i, :] == nets[:, i, :1], axis=(1, 2))
        col = np.all(nets[:, :, i] == nets[:, :1, i], axis=(1, 2))
        at = 0 if i == 0 else -1
        p[row, at, :] = nets[row, i, 0][:, None, :]
        p[col, :, at] = nets[col, 0, i][:, None, :]


def teapot(level: int = 8) -> Mesh:
    """Newell's teapot, each of its 32 bicubic patches tessellated into a ``level x level`` grid.

    Parameters
    ----------
    level : int
        Segments per patch side, 2..256 (at 1 some flat patch corners give zero-area
        triangles). Each patch gives ``2 level^2`` triangles less the ones that collapse at the
        lid knob and bottom centre (dropped).

    Returns
    -------
    Mesh
        y up (``(x, y, z) -> (x, z, -y)`` from the data), standing on y = 0, spout towards +x,
        3.15 units high. Vertices are per patch (patch edges duplicated with bitwise-equal
        positions); uv are the patch parameters in [0, 1]^2 (u around the body, v down the
        profile); normals from the patch tangents (limits at collapsed corners). Not closed.
    """
    level = check_int("level", level, minimum=2, maximum=256)
    nets = teapot_patches()
    p, p_u, p_v, p_uv = _evaluate(nets, level)
    _snap_collapsed_edges(p, nets)
    normals = _normals(p_u, p_v, p_uv, level)
    n_patch, side = nets.shape[0], level + 1
    grid = grid_faces(level, level)  # normal along d/du x d/dv (columns x rows)
    faces = (grid[None] + (side * side) * np.arange(n_patch)[:, None, None]).reshape(-1, 3)
    positions = p.reshape(-1, 3)
    faces = drop_degenerate(positions, faces)
    t = np.arange(side) / level
    vv, uu = np.meshgrid(t, t, indexing="ij")
    uv = np.tile(np.stack([uu.ravel(), vv.ravel()], axis=1), (n_patch, 1))
    keep, faces = compact(positions.shape[0], faces)
    z_to_y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
    positions = positions[keep] @ z_to_y.T + 0.0
    normals = normals.reshape(-1, 3)[keep] @ z_to_y.T + 0.0
    return Mesh(positions, faces, normals, uv[keep], name="teapot")
