"""X-Toon optical flow in sequences (sec. 5): ``XToonStyle.for_frame`` takes the previous frame's
camera and object transforms, so the flow of a vertex is its screen position now minus that of
its object-space position through the previous transform and camera. Oracles: projections by
hand with the camera matrices, the analytic displacement of a translating object, and the
previous ``prev_camera``-only behaviour for camera motion."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import Camera, rasterize
from refnpr.scenes import Light, Scene, SceneObject, transform_matrix, uv_sphere
from refnpr.styles.base import ShadeContext
from refnpr.styles.xtoon import XToonStyle

W, H = 80, 60
CAM = Camera.look_at((0.0, 1.0, 8.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 0.5, 30.0)
CAM_PREV = Camera.look_at((0.6, 1.2, 8.0), (0.2, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 0.5, 30.0)
MOVER = uv_sphere(1.0, 24, 12)
STILL = uv_sphere(0.8, 16, 8)


def frame_scene(x_mover: float, camera: Camera = CAM) -> Scene:
    """A sphere ("mover") at x = ``x_mover`` beside a still one, lit from the upper left."""
    objs = (
        SceneObject(MOVER, transform_matrix(translate=(x_mover, 0.0, 0.0)), name="mover"),
        SceneObject(STILL, transform_matrix(translate=(0.0, 0.3, -3.0)), name="still"),
    )
    return Scene(objs, camera, lights=(Light(direction=(-0.5, 0.8, 0.6)),), name="flow")


def pixel_by_hand(point, camera: Camera) -> np.ndarray:
    """x right, y down, pixel centres at +0.5, from the 4x4 projection @ view matrices."""
    clip = camera.projection_matrix(W, H) @ camera.view_matrix() @ np.append(point, 1.0)
    ndc = clip[:3] / clip[3]
    return np.array([(ndc[0] + 1.0) * 0.5 * W, (1.0 - ndc[1]) * 0.5 * H])


def vertex_flow(style: XToonStyle, scene: Scene) -> list[np.ndarray]:
    return [a["xtoon_flow"] for a in style.vertex_attributes(scene, width=W, height=H)]


def test_translating_object_has_the_analytic_vertex_flow():
    prev, now = frame_scene(-1.0), frame_scene(-0.4)  # 0.6 units to the right in one frame
    style = XToonStyle(detail="flow", detail_mode="vertex").for_frame(now, prev)
    mover, still = vertex_flow(style, now)
    assert np.all(still == 0.0)  # still object, still camera: no motion at all
    for i in range(0, MOVER.n_vertices, 7):
        p = MOVER.positions[i]
        want = pixel_by_hand(p + (-0.4, 0, 0), CAM) - pixel_by_hand(p + (-1.0, 0, 0), CAM)
        np.testing.assert_allclose(mover[i], want, rtol=1e-9, atol=1e-9)
    assert np.all(mover[:, 0] > 0.0)  # to the right on screen


def test_translating_object_flow_per_pixel():
    """Per pixel: D of each covered sample from its G-buffer position, moved back by the
    translation (mover) or left in place (still), projected by hand."""
    prev, now = frame_scene(-1.0), frame_scene(-0.4)
    style = XToonStyle(detail="flow", flow_min=1.0, flow_max=6.0).for_frame(now, prev)
    gb = rasterize(now, now.camera, W, H, style.requires(now), 1)
    detail = style.fields(ShadeContext(gb, now))["detail"]
    mesh_id, pos = gb["mesh_id"], gb["position"].astype(np.float64)
    ys, xs = np.nonzero(mesh_id >= 0)
    assert np.any(mesh_id == 0) and np.any(mesh_id == 1)
    for y, x in list(zip(ys, xs, strict=True))[::5]:
        p = pos[y, x]
        before = p - (0.6, 0.0, 0.0) if mesh_id[y, x] == 0 else p
        f = pixel_by_hand(p, CAM) - pixel_by_hand(before, CAM)
        want = 1.0 - np.clip((np.hypot(*f) - 1.0) / 5.0, 0.0, 1.0)
        assert detail[y, x] == pytest.approx(want, abs=1e-6), (y, x)
    assert np.all(detail[mesh_id == 1] == 1.0)
    assert np.all(detail[mesh_id == 0] < 1.0)  # 0.6 units is several pixels here


def test_camera_only_motion_matches_prev_camera():
    """Still objects, moving camera: for_frame gives what an explicit prev_camera gave."""
    prev, now = frame_scene(-0.4, CAM_PREV), frame_scene(-0.4)
    old = XToonStyle(detail="flow", prev_camera=CAM_PREV, detail_mode="vertex")
    new = XToonStyle(detail="flow", detail_mode="vertex").for_frame(now, prev)
    for mode in ("pixel", "vertex"):
        a = XToonStyle(detail="flow", prev_camera=CAM_PREV, flow_max=8.0, detail_mode=mode)
        b = XToonStyle(detail="flow", flow_max=8.0, detail_mode=mode).for_frame(now, prev)
        gb = rasterize(now, now.camera, W, H, a.requires(now), 1)
        ctx = ShadeContext(gb, now)
        assert np.array_equal(a.shade(ctx), b.shade(ctx))
    for fa, fb in zip(vertex_flow(old, now), vertex_flow(new, now), strict=True):
        assert np.array_equal(fa, fb)


def test_first_frame_has_zero_flow():
    now = frame_scene(-0.4)
    style = XToonStyle(detail="flow", texture="loa_receding", detail_mode="vertex")
    style = style.for_frame(now, None)
    full = XToonStyle(detail="none", texture="loa_receding")  # D = 1: no motion
    still = XToonStyle(detail="flow", texture="loa_receding")  # a still: frame 0 as well
    channels = style.requires(now) | full.requires(now) | still.requires(now)
    ctx = ShadeContext(rasterize(now, now.camera, W, H, channels, 1), now)
    assert np.array_equal(style.shade(ctx), full.shade(ctx))
    assert np.array_equal(still.shade(ctx), full.shade(ctx))
    assert all(np.all(f == 0.0) for f in vertex_flow(style, now))


def test_explicit_parameters_win():
    prev, now = frame_scene(-1.0, CAM_PREV), frame_scene(-0.4)
    given = XToonStyle(detail="flow", prev_camera=CAM, prev_transforms=[np.eye(4)] * 2)
    assert given.for_frame(now, prev) is given
    depth = XToonStyle(detail="depth")
    assert depth.for_frame(now, prev) is depth
    cam_only = XToonStyle(detail="flow", prev_camera=CAM, detail_mode="vertex")
    cam_only = cam_only.for_frame(now, prev)
    assert cam_only.params()["prev_camera"]["eye"] == list(CAM.eye)
    mover, _ = vertex_flow(cam_only, now)  # the still camera with the object's motion
    p = MOVER.positions[3]
    want = pixel_by_hand(p + (-0.4, 0, 0), CAM) - pixel_by_hand(p + (-1.0, 0, 0), CAM)
    np.testing.assert_allclose(mover[3], want, rtol=1e-9, atol=1e-9)


def test_prev_transforms_are_checked():
    now = frame_scene(-0.4)
    style = XToonStyle(detail="flow", prev_transforms=[np.eye(4)] * 3)
    gb = rasterize(now, now.camera, W, H, style.requires(now), 1)
    with pytest.raises(ValueError, match="prev_transforms: got 3 transforms but the scene has 2"):
        style.shade(ShadeContext(gb, now))
    with pytest.raises(ValueError, match="prev_transforms: expected one 4x4 matrix"):
        XToonStyle(detail="flow", prev_transforms="identity")
    with pytest.raises(ValueError, match=r"prev_transforms\[1\]: the last row"):
        XToonStyle(detail="flow", prev_transforms=[np.eye(4), np.ones((4, 4))])
    with pytest.warns(UserWarning, match="(?s)prev_transforms: .* is ignored with detail='depth'"):
        XToonStyle(detail="depth", prev_transforms=[np.eye(4)])
    one = Scene(now.objects[:1], CAM, lights=now.lights)
    with pytest.raises(ValueError, match="prev_scene: has 1 objects but the frame's scene has 2"):
        XToonStyle(detail="flow").for_frame(now, one)
