"""uv charts of the stroke field: a smooth tangent frame per vertex, chart orientation.

TAMISS "needs an overlap-free UV mapping, oriented on object features" (Szécsi et al., sec. 4.1):
the hatching direction is the uv direction. A patch-wise mapping such as the Newell teapot's 32
Bezier patches breaks it twice, and this module repairs both without touching the mesh
(``docs/tamiss.md``, "uv charts"): neighbouring patches may have u and v swapped or reversed, so
:func:`chart_layout` gives every chart a signed permutation M of (u, v) (u' = M u) under which the
oriented tangent frames agree across shared borders; and the rasterizer's d(uv)/d(x, y) is one
value per triangle, so levels and density boundaries would follow the tessellation:
:func:`vertex_frames` gives each vertex the area-weighted mean of its triangles' dP/du, dP/dv,
from which the kernels (``_kernels._smooth_duv``) make a d(uv)/d(x, y) continuous across edges
(``derivatives="smooth"``).
"""

from __future__ import annotations

import functools
import weakref
from dataclasses import dataclass

import numpy as np

__all__ = [
    "SYMMETRIES",
    "UV_CONTINUITY_TOL",
    "ChartLayout",
    "vertex_frames",
    "chart_layout",
]

#: The 8 signed permutations of (u, v): u' = M u.
SYMMETRIES = np.array(
    [
        [[sa, 0], [0, sb]] if swap == 0 else [[0, sa], [sb, 0]]
        for swap in (0, 1)
        for sa in (1, -1)
        for sb in (1, -1)
    ],
    dtype=np.float64,
)


def per_mesh(fn):
    """``fn(mesh, ...)`` computed once per mesh (kept while the mesh lives)."""
    cache: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

    @functools.wraps(fn)
    def cached(mesh, *args, **kwargs):
        if mesh not in cache:
            cache[mesh] = fn(mesh, *args, **kwargs)
        return cache[mesh]

    return cached


@per_mesh
def vertex_frames(mesh) -> np.ndarray:
    """(V, 3, 2) float64 tangent frame [dP/du, dP/dv] per vertex of ``mesh``.

    Each triangle's frame solves [P1 - P0, P2 - P0] = F [uv1 - uv0, uv2 - uv0]; a vertex takes
    the mean of its triangles' frames weighted by their area (triangles with a degenerate uv
    map are left out; a vertex with none gets zeros). Needs ``mesh.uv``.
    """
    pos = np.asarray(mesh.positions, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    uv = np.asarray(mesh.uv, dtype=np.float64)
    e1 = pos[faces[:, 1]] - pos[faces[:, 0]]
    e2 = pos[faces[:, 2]] - pos[faces[:, 0]]
    d1 = uv[faces[:, 1]] - uv[faces[:, 0]]
    d2 = uv[faces[:, 2]] - uv[faces[:, 0]]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)
    ok = np.abs(det) > 1e-14
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    # F = [e1 e2] [d1 d2]^-1, with [d1 d2]^-1 = [[d2v, -d2u], [-d1v, d1u]] / det
    t_u = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * inv[:, None]
    t_v = (-e1 * d2[:, 0:1] + e2 * d1[:, 0:1]) * inv[:, None]
    w = np.where(ok, area, 0.0)
    frames = np.zeros((pos.shape[0], 3, 2))
    wsum = np.zeros(pos.shape[0])
    for j in range(3):
        np.add.at(frames[:, :, 0], faces[:, j], t_u * w[:, None])
        np.add.at(frames[:, :, 1], faces[:, j], t_v * w[:, None])
        np.add.at(wsum, faces[:, j], w)
    frames /= np.where(wsum > 0, wsum, 1.0)[:, None, None]
    return frames


def _unit_columns(frames: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(frames, axis=1, keepdims=True)
    return np.divide(frames, norm, out=np.zeros_like(frames), where=norm > 1e-12)


def _shared_vertices(mesh, labels: np.ndarray, unit: np.ndarray):
    """Pairs (a, b) of vertices at one exact position in different charts, and the chart of each
    vertex. Positions where a chart has two vertices (a collapsed patch edge, such as the lid's
    pole) or a vertex has a degenerate frame are left out: there the frame says nothing about the
    border."""
    faces = np.asarray(mesh.faces, dtype=np.int64)
    n_v = mesh.positions.shape[0]
    v_chart = np.full(n_v, -1, dtype=np.int64)
    v_chart[faces.ravel()] = np.repeat(labels, 3)
    _, group = np.unique(np.asarray(mesh.positions), axis=0, return_inverse=True)
    group = group.ravel()
    order = np.lexsort((np.arange(n_v), group))
    g_sorted = group[order]
    ok = np.all(np.linalg.norm(unit, axis=1) > 0.5, axis=1)
    pair_a, pair_b = [], []
    starts = np.flatnonzero(np.r_[True, g_sorted[1:] != g_sorted[:-1]])
    ends = np.r_[starts[1:], n_v]
    for k in np.flatnonzero(ends - starts > 1):
        members = order[starts[k] : ends[k]]
        ch = v_chart[members]
        if np.any(ch < 0) or np.unique(ch).size != ch.size or not np.all(ok[members]):
            continue
        for i in range(len(members)):
            for j in range(i + 1, len(members)):
                pair_a.append(members[i])
                pair_b.append(members[j])
    return np.array(pair_a, dtype=np.int64), np.array(pair_b, dtype=np.int64), v_chart


@dataclass(frozen=True, eq=False)
class ChartLayout:
    """How each chart of a mesh enters the stroke field (all indexed by chart).

    Attributes
    ----------
    symmetry : (C,) int64, index into :data:`SYMMETRIES` (u' = M u + offset)
    offset : (C, 2) float64, added after the symmetry
    group : (C,) int64, the chart the stroke ids use: charts whose oriented, offset uv continue
        each other across a border (and do not overlap) form one group, so strokes run on from
        one patch into the next instead of ending at every border
    """

    symmetry: np.ndarray
    offset: np.ndarray
    group: np.ndarray


#: Largest mismatch (uv units) of two charts' uv at shared vertices that still counts as the
#: same mapping continued (patch borders are bitwise shared, their uv exact).
UV_CONTINUITY_TOL = 1e-6


@per_mesh
def chart_layout(mesh, labels: np.ndarray) -> ChartLayout:
    """Orientation, offset and id group of every chart of ``mesh`` (``labels``: chart per face).

    Charts touch where vertices of different charts share a position exactly (patch borders
    duplicated bitwise; collapsed edges and degenerate frames are skipped). For touching charts
    a and b, C_ab = sum over shared positions of F_a^T F_b (unit columns) scores a pair of
    orientations by trace(M_a C_ab M_b^T), the agreement of the oriented frames F M^T. Charts
    are visited along a maximum spanning tree of the touch counts, from the lowest-numbered
    chart of each connected set (which keeps its mapping), each taking the symmetry that agrees
    best with its parent. A child then takes the offset that carries its oriented uv onto the
    parent's at the shared vertices; where that fits every shared vertex to
    :data:`UV_CONTINUITY_TOL` and the child's uv box does not overlap the boxes already in the
    parent's group, it joins the group (its strokes continue the parent's), else it starts a
    group of its own (offset 0). Deterministic; charts touching nothing keep the identity.
    Computed once per mesh.
    """
    labels = np.asarray(labels, dtype=np.int64)
    n_charts = int(labels.max()) + 1 if labels.size else 0
    unit = _unit_columns(vertex_frames(mesh))
    pa, pb, v_chart = _shared_vertices(mesh, labels, unit)
    sym = np.zeros(n_charts, dtype=np.int64)
    offset = np.zeros((n_charts, 2))
    group = np.arange(n_charts, dtype=np.int64)
    uv = np.asarray(mesh.uv, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    # each chart's uv box (from its faces' vertices)
    lo = np.full((n_charts, 2), np.inf)
    hi = np.full((n_charts, 2), -np.inf)
    fv = uv[faces]  # (M, 3, 2)
    np.minimum.at(lo, labels, fv.min(axis=1))
    np.maximum.at(hi, labels, fv.max(axis=1))
    if pa.size == 0:
        return ChartLayout(sym, offset, group)
    ca, cb = v_chart[pa], v_chart[pb]
    swap = ca > cb
    ca, cb = np.where(swap, cb, ca), np.where(swap, ca, cb)
    pa, pb = np.where(swap, pb, pa), np.where(swap, pa, pb)
    prod = np.einsum("nki,nkj->nij", unit[pa], unit[pb])  # F_a^T F_b per pair
    key = ca * n_charts + cb
    keys, inv = np.unique(key, return_inverse=True)
    inv = inv.ravel()
    c_sum = np.zeros((keys.size, 2, 2))
    np.add.at(c_sum, inv, prod)
    count = np.bincount(inv, minlength=keys.size)
    by_edge = np.split(np.argsort(inv, kind="stable"), np.cumsum(count)[:-1])
    edges = sorted(
        (-int(count[e]), int(keys[e] // n_charts), int(keys[e] % n_charts), e)
        for e in range(keys.size)
    )  # fmt: skip
    # Kruskal: maximum spanning forest by touch count (ties by chart numbers)
    parent = list(range(n_charts))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    adj: dict[int, list[tuple[int, int]]] = {c: [] for c in range(n_charts)}
    for _, a, b, e in edges:
        ra, rb = find(a), find(b)
        if ra == rb:
            continue
        parent[max(ra, rb)] = min(ra, rb)
        adj[a].append((b, e))
        adj[b].append((a, e))
    members: dict[int, list[int]] = {}
    seen = np.zeros(n_charts, dtype=bool)

    def box(c: int) -> tuple[np.ndarray, np.ndarray]:
        corners = np.array([[lo[c, 0], lo[c, 1]], [hi[c, 0], hi[c, 1]]]) @ SYMMETRIES[sym[c]].T
        return corners.min(axis=0) + offset[c], corners.max(axis=0) + offset[c]

    def overlap(b: int, c: int) -> bool:
        (b_lo, b_hi), (c_lo, c_hi) = box(b), box(c)
        return bool(np.all(np.minimum(b_hi, c_hi) - np.maximum(b_lo, c_lo) > UV_CONTINUITY_TOL))

    for root in range(n_charts):
        if seen[root]:
            continue
        seen[root] = True
        members[root] = [root]
        stack = [root]
        while stack:
            a = stack.pop()
            m_a = SYMMETRIES[sym[a]]
            for b, e in sorted(adj[a]):
                if seen[b]:
                    continue
                c_ab = c_sum[e] if a < b else c_sum[e].T
                scores = np.einsum("ij,jk,lik->l", m_a, c_ab, SYMMETRIES)  # trace(M_a C M_b^T)
                sym[b] = int(np.argmax(scores))
                seen[b] = True
                stack.append(b)
                # the offset that continues a's uv into b's across the shared vertices
                idx = by_edge[e]
                va, vb = (pa[idx], pb[idx]) if a < b else (pb[idx], pa[idx])
                d = uv[va] @ m_a.T + offset[a] - uv[vb] @ SYMMETRIES[sym[b]].T
                o_b = np.median(d, axis=0)
                if np.max(np.abs(d - o_b)) > UV_CONTINUITY_TOL:
                    members[b] = [b]
                    continue
                offset[b] = o_b
                g = group[a]
                if any(overlap(b, c) for c in members[g]):
                    offset[b] = 0.0
                    members[b] = [b]
                else:
                    group[b] = g
                    members[g].append(b)
    return ChartLayout(sym, offset, group)
