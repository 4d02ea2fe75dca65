"""Plane, room and terrain: orientation, welded corners, tiled uv, analytic normals."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.scenes import plane, room, terrain, terrain_height, torus, torus_knot, uv_sphere, vase


def test_plane_faces_up_and_tiles(checks):
    m = plane(6.0, 4.0, tile=0.5, segments=3)
    assert m.n_faces == 2 * 3 * 3
    assert np.allclose(checks.face_normals(m), [0.0, 1.0, 0.0])
    checks.assert_normals_match_winding(m, min_dot=0.999)
    # uv = world distance / tile: u grows with x, v grows towards -z
    assert np.allclose(m.uv[:, 0], (m.positions[:, 0] + 3.0) / 0.5)
    assert np.allclose(m.uv[:, 1], (2.0 - m.positions[:, 2]) / 0.5)
    assert m.uv.max(axis=0).tolist() == [12.0, 8.0]


@given(
    width=st.floats(0.1, 50.0),
    depth=st.floats(0.1, 50.0),
    height=st.floats(0.1, 50.0),
    segments=st.integers(1, 9),
)
def test_room_corners_weld_exactly(checks, width, depth, height, segments):
    m = room(width, depth, height, tile=1.0, segments=segments)
    assert m.n_faces == 3 * 2 * segments**2
    tm = checks.weld_exact(m)
    counts = checks.edge_use(tm)
    # the three shared corner edges weld; the open outline has 6 sides of `segments` edges
    assert counts.max() == 2 and np.sum(counts == 1) == 6 * segments
    assert tm.is_winding_consistent
    checks.assert_normals_match_winding(m, min_dot=0.999)


def test_room_faces_inward_and_tiled_uv():
    m = room(8.0, 6.0, 4.0, tile=2.0, segments=2)
    n, p = m.normals, m.positions
    floor = np.all(n == [0.0, 1.0, 0.0], axis=1)
    back = np.all(n == [0.0, 0.0, 1.0], axis=1)
    left = np.all(n == [1.0, 0.0, 0.0], axis=1)
    assert (floor | back | left).all()
    assert np.all(p[floor, 1] == 0.0) and np.all(p[back, 2] == -3.0) and np.all(p[left, 0] == -4.0)
    # tiled uv: distance / tile along each rectangle
    assert np.allclose(m.uv[back], np.stack([p[back, 0] + 4.0, p[back, 1]], axis=1) / 2.0)
    assert np.allclose(m.uv[left], np.stack([3.0 - p[left, 2], p[left, 1]], axis=1) / 2.0)
    assert m.uv[floor].max(axis=0).tolist() == [4.0, 3.0]


def test_terrain_normals_match_finite_differences(checks):
    size, height = 10.0, 1.0
    m = terrain(size, n=64, height=height, octaves=4, seed=3)
    checks.assert_normals_match_winding(m, min_dot=0.5)
    x, z = m.positions[:, 0], m.positions[:, 2]
    h = 1e-5
    kw = dict(size=size, height=height, octaves=4, seed=3)
    hx = (terrain_height(x + h, z, **kw)[0] - terrain_height(x - h, z, **kw)[0]) / (2 * h)
    hz = (terrain_height(x, z + h, **kw)[0] - terrain_height(x, z - h, **kw)[0]) / (2 * h)
    fd = np.stack([-hx, np.ones_like(hx), -hz], axis=1)
    fd /= np.linalg.norm(fd, axis=1, keepdims=True)
    assert np.allclose(m.normals, fd, atol=1e-7)
    assert np.all(np.abs(m.positions[:, 1]) <= height)
    assert m.uv.min() == 0.0 and m.uv.max() == 1.0
    assert np.allclose(m.uv[:, 0], x / size + 0.5) and np.allclose(m.uv[:, 1], 0.5 - z / size)


def test_terrain_seeded():
    a, b, c = terrain(n=16, seed=1), terrain(n=16, seed=1), terrain(n=16, seed=2)
    assert np.array_equal(a.positions, b.positions)
    assert not np.array_equal(a.positions, c.positions)
    assert terrain(n=16, height=0.0).positions[:, 1].max() == 0.0


@pytest.mark.parametrize(
    "call, exc, match",
    [
        (lambda: plane(width=-1.0), ValueError, "width: expected a positive number, got -1.0"),
        (lambda: room(segments=0), ValueError, "segments: expected an integer >= 1, got 0"),
        (lambda: room(tile="1"), TypeError, "tile: expected a real number, got str"),
        (lambda: terrain(seed=-1), ValueError, "seed: expected an integer >= 0, got -1"),
        (lambda: terrain(octaves=0), ValueError, "octaves: expected an integer >= 1, got 0"),
    ],
)
def test_flat_validation(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


@pytest.mark.parametrize(
    "build, counts",
    [
        (lambda: plane(segments=10**6), "segments=1000000"),
        (lambda: room(segments=2600), "segments=2600"),  # three rectangles of 2601^2 vertices
        (lambda: terrain(n=10**5), "n=100000"),
        (lambda: uv_sphere(n_u=30_000, n_v=30_000), "n_u=30000, n_v=30000"),
        (lambda: torus(n_u=30_000, n_v=3_000), "n_u=30000, n_v=3000"),
        (lambda: vase(n_u=10**5, n_v=10**5), "n_u=100000, n_v=100000"),
        (lambda: torus_knot(n_u=10**5, n_v=1000), "n_u=100000, n_v=1000"),
    ],
)
def test_a_builder_refuses_a_resolution_beyond_the_vertex_cap_before_allocating(build, counts):
    """A resolution nobody checked allocated until a MemoryError (n_u = n_v = 30000: 6.7 GiB
    for the sphere's grid alone)."""
    with pytest.raises(ValueError, match=rf"{counts} makes about [\d,]+ vertices, more than the "):
        build()


def test_the_vertex_cap_admits_a_grid_of_exactly_the_cap(monkeypatch):
    import refnpr.scenes._params as params

    monkeypatch.setattr(params, "MAX_GENERATED_VERTICES", 100)
    assert plane(segments=9).positions.shape == (100, 3)  # (9 + 1)^2 vertices
    with pytest.raises(
        ValueError, match=r"segments=10 makes about 121 vertices, more than the 100"
    ):
        plane(segments=10)


@pytest.mark.parametrize(
    "build, counts",
    [
        (lambda: plane(segments=7), {"segments": 7}),
        (lambda: room(segments=5), {"segments": 5}),
        (lambda: terrain(n=6), {"n": 6}),
        (lambda: uv_sphere(n_u=9, n_v=5), {"n_u": 9, "n_v": 5}),
        (lambda: torus(n_u=9, n_v=5), {"n_u": 9, "n_v": 5}),
        (lambda: vase(n_u=8, n_v=4), {"n_u": 8, "n_v": 4}),
        (lambda: torus_knot(n_u=16, n_v=5), {"n_u": 16, "n_v": 5}),
    ],
)
def test_the_vertex_estimate_of_each_builder_bounds_its_mesh_closely(build, counts, monkeypatch):
    """With the cap one vertex below a builder's mesh, the builder refuses it: the estimate it
    checks is at least the vertices it makes, and at most a few more (seams, poles)."""
    import re

    import refnpr.scenes._params as params

    n = build().positions.shape[0]
    monkeypatch.setattr(params, "MAX_GENERATED_VERTICES", n - 1)
    with pytest.raises(ValueError, match=r"makes about [\d,]+ vertices") as info:
        build()
    estimate = int(re.search(r"about ([\d,]+)", str(info.value)).group(1).replace(",", ""))
    assert n <= estimate <= 1.25 * n, (n, estimate)
