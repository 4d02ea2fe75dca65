"""Watertightness: closed meshes, fans and grids sharing edges and vertices on sample centres and
at 1/256 px offsets, and shared edges that cross the near plane, via the coverage_count channel."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import Camera, Mesh, rasterize

from .meshes import at_pixels, cube, icosphere, random_outside_camera, torus
from .oracle import View, cast, pixel_centres, region_distance

EPS = 1.0 / 128.0  # pixels: the outer boundary of a union may round either way within this band
SUB = 1.0 / 256.0  # one fixed-point step


def _counts(mesh_or_meshes, camera, width, height, spp, cull=False):
    gb = rasterize(
        mesh_or_meshes,
        camera,
        width,
        height,
        ("coverage_count", "tri_id"),
        spp,
        cull_backfaces=cull,
    )
    return gb["coverage_count"], gb["tri_id"]


# ---------------------------------------------------------------------------------------------
# closed meshes
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("spp", [1, 4])
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(
    "make", [lambda: icosphere(2), lambda: cube(1.4)], ids=["icosphere", "cube"]
)
def test_convex_closed_mesh_is_claimed_twice_inside_and_once_when_culled(make, seed, spp):
    mesh = make()
    rng = np.random.default_rng(seed)
    cam = random_outside_camera(rng, radius=1.3)
    w, h = 40, 32
    count, tri_id = _counts(mesh, cam, w, h, spp)
    inside = tri_id >= 0
    assert 0.05 < inside.mean() < 0.95
    np.testing.assert_array_equal(count, np.where(inside, 2, 0))
    count1, tri1 = _counts(mesh, cam, w, h, spp, cull=True)
    np.testing.assert_array_equal(count1, np.where(inside, 1, 0))
    np.testing.assert_array_equal(tri1 >= 0, inside)
    # the silhouette itself agrees with the oracle away from edges
    n = int(round(spp**0.5))
    px, py = pixel_centres(w, h, n)
    hits = cast(View.of(cam, w, h), mesh.positions, mesh.faces, px, py)
    assert hits.clear.mean() > 0.8
    np.testing.assert_array_equal(inside.ravel()[hits.clear], hits.tri[hits.clear] >= 0)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_torus_front_and_back_layers_balance_at_every_sample(seed):
    """For a closed surface every sample is claimed by as many front- as back-facing triangles:
    count(no culling) == 2 count(front faces only), whatever the depth complexity."""
    mesh = torus(1.0, 0.4, 32, 14)
    rng = np.random.default_rng(100 + seed)
    cam = random_outside_camera(rng, radius=1.4)
    w, h = 44, 36
    count, tri_id = _counts(mesh, cam, w, h, 4)
    front, _ = _counts(mesh, cam, w, h, 4, cull=True)
    np.testing.assert_array_equal(count, 2 * front)
    np.testing.assert_array_equal(front > 0, tri_id >= 0)
    assert (tri_id >= 0).mean() > 0.05


def test_torus_from_the_side_has_four_layers():
    """Seen edge-on the torus is claimed four times where both rings overlap: the balance above
    is tested with depth complexity > 2."""
    mesh = torus(1.0, 0.4, 32, 14)
    cam = Camera.look_at((0.0, -4.0, 0.3), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 50.0, 0.1, 20.0)
    count, _ = _counts(mesh, cam, 40, 24, 1)
    front, _ = _counts(mesh, cam, 40, 24, 1, cull=True)
    np.testing.assert_array_equal(count, 2 * front)
    assert np.count_nonzero(count == 4) > 20


# ---------------------------------------------------------------------------------------------
# fans and grids in screen space
# ---------------------------------------------------------------------------------------------

W, H = 36, 32
#: Ring of a fan, in pixels around its centre: axis-aligned and diagonal shared edges.
RING8 = np.array([(6, 0), (5, 5), (0, 6), (-5, 5), (-6, 0), (-5, -5), (0, -6), (5, -5)], float)
_CAM = Camera.look_at((0.4, -0.3, 3.0), (0.0, 0.1, 0.0), (0.1, 1.0, 0.0), 50.0, 0.1, 100.0)


def _fan_mesh(centre, ring, rng) -> Mesh:
    """Triangles (centre, ring[i], ring[i+1]) with vertices at the given pixel coordinates and
    random depths (a non-planar fan: coverage only depends on screen positions)."""
    pts = np.vstack([centre, ring])
    depth = rng.uniform(1.5, 4.0, len(pts))
    pos = at_pixels(View.of(_CAM, W, H), pts[:, 0], pts[:, 1], depth)
    k = len(ring)
    faces = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)])
    return Mesh(pos, faces, name="fan")


def _convex_distance(poly, px, py):
    """Signed 2D distance (pixels) to a convex polygon (K, 2), positive inside."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    area = np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1])
    e = b - a
    cross = e[:, 0] * (py[..., None] - a[:, 1]) - e[:, 1] * (px[..., None] - a[:, 0])
    return (np.sign(area) * cross / np.hypot(e[:, 0], e[:, 1])).min(axis=-1)


def _fan_cases():
    c = np.array([16.5, 14.5])
    cases = {
        "pixel_centres": (1, c, c + RING8),
        "plus_1_256": (1, c + SUB, c + RING8 + SUB),
        "minus_1_256": (1, c - [SUB, 0.0], c + RING8 - [SUB, 0.0]),
        "mixed_1_256": (1, c + [SUB, -SUB], c + RING8 + SUB * np.array([[1, -1], [-1, 1]] * 4)),
        "pixel_corner": (4, np.array([16.0, 14.0]), np.array([16.0, 14.0]) + RING8),
    }
    for n in (2, 3, 4):  # centre and ring on sample centres of the n x n grid
        centre = np.array([16.0 + 1.5 / n, 14.0 + 0.5 / n])
        cases[f"samples_spp{n * n}"] = (n * n, centre, centre + RING8 * (n + 1) / n)
    return cases


@pytest.mark.parametrize("case", sorted(_fan_cases()))
def test_fan_covers_its_union_exactly_once(case):
    spp, centre, ring = _fan_cases()[case]
    mesh = _fan_mesh(centre, ring, np.random.default_rng(5))
    count, tri_id = _counts(mesh, _CAM, W, H, spp)
    np.testing.assert_array_equal(tri_id >= 0, count > 0)
    n = int(round(spp**0.5))
    px, py = pixel_centres(W, H, n)
    d = _convex_distance(ring, px, py)
    assert count.max() <= 1, f"{np.count_nonzero(count > 1)} samples claimed twice"
    inside, outside = d >= EPS, d <= -EPS
    np.testing.assert_array_equal(count[inside], 1)
    np.testing.assert_array_equal(count[outside], 0)
    # the configuration really puts samples on the shared edges through the centre
    on_axis = (np.abs(py - centre[1]) < 1e-12) | (np.abs(px - centre[0]) < 1e-12)
    if case == "pixel_centres" or (case.startswith("samples") and n != 3):
        assert np.count_nonzero(on_axis & inside) >= 4


@pytest.mark.parametrize("spp", [1, 4, 9, 16])
def test_jittered_grid_covers_every_sample_exactly_once(spp):
    """A triangulated grid over more than the viewport, vertices on sample centres, some moved
    by +-1/256 px (others keep exactly horizontal and vertical edges through sample centres),
    random diagonals and depths: every sample is claimed by exactly one triangle."""
    n = int(round(spp**0.5))
    rng = np.random.default_rng(spp)
    step = 2 * n + 1  # in samples
    xs = (np.arange(-3 * n, n * W + 3 * n, step) + 0.5) / n
    ys = (np.arange(-3 * n, n * H + 3 * n, step) + 0.5) / n
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    jitter = rng.choice([0.0, 0.0, SUB, -SUB], size=(*gx.shape, 2))
    gx, gy = gx + jitter[..., 0], gy + jitter[..., 1]
    depth = rng.uniform(1.5, 4.0, gx.shape)
    pos = at_pixels(View.of(_CAM, W, H), gx.ravel(), gy.ravel(), depth.ravel())
    idx = np.arange(gx.size).reshape(gx.shape)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    flip = rng.random(a.shape) < 0.5
    t1 = np.where(flip[..., None], np.stack([a, b, c], -1), np.stack([a, b, d], -1))
    t2 = np.where(flip[..., None], np.stack([a, c, d], -1), np.stack([b, c, d], -1))
    faces = np.concatenate([t1.reshape(-1, 3), t2.reshape(-1, 3)])
    count, tri_id = _counts(Mesh(pos, faces), _CAM, W, H, spp)
    assert np.all(tri_id >= 0)
    bad = np.argwhere(count != 1)
    assert bad.size == 0, f"{len(bad)} samples not claimed exactly once, first {bad[:3].tolist()}"


@pytest.mark.parametrize("spp", [1, 4])
def test_top_left_fill_rule_on_pixel_centres(spp):
    """A square with corners on pixel centres (2.5, 2.5) and (8.5, 6.5), split on its diagonal:
    the left and top edges are inside, the right and bottom edges outside, the diagonal's
    samples belong to exactly one triangle. Both windings."""
    n = int(round(spp**0.5))
    view = View.of(_CAM, W, H)
    corners = np.array([(2.5, 2.5), (8.5, 2.5), (8.5, 6.5), (2.5, 6.5)])
    pos = at_pixels(view, corners[:, 0], corners[:, 1], np.array([2.0, 2.5, 3.0, 2.2]))
    px, py = pixel_centres(W, H, n)
    expect = ((px >= 2.5) & (px < 8.5) & (py >= 2.5) & (py < 6.5)).astype(int)
    for faces in ([[0, 1, 2], [0, 2, 3]], [[0, 2, 1], [0, 3, 2]]):
        count, tri_id = _counts(Mesh(pos, faces), _CAM, W, H, spp)
        np.testing.assert_array_equal(count, expect)
        np.testing.assert_array_equal(tri_id >= 0, expect.astype(bool))


# ---------------------------------------------------------------------------------------------
# shared edges crossing the near plane and the eye plane
# ---------------------------------------------------------------------------------------------


def _camera_frame(cam: Camera, xyw) -> np.ndarray:
    right, up, back = cam.basis()
    xyw = np.asarray(xyw, dtype=np.float64)
    return cam.eye + xyw[:, :1] * right + xyw[:, 1:2] * up - xyw[:, 2:3] * back


def _plane_y(x, w):
    return -1.0 + 0.05 * x + 0.12 * w  # a tilted floor in the camera frame


@pytest.mark.parametrize("far", [30.0, 5.0])
@pytest.mark.parametrize("spp", [1, 4])
def test_quad_split_on_a_diagonal_through_the_near_plane_is_covered_once(spp, far):
    """Two triangles whose shared diagonal runs from behind the eye (w < 0) across w = 0 and the
    near plane (and, with far = 5, the far plane): the union is covered exactly once."""
    cam = Camera.look_at((0.2, 0.5, 1.0), (0.0, 0.2, -3.0), (0.0, 1.0, 0.0), 70.0, 0.5, far)
    x = np.array([-3.0, 3.0, 2.5, -2.5])
    w = np.array([-2.0, -1.0, 7.0, 8.0])
    pos = _camera_frame(cam, np.stack([x, _plane_y(x, w), w], -1))
    mesh = Mesh(pos, [[0, 1, 2], [0, 2, 3]])
    width, height = 40, 30
    count, tri_id = _counts(mesh, cam, width, height, spp)
    np.testing.assert_array_equal(tri_id >= 0, count > 0)
    n = int(round(spp**0.5))
    px, py = pixel_centres(width, height, n)
    d = region_distance(View.of(cam, width, height), pos, np.array([[0, 1, 2, 3]]), px, py)
    d = d.reshape(count.shape)
    assert count.max() <= 1
    assert np.count_nonzero(d >= EPS) > 50
    np.testing.assert_array_equal(count[d >= EPS], 1)
    np.testing.assert_array_equal(count[d <= -EPS], 0)


@pytest.mark.parametrize("spp", [1, 4])
def test_planar_fan_around_a_vertex_behind_the_eye_is_covered_once(spp):
    """Every shared edge of this fan starts behind the camera and crosses the eye and near
    planes; the fan's union (a convex polygon) is still covered exactly once."""
    cam = Camera.look_at((0.0, 0.3, 0.0), (0.0, 0.1, -1.0), (0.0, 1.0, 0.0), 75.0, 0.3, 40.0)
    angles = np.linspace(0.0, 2.0 * np.pi, 9)[:-1] + 0.1
    x = np.concatenate([[0.0], 6.0 * np.cos(angles)])
    w = np.concatenate([[-1.5], 2.0 + 6.0 * np.sin(angles)])
    pos = _camera_frame(cam, np.stack([x, _plane_y(x, w), w], -1))
    faces = np.array([[0, 1 + i, 1 + (i + 1) % 8] for i in range(8)])
    width, height = 36, 28
    count, tri_id = _counts(Mesh(pos, faces), cam, width, height, spp)
    np.testing.assert_array_equal(tri_id >= 0, count > 0)
    n = int(round(spp**0.5))
    px, py = pixel_centres(width, height, n)
    d = region_distance(View.of(cam, width, height), pos, np.arange(1, 9)[None], px, py)
    d = d.reshape(count.shape)
    assert count.max() <= 1
    assert np.count_nonzero(d >= EPS) > 50
    np.testing.assert_array_equal(count[d >= EPS], 1)
    np.testing.assert_array_equal(count[d <= -EPS], 0)
