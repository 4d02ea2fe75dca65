"""Newell's teapot: file parsing, positions and normals against a de Casteljau oracle,
collapsed corners, welded patch edges, the expected open boundaries."""

import numpy as np
import pytest

from refnpr.scenes import read_bpt, teapot, teapot_patches


def _casteljau(nets, u, v):
    """Oracle: de Casteljau on each (4, 4, 3) net at (u, v); u along columns, v along rows.

    nets : (K, 4, 4, 3); u, v : (K,) -> (K, 3)"""
    pts = nets.copy()
    for _ in range(3):  # columns
        pts = (1 - u)[:, None, None, None] * pts[:, :, :-1] + u[:, None, None, None] * pts[:, :, 1:]
    pts = pts[:, :, 0]
    for _ in range(3):  # rows
        pts = (1 - v)[:, None, None] * pts[:, :-1] + v[:, None, None] * pts[:, 1:]
    return pts[:, 0]


def _to_y_up(p):
    return np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)


def _match_patches(mesh):
    """(N, 32) bool: patches whose surface at the vertex's uv is that vertex (oracle). A few
    vertices match several patches (collapsed points, the handle touching the body)."""
    nets = teapot_patches()
    n, k = mesh.n_vertices, nets.shape[0]
    u = np.repeat(mesh.uv[:, 0], k)
    v = np.repeat(mesh.uv[:, 1], k)
    pts = _to_y_up(_casteljau(np.tile(nets, (n, 1, 1, 1)), u, v)).reshape(n, k, 3)
    return np.linalg.norm(pts - mesh.positions[:, None, :], axis=2) < 1e-12


def test_read_bpt_shipped_file():
    nets = teapot_patches()
    assert nets.shape == (32, 4, 4, 3)
    assert nets[..., 2].min() == 0.0 and nets[..., 2].max() == 3.15  # z up, 0 .. 3.15
    assert nets[..., 0].min() == -3.0  # the handle's far end


@pytest.mark.parametrize(
    "text, match",
    [
        ("", "empty patch file"),
        ("1\n1,2,3\n1\n0,0,0\n", "line 2: expected 16 values, got 3"),
        ("1\n1,2,3\n", "expected 1 patch lines and a point count"),
        ("1\n" + ",".join(["1"] * 16) + "\n1\n0,0\n", "line 4: expected 3 values, got 2"),
        (
            "1\n" + ",".join(["2"] * 16) + "\n1\n0,0,0\n",
            r"one-based in \[1, 1\], got range \[2, 2\]",
        ),
        ("1\n" + ",".join(["1"] * 16) + "\n1\n0,x,0\n", "line 4: cannot parse '0,x,0'"),
        ("1\n" + ",".join(["1"] * 16) + "\n2\n0,0,0\n", "expected 2 control points"),
    ],
)
def test_read_bpt_errors(text, match):
    with pytest.raises(ValueError, match=match):
        read_bpt(text, source="t.bpt")


@pytest.mark.parametrize("level", [2, 3, 5, 8, 12])
def test_teapot_counts_and_degenerates(checks, level):
    m = teapot(level)
    # 32 patches of 2 L^2 triangles; the 8 patches with a collapsed first row lose L each
    assert m.n_faces == 32 * 2 * level**2 - 8 * level
    assert m.n_vertices == 32 * (level + 1) ** 2 - 8
    checks.assert_no_degenerate(m)
    assert m.uv.min() == 0.0 and m.uv.max() == 1.0
    assert np.all(np.isfinite(m.normals))
    assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-12)


def _boundary_loops(tm):
    edges, counts = np.unique(tm.edges_sorted, axis=0, return_counts=True)
    boundary = edges[counts == 1]
    parent = {}

    def find(a):
        while parent.setdefault(a, a) != a:
            a = parent[a]
        return a

    for a, b in boundary:
        parent[find(a)] = find(b)
    roots = [find(a) for a in boundary[:, 0]]
    _, sizes = np.unique(roots, return_counts=True)
    return counts, sorted(sizes.tolist())


@pytest.mark.parametrize("level", [4, 8])
def test_teapot_patch_edges_weld_exactly(checks, level):
    """Shared patch edges are bitwise equal, so exact welding leaves only the teapot's real
    openings: the pot rim and the lid rim (4L edges each), the two ends of the handle and of
    the spout (2L edges each). A crack would add boundary loops."""
    tm = checks.weld_exact(teapot(level))
    counts, loops = _boundary_loops(tm)
    assert counts.max() == 2
    assert loops == [2 * level] * 4 + [4 * level] * 2
    assert tm.is_winding_consistent


def test_teapot_positions_on_patches_and_y_up():
    m = teapot(6)
    match = _match_patches(m)
    assert np.all(match.any(axis=1))  # every vertex is a point of some patch at its uv
    assert np.all(match.sum(axis=0) >= 7 * 7 - 7)  # and every patch is there
    lo, hi = m.positions.min(axis=0), m.positions.max(axis=0)
    assert lo[1] == 0.0 and hi[1] == 3.15  # stands on y = 0
    assert hi[0] > 3.4 and lo[0] == -3.0  # spout towards +x, handle towards -x


def _fd_normal(nets, u, v, h=1e-6):
    """Oracle normal: central differences of the de Casteljau surface, d/du x d/dv, y up."""
    u = np.clip(u, h, 1 - h)
    v = np.clip(v, h, 1 - h)
    du = _casteljau(nets, u + h, v) - _casteljau(nets, u - h, v)
    dv = _casteljau(nets, u, v + h) - _casteljau(nets, u, v - h)
    n = _to_y_up(np.cross(du, dv))
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_teapot_normals_match_surface_oracle():
    m = teapot(6)
    match = _match_patches(m)
    vertex, patch = np.nonzero(match)
    oracle = _fd_normal(teapot_patches()[patch], m.uv[vertex, 0], m.uv[vertex, 1], h=1e-4)
    dots = np.full(m.n_vertices, -np.inf)
    np.maximum.at(dots, vertex, np.einsum("ij,ij->i", oracle, m.normals[vertex]))
    # away from collapsed points the normals agree closely; at them the oracle (a step inside)
    # is the limit the code must return
    assert np.percentile(dots, 1) > 1 - 1e-6
    assert dots.min() > 0.999


def test_teapot_collapsed_corner_normals():
    m = teapot(8)
    top = np.all(m.positions == [0.0, 3.15, 0.0], axis=1)
    bottom = np.all(m.positions == [0.0, 0.0, 0.0], axis=1)
    assert top.sum() == 4 * 8 and bottom.sum() == 4 * 8  # L vertices per collapsed row, 4 patches
    assert np.allclose(m.normals[top], [0.0, 1.0, 0.0], atol=1e-12)
    assert np.allclose(m.normals[bottom], [0.0, -1.0, 0.0], atol=1e-12)


def test_teapot_normals_outward_by_part():
    m = teapot(6)
    match = _match_patches(m)
    n, p = m.normals, m.positions

    def only(lo, hi):  # vertices that belong to patches lo..hi-1 and to no other patch
        return match[:, lo:hi].any(axis=1) & ~np.delete(match, np.s_[lo:hi], axis=1).any(axis=1)

    body = only(4, 12) & (m.uv[:, 1] < 1.0)  # the body's bottom ring has vertical normals
    assert np.all(n[body, 0] * p[body, 0] + n[body, 2] * p[body, 2] > 0)  # radially outward
    lid = only(24, 28) & (m.uv[:, 1] < 1.0)  # the lid's lower edge is a vertical flange
    assert np.all(n[lid, 1] > 0)  # lid faces up
    bottom = only(28, 32) & (m.uv[:, 1] < 1.0)  # its outer edge turns up into the body
    assert np.all(n[bottom, 1] < 0)  # bottom faces down


@pytest.mark.parametrize("level", [2, 4, 10, 12, 32])
def test_teapot_has_no_sliver_triangles(level):
    """No triangle is thinner than 1/25 of its longest edge (measured minimum 0.047 over
    levels 2..32: the rim bead's rows, and at level 32 the fan around the knob's top). The
    dotted line along the lid rim of the old spp-1 toon default was not a mesh sliver but the
    bead's crest turning away from the camera in a band under a pixel wide (see
    tests/render/test_cli.py)."""
    m = teapot(level)
    p = m.positions[m.faces]
    e = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]], axis=1)
    longest = np.linalg.norm(e, axis=2).max(axis=1)
    altitude = np.linalg.norm(np.cross(e[:, 0], e[:, 1]), axis=1) / longest
    assert (altitude / longest).min() > 0.04


def test_teapot_validation():
    with pytest.raises(ValueError, match="level: expected an integer >= 2, got 1"):
        teapot(1)
    with pytest.raises(TypeError, match="level: expected an integer, got str"):
        teapot("8")


@pytest.mark.parametrize("variant", ["transpose", "reverse_rows", "reverse_cols"])
def test_collapsed_edge_limit_on_any_side(variant):
    """The lid-knob patch collapses its first row; re-parametrized copies collapse the first
    column or the last row instead. Their normals must be the same surface normals (up to the
    sign flip the re-parametrization implies), including at the collapsed point."""
    from refnpr.scenes.teapot import _evaluate, _normals, _snap_collapsed_edges

    level = 6
    net = teapot_patches()[20:21]

    def normals(nets):
        p, p_u, p_v, p_uv = _evaluate(nets, level)
        _snap_collapsed_edges(p, nets)
        return _normals(p_u, p_v, p_uv, level)[0]

    ref = normals(net)
    if variant == "transpose":  # collapsed column 0; swapping u and v flips u x v
        got = -normals(net.transpose(0, 2, 1, 3)).transpose(1, 0, 2)
    elif variant == "reverse_rows":  # collapsed last row; v -> 1 - v flips the normal
        got = -normals(net[:, ::-1])[::-1]
    else:  # u -> 1 - u flips the normal
        got = -normals(net[:, :, ::-1])[:, ::-1]
    assert np.all(np.isfinite(got))
    assert np.allclose(got, ref, atol=1e-12)
    assert np.allclose(ref[0], [0.0, 0.0, 1.0], atol=1e-12)  # z up in the data's frame
