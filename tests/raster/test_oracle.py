"""Sanity tests of the float64 ray-cast oracle itself, against closed-form planes."""

from __future__ import annotations

import math

import numpy as np

from refnpr.raster import Camera

from .meshes import at_pixels
from .oracle import View, cast, derivatives, intersect, pixel_centres, region_distance, surface

W, H = 32, 24


def _axis_camera(fov=60.0, near=0.5, far=50.0) -> Camera:
    """Eye at the origin looking down -z with +y up: eye space equals world space."""
    return Camera.look_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), fov, near, far)


def _quad(corners) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(corners, dtype=np.float64), np.array([[0, 1, 2], [0, 2, 3]])


def test_rays_span_near_to_far_through_the_pixel():
    cam = _axis_camera(fov=90.0, near=0.5, far=50.0)
    view = View.of(cam, W, H)
    px, py = np.array([0.0, 16.0, 32.0, 8.5]), np.array([0.0, 12.0, 24.0, 3.25])
    o, d = view.rays(px, py)
    np.testing.assert_allclose(view.depth(o), 0.5, rtol=1e-14)
    np.testing.assert_allclose(view.depth(o + d), 50.0, rtol=1e-13)
    # tan(45 deg) = 1: eye-space direction (x_ndc * aspect, y_ndc, -1)
    x_ndc, y_ndc = 2 * px / W - 1, 1 - 2 * py / H
    expect = np.stack([x_ndc * W / H, y_ndc, -np.ones(4)], -1)
    np.testing.assert_allclose(d / -d[:, 2:], expect, rtol=1e-13, atol=1e-14)
    # the ray passes through the eye: origin is on the segment eye -> far point
    np.testing.assert_allclose(np.cross(o, d), 0.0, atol=1e-12)


def test_intersect_matches_a_hand_computed_hit():
    t, b = intersect(
        np.array([0.2, 0.3, 1.0]),
        np.array([0.0, 0.0, -2.0]),
        np.array([0.0, 0.0, 0.0]),
        np.array([1.0, 0.0, 0.0]),
        np.array([0.0, 1.0, 0.0]),
    )
    assert float(t) == 0.5
    np.testing.assert_allclose(b, [0.5, 0.2, 0.3], rtol=1e-15)


def test_fronto_parallel_plane_closed_form():
    """A plane z = -d: position, depth, ndc_z, uv and constant derivatives in closed form."""
    cam = _axis_camera(fov=60.0, near=0.5, far=50.0)
    view = View.of(cam, W, H)
    d = 3.0
    pos, faces = _quad([(-20, -20, -d), (20, -20, -d), (20, 20, -d), (-20, 20, -d)])
    uv = np.stack([0.25 * pos[:, 0] + 0.5, -0.75 * pos[:, 1] + 0.1], -1)
    px, py = (a.ravel() for a in pixel_centres(W, H))
    hits = cast(view, pos, faces, px, py)
    assert np.all(hits.tri >= 0)
    tan = math.tan(math.radians(30.0))
    x = (2 * px / W - 1) * (W / H) * tan * d
    y = (1 - 2 * py / H) * tan * d
    s = surface(view, pos, faces, hits.tri, px, py, {"uv": uv})
    np.testing.assert_allclose(s["position"], np.stack([x, y, np.full_like(x, -d)], -1), atol=1e-13)
    np.testing.assert_allclose(s["depth"], d, rtol=1e-14)
    p = cam.projection_matrix(W, H)
    np.testing.assert_allclose(s["ndc_z"], (p[2, 2] * -d + p[2, 3]) / d, rtol=1e-13)
    np.testing.assert_allclose(s["uv"], np.stack([0.25 * x + 0.5, -0.75 * y + 0.1], -1), atol=1e-13)
    assert np.all(s["bary"] >= -1e-15) and np.allclose(s["bary"].sum(-1), 1.0)
    der = derivatives(view, pos, faces, hits.tri, px, py, {"uv": uv})
    du_dx, du_dy = der["uv"]
    np.testing.assert_allclose(du_dx[:, 0], 0.25 * (2 / W) * (W / H) * tan * d, rtol=1e-10)
    np.testing.assert_allclose(du_dy[:, 1], -0.75 * (-2 / H) * tan * d, rtol=1e-10)
    np.testing.assert_allclose(du_dx[:, 1], 0.0, atol=1e-10)
    np.testing.assert_allclose(du_dy[:, 0], 0.0, atol=1e-10)


def test_floor_plane_perspective_derivatives_closed_form():
    """The floor y = -h below an eye looking at the horizon: depth = h / (tan * -y_ndc); the
    central-difference derivatives match the closed form to 1e-8 even half a pixel from the
    horizon (truncation O(h^4) there; rounding O(eps / h) on this 2000-unit quad)."""
    cam = _axis_camera(fov=60.0, near=0.1, far=1e4)
    view = View.of(cam, W, H)
    h = 1.5
    pos, faces = _quad([(-1e3, -h, 10.0), (1e3, -h, 10.0), (1e3, -h, -1e3), (-1e3, -h, -1e3)])
    uv = np.stack([pos[:, 0], pos[:, 2]], -1)
    px, py = (a.ravel() for a in pixel_centres(W, H))
    px, py = px[py > H / 2], py[py > H / 2]  # every row below the horizon
    hits = cast(view, pos, faces, px, py)
    assert np.all(hits.tri >= 0)
    tan = math.tan(math.radians(30.0))
    a = 2 * py / H - 1  # -y_ndc > 0
    w = h / (tan * a)
    dw_dy = -h / tan * (2 / H) / a**2
    x_ndc = 2 * px / W - 1
    s = surface(view, pos, faces, hits.tri, px, py, {"uv": uv})
    np.testing.assert_allclose(s["depth"], w, rtol=1e-12)
    np.testing.assert_allclose(s["uv"][:, 0], x_ndc * (W / H) * tan * w, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(s["uv"][:, 1], -w, rtol=1e-12)
    (du_dx, du_dy) = derivatives(view, pos, faces, hits.tri, px, py, {"uv": uv})["uv"]
    np.testing.assert_allclose(du_dx[:, 0], (2 / W) * (W / H) * tan * w, rtol=1e-8)
    np.testing.assert_allclose(du_dx[:, 1], 0.0, atol=1e-8)
    np.testing.assert_allclose(du_dy[:, 0], x_ndc * (W / H) * tan * dw_dy, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(du_dy[:, 1], -dw_dy, rtol=1e-8)


def test_nearest_hit_and_backface_culling():
    cam = _axis_camera()
    view = View.of(cam, W, H)
    near_quad = [(-9, -9, -2), (9, -9, -2), (9, 9, -2), (-9, 9, -2)]  # counter-clockwise: front
    far_quad = [(-9, -9, -3), (9, -9, -3), (9, 9, -3), (-9, 9, -3)]
    pos = np.array(near_quad[::-1] + far_quad, dtype=np.float64)  # the near quad faces away
    faces = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    px, py = (a.ravel() for a in pixel_centres(W, H))
    hits = cast(view, pos, faces, px, py)
    assert set(hits.tri[hits.clear]) == {0, 1}
    culled = cast(view, pos, faces, px, py, cull_backfaces=True)
    assert set(culled.tri[culled.clear]) == {2, 3}
    np.testing.assert_allclose(
        view.depth(surface(view, pos, faces, culled.tri, px, py)["position"]), 3
    )


def test_near_and_far_planes_bound_the_hits():
    """A floor from behind the eye to beyond the far plane: hits only at near <= depth <= far;
    the unhit rows are exactly those whose floor point lies outside [near, far]."""
    near, far, h = 2.0, 20.0, 1.0
    cam = _axis_camera(fov=60.0, near=near, far=far)
    view = View.of(cam, W, H)
    pos, faces = _quad([(-1e3, -h, 50.0), (1e3, -h, 50.0), (1e3, -h, -1e3), (-1e3, -h, -1e3)])
    px, py = (a.ravel() for a in pixel_centres(W, H))
    hits = cast(view, pos, faces, px, py)
    tan = math.tan(math.radians(30.0))
    a = 2 * py / H - 1
    with np.errstate(divide="ignore"):
        w = np.where(a > 0, h / (tan * a), np.inf)
    np.testing.assert_array_equal(hits.tri >= 0, (w >= near) & (w <= far))
    assert np.any(hits.tri >= 0) and np.any((hits.tri < 0) & (a > 0))


def test_region_distance_is_the_screen_distance_to_the_edges():
    """A triangle placed at known pixel positions (tilted in depth): the signed distance is the
    2D distance to the nearest edge, positive inside."""
    cam = Camera.look_at((0.3, 0.2, 2.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 50.0, 0.1, 100.0)
    view = View.of(cam, W, H)
    corners = at_pixels(
        view, np.array([4.0, 28.0, 4.0]), np.array([4.0, 4.0, 20.0]), [1.0, 3.0, 7.0]
    )
    faces = np.array([[0, 1, 2]])
    px = np.array([10.0, 5.0, 4.0, 2.0, 12.0, 10.0])
    py = np.array([10.0, 6.0, 12.0, 10.0, 14.0, 3.0])
    hyp = (px - 4.0) * 16.0 + (py - 4.0) * 24.0 - 24.0 * 16.0  # <= 0 inside, along the hypotenuse
    expect = np.minimum.reduce([px - 4.0, py - 4.0, -hyp / math.hypot(16.0, 24.0)])
    got = region_distance(view, corners, faces, px, py)[:, 0]
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-9)


def test_region_distance_agrees_with_ray_hits_for_clipped_triangles():
    """Two independent computations of 'the ray hits the triangle between near and far': the
    signed region distance (2D homogeneous lines) and the ray/triangle test. Triangles cross the near
    plane, the eye plane (w = 0) and lie partly or wholly behind the camera."""
    rng = np.random.default_rng(7)
    cam = Camera.look_at((0.0, 0.0, 0.0), (0.2, -0.1, -1.0), (0.0, 1.0, 0.0), 70.0, 0.5, 8.0)
    view = View.of(cam, W, H)
    fwd = cam.forward
    pos = rng.normal(scale=3.0, size=(60, 3)) + fwd * rng.uniform(-2.0, 6.0, size=(60, 1))
    right, up, _ = cam.basis()
    pos[:3] = [up, right - up, 5.0 * fwd - right]  # two vertices on the eye plane (w = 0)
    faces = np.arange(60).reshape(20, 3)
    px = rng.uniform(0, W, 3000)
    py = rng.uniform(0, H, 3000)
    dist = region_distance(view, pos, faces, px, py)
    o, d = view.rays(px, py)
    v = pos[faces]
    t, b = intersect(o[:, None], d[:, None], v[None, :, 0], v[None, :, 1], v[None, :, 2])
    hit = np.all(b >= 0, axis=-1) & (t >= 0) & (t <= 1)
    sure = np.abs(dist) > 1e-7
    np.testing.assert_array_equal(hit[sure], dist[sure] > 0)
    assert 0.05 < hit.mean() < 0.95 and sure.mean() > 0.99


def test_polygon_region_is_the_union_of_its_triangles():
    """A planar convex quad crossing the near plane and the eye plane: its region (four edges,
    near, far) is the union of the regions of the two triangles sharing its diagonal."""
    cam = Camera.look_at((0.0, 0.0, 0.0), (0.1, -0.2, -1.0), (0.0, 1.0, 0.0), 70.0, 0.5, 6.0)
    view = View.of(cam, W, H)
    right, up, back = cam.basis()
    xyw = np.array([(-3.0, -1.0, -2.0), (3.0, -1.2, -1.0), (2.0, -0.8, 7.0), (-2.5, -1.1, 8.0)])
    xyw[:, 1] = -1.0 + 0.05 * xyw[:, 0] + 0.1 * xyw[:, 2]  # planar
    quad = xyw[:, :1] * right + xyw[:, 1:2] * up - xyw[:, 2:3] * back
    rng = np.random.default_rng(3)
    px, py = rng.uniform(0, W, 4000), rng.uniform(0, H, 4000)
    poly = region_distance(view, quad, np.array([[0, 1, 2, 3]]), px, py)[:, 0]
    tris = region_distance(view, quad, np.array([[0, 1, 2], [0, 2, 3]]), px, py)
    sure = (np.abs(poly) > 1e-7) & np.all(np.abs(tris) > 1e-7, axis=1)
    np.testing.assert_array_equal(poly[sure] > 0, np.any(tris[sure] > 0, axis=1))
    assert 0.1 < np.mean(poly > 0) < 0.9 and sure.mean() > 0.99


def test_edge_on_triangle_is_never_hit_and_its_line_is_ambiguous():
    """A triangle whose plane contains the eye (one edge lies on the view axis) projects to a
    line: rays in that plane must not report spurious hits (the intersection is 0/0 there), and
    the pixels on the line are ambiguous (the rasterizer may cover a snapped sliver)."""
    cam = Camera.look_at((0.0, 0.0, 1.0), (0.0, 0.75, 2.0), (1.0, 0.0, 0.0), 5.0, 3.16, 316.0)
    pos = np.array([[0.0, 0.6, 1.8], [0.43660943, 6.0, 9.0], [0.0, 6.0, 9.0]])
    view = View.of(cam, 1, 2)
    px, py = (a.ravel() for a in pixel_centres(1, 2))
    hits = cast(view, pos, np.array([[0, 1, 2]]), px, py)
    np.testing.assert_array_equal(hits.tri, -1)
    assert hits.ambiguous.all()
    view = View.of(cam, 9, 4)  # the line is the image's middle column
    px, py = (a.ravel() for a in pixel_centres(9, 4))
    hits = cast(view, pos, np.array([[0, 1, 2]]), px, py)
    np.testing.assert_array_equal(hits.ambiguous, np.abs(px - 4.5) < 1e-9)


def test_triangle_lying_in_the_near_plane_is_ambiguous():
    """Whether a triangle in the near plane is clipped away is decided by rounding (in the
    rasterizer and the oracle alike): its hits are ambiguous, not clear."""
    cam = _axis_camera(fov=60.0, near=1.0, far=10.0)
    view = View.of(cam, W, H)
    pos = np.array([(-9.0, -5.0, -1.0), (9.0, -5.0, -1.0), (0.0, 9.0, -1.0)])
    faces = np.array([[0, 1, 2]])
    px, py = (a.ravel() for a in pixel_centres(W, H))
    assert cast(view, pos, faces, px, py).ambiguous.all()
    behind_near = cast(view, pos - [0, 0, 1e-6], faces, px, py)
    assert not behind_near.ambiguous.any() and np.all(behind_near.tri == 0)
