"""The exact motion field and its valid mask, against hand projections in float64."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from refnpr.coherence import MOTION_CHANNELS, motion_field
from refnpr.raster import rasterize
from refnpr.scenes import SceneObject, icosphere, plane, transform_matrix

from .fixtures import EYE, H, W, camera, hit_plane, pixel_size, project, quad, scene, wall


def gbuf(sc, channels=MOTION_CHANNELS, spp=1, dtype=np.float64, width=W, height=H):
    return rasterize(sc, None, width, height, channels, spp, dtype=dtype)


def field(sc_now, sc_prev, **kw):
    return motion_field(gbuf(sc_now), gbuf(sc_prev), sc_now, sc_prev, **kw)


def test_static_scene_maps_every_covered_pixel_onto_itself():
    sc = scene(
        [
            wall(tz=-1.0),
            SceneObject(icosphere(2, 1.0), transform_matrix((0.3, -0.2, 0.5))),
        ]
    )
    mf = field(sc, sc)
    ys, xs = np.mgrid[0:H, 0:W] + 0.5
    assert mf.covered.all()
    assert np.array_equal(mf.valid, mf.covered)  # nothing occluded, nothing outside
    assert np.array_equal(mf.xy[..., 0], xs) and np.array_equal(mf.xy[..., 1], ys)  # snapped
    assert np.all(mf.weights[0][mf.valid] == 1.0)  # one tap, the pixel itself
    assert np.array_equal(mf.taps[0], (ys - 0.5) * W + (xs - 0.5))


@pytest.mark.parametrize(
    "move",
    [
        dict(translate=(0.061, 0.0, 0.0), rot=(90.0, 0.0, 0.0)),  # frontal, sub-pixel along x
        dict(translate=(0.11, -0.07, 0.4), rot=(70.0, 25.0, 0.0)),  # slanted, towards the eye
    ],
)
def test_object_motion_equals_the_hand_projection(move):
    rot = move["rot"]
    t = np.asarray(move["translate"])
    before = scene([wall(rot=rot)])
    after = scene([wall(*t, rot=rot)])
    mf = field(after, before)
    # oracle: ray through each pixel centre meets the plane at frame t, the point moves back
    # by -t (pure translation), and is projected by hand with the same fixed camera
    normal = transform_matrix(rotate_deg=rot)[:3, :3] @ np.array([0.0, 1.0, 0.0])
    p_now = hit_plane(t, normal)
    xy, w = project((p_now - t).reshape(-1, 3))
    xy, w = xy.reshape(H, W, 2), w.reshape(H, W)
    m = mf.covered
    assert m.sum() > 0.9 * W * H
    np.testing.assert_allclose(mf.xy[m], xy[m], atol=1e-6)
    np.testing.assert_allclose(mf.w[m], w[m], rtol=1e-9)
    inside = (xy[..., 0] >= 0) & (xy[..., 0] < W) & (xy[..., 1] >= 0) & (xy[..., 1] < H)
    assert np.array_equal(mf.inside[m], inside[m])
    # one surface, no occlusion: every point that lands in the frame is compared
    assert np.array_equal(mf.valid, m & inside)


def test_frontal_translation_is_a_uniform_pixel_shift():
    dx = 0.061
    mf = field(scene([wall(dx)]), scene([wall()]))
    shift = dx / pixel_size(EYE[2])  # the plane is at view distance 5
    flow = mf.flow()[mf.covered]
    np.testing.assert_allclose(flow[:, 0], -shift, atol=1e-9)
    np.testing.assert_allclose(flow[:, 1], 0.0, atol=1e-9)
    # the first column lands left of the image (shift < 1 px): outside, hence not valid
    assert shift < 1.0
    assert not mf.valid[:, 0].any() and mf.valid[:, 1:].all()


@pytest.mark.parametrize("yaw", [2.5, -4.0])
def test_camera_pan_equals_the_hand_projection(yaw):
    sc_prev = scene([wall(size=40.0)], camera(0.0))
    sc_now = scene([wall(size=40.0)], camera(yaw))
    mf = field(sc_now, sc_prev)
    p = hit_plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), yaw_deg=yaw)
    xy, w = project(p.reshape(-1, 3), yaw_deg=0.0)
    xy, w = xy.reshape(H, W, 2), w.reshape(H, W)
    assert mf.covered.all()
    np.testing.assert_allclose(mf.xy, xy, atol=1e-6)
    np.testing.assert_allclose(mf.w, w, rtol=1e-9)
    inside = (xy[..., 0] >= 0) & (xy[..., 0] < W) & (xy[..., 1] >= 0) & (xy[..., 1] < H)
    # a band enters from the side the camera turns to (with a keystone: its corners reach
    # above and below the previous frame)
    assert 0 < (~inside).sum() < W * H // 4
    assert (xy[..., 1] < 0).any()
    assert np.array_equal(mf.valid, inside)


def _occluder(shift_px):
    """Background wall at z = 0 and a rectangle at z = 2 spanning pixels [20.2, 31.1] x [15.3,
    24.8] in frame t-1, moved right by ``shift_px`` pixels in frame t (camera fixed)."""
    w = EYE[2] - 2.0
    s = pixel_size(w)
    f = 1.0 / math.tan(math.radians(22.5))

    def world_x(px):  # pixel x -> world x at view distance w
        return ((2 * px / W) - 1) * w * (W / H) / f

    def world_y(py):
        return (1 - 2 * py / H) * w / f

    box = (world_x(20.2), world_x(31.1), world_y(24.8), world_y(15.3))
    prev = scene([wall(size=40.0), quad(*box, 2.0)])
    now = scene([wall(size=40.0), quad(*box, 2.0, dx=shift_px * s)])
    return now, prev


def _expected_valid(shift_px):
    """Hand-computed M: background pixels are valid unless their centre was behind the
    rectangle at t-1; rectangle pixels unless a weighted bilinear tap of their landing point
    (centre - shift) falls off the rectangle at t-1."""

    def in_prev(cx, cy):
        return 20.2 < cx < 31.1 and 15.3 < cy < 24.8

    def in_now(cx, cy):
        return 20.2 + shift_px < cx < 31.1 + shift_px and 15.3 < cy < 24.8

    valid = np.zeros((H, W), bool)
    for j in range(H):
        for i in range(W):
            cx, cy = i + 0.5, j + 0.5
            if not in_now(cx, cy):
                valid[j, i] = not in_prev(cx, cy)
                continue
            lx = cx - shift_px - 0.5  # landing point in pixel-index space
            x0 = math.floor(lx)
            fx = lx - x0
            cols = [x0] + ([x0 + 1] if fx > 0 else [])
            valid[j, i] = all(in_prev(c + 0.5, cy) for c in cols)
    return valid


@pytest.mark.parametrize("shift_px", [3.0, 2.5])
def test_occluder_masks_exactly_the_pixels_it_disoccludes(shift_px):
    now, prev = _occluder(shift_px)
    mf = field(now, prev)
    expected = _expected_valid(shift_px)
    assert mf.covered.all()
    assert np.array_equal(mf.valid, expected), np.argwhere(mf.valid != expected)[:10]
    # the disoccluded strip: rows 15-24, columns 20-22 (centres behind the rectangle at t-1
    # and not at t); with a half-pixel shift also the rectangle's right column, whose landing
    # point straddles its right edge at t-1
    hole = np.argwhere(~mf.valid)
    cols = sorted(set(hole[:, 1]))
    assert sorted(set(hole[:, 0])) == list(range(15, 25))
    assert cols == ([20, 21, 22] if shift_px == 3.0 else [20, 21, 22, 33])


def test_depth_test_tolerance_on_the_previous_depth():
    sc = scene([wall(size=40.0)])
    gb = gbuf(sc)
    depth = gb["depth"].copy()
    depth[10:20, 10:20] *= 0.97  # something 3 % nearer: an occluder
    depth[30:40, 30:40] *= 0.995  # 0.5 % nearer: within the default 1 % tolerance
    prev = dataclasses.replace(gb, channels={**gb.channels, "depth": depth})
    mf = motion_field(gb, prev, sc, sc)
    expected = np.ones((H, W), bool)
    expected[10:20, 10:20] = False
    assert np.array_equal(mf.valid, expected)
    tight = motion_field(gb, prev, sc, sc, depth_rtol=1e-3)
    expected[30:40, 30:40] = False
    assert np.array_equal(tight.valid, expected)


def test_grazing_floor_passes_the_plane_depth_test():
    # a floor seen at a grazing angle, the camera moving forward: the depth changes by far more
    # than 1 % per pixel, yet every point that lands in the frame is on the same surface
    floor = SceneObject(plane(60.0, 60.0, tile=0.5), name="floor")
    from refnpr.raster import Camera

    def cam(z):
        return Camera.look_at((0.0, 0.4, z), (0.0, 0.0, z - 10.0), (0, 1, 0), 45.0)

    prev, now = scene([floor], cam(0.0)), scene([floor], cam(-0.05))
    mf = field(now, prev)
    on_floor = gbuf(prev)["mesh_id"] >= 0
    # hand-computed: a point is comparable when it lands in the frame and every bilinear tap
    # with a non-zero weight shows the floor at t-1 (the top rows land next to the horizon)
    expected = np.zeros((H, W), bool)
    for j, i in np.argwhere(mf.covered & mf.inside & mf.in_front):
        lx, ly = mf.xy[j, i] - 0.5
        x0, y0 = math.floor(lx), math.floor(ly)
        cols = [x0] + ([x0 + 1] if lx > x0 else [])
        rows = [y0] + ([y0 + 1] if ly > y0 else [])
        expected[j, i] = all(
            on_floor[min(max(r, 0), H - 1), min(max(c, 0), W - 1)] for r in rows for c in cols
        )
    assert mf.covered.sum() > 0.4 * W * H
    assert expected.sum() > 0.9 * mf.covered.sum()
    assert np.array_equal(mf.valid, expected)
    # a constant-depth test at the landing pixel's neighbours would fail here: the depth of the
    # previous frame changes by more than the tolerance between vertically adjacent pixels
    d = np.where(on_floor, gbuf(prev)["depth"], 1.0)
    both = on_floor[1:] & on_floor[:-1]
    assert (np.abs(d[1:] - d[:-1]) / d[1:])[both].max() > 0.01


# -- bad input ----------------------------------------------------------------------------
def test_mismatched_sizes_are_an_error():
    sc = scene([wall()])
    with pytest.raises(ValueError, match=r"prev_gb: is 40 x 30, gb is 80 x 60"):
        motion_field(gbuf(sc), gbuf(sc, width=40, height=30), sc, sc)


def test_missing_position_is_an_error():
    sc = scene([wall()])
    gb = gbuf(sc, channels=("depth", "mesh_id"))
    with pytest.raises(ValueError, match=r"gb: lacks channels \['position'"):
        motion_field(gb, gbuf(sc), sc, sc)
    with pytest.raises(ValueError, match=r"prev_gb: lacks channels \['depth'\]"):
        motion_field(gbuf(sc), gbuf(sc, channels=("position", "mesh_id")), sc, sc)


def test_supersampled_gbuffer_is_an_error():
    sc = scene([wall()])
    with pytest.raises(ValueError, match=r"gb: expected a pixel-resolution G-buffer \(spp 1\)"):
        motion_field(gbuf(sc, spp=4), gbuf(sc), sc, sc)


def test_different_object_count_is_an_error():
    one = scene([wall()])
    two = scene([wall(), SceneObject(icosphere(1, 0.5))])
    with pytest.raises(ValueError, match=r"prev_scene: has 2 objects, scene has 1"):
        motion_field(gbuf(one), gbuf(two), one, two)


def test_different_mesh_is_an_error():
    a = scene([SceneObject(icosphere(1, 0.5))])
    b = scene([SceneObject(icosphere(2, 0.5))])
    with pytest.raises(ValueError, match=r"prev_scene: object 0 .* different mesh"):
        motion_field(gbuf(a), gbuf(b), a, b)


@pytest.mark.parametrize("bad", [0.0, 1.5, -0.1])
def test_bad_depth_rtol_is_an_error(bad):
    sc = scene([wall()])
    with pytest.raises(ValueError, match=r"depth_rtol: expected a tolerance in \(0, 1\)"):
        motion_field(gbuf(sc), gbuf(sc), sc, sc, depth_rtol=bad)


def test_not_a_gbuffer_is_a_type_error():
    sc = scene([wall()])
    with pytest.raises(TypeError, match=r"gb: expected a refnpr.raster.GBuffer"):
        motion_field({"position": 1}, gbuf(sc), sc, sc)
