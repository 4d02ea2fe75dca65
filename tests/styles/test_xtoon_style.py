"""X-Toon style (Barla et al. 2006): attribute maps against independent oracles, the per-vertex
mode against naive loops, texture orientation and alpha, shape abstraction, channel sets and
parameter errors."""

from __future__ import annotations

import math

import imageio.v3 as iio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.formulas import xtoon as fx
from refnpr.raster import Camera, rasterize
from refnpr.render import render, required_channels
from refnpr.scenes import Light, Scene, SceneObject, load_scene, plane, transform_matrix, uv_sphere
from refnpr.styles import get_style, list_styles, style_from_spec
from refnpr.styles.base import ShadeContext
from refnpr.styles.xtoon import XToonStyle, abstract_normals, resolve_texture

W, H = 64, 48
EYE = (0.0, 2.0, 3.0)
TARGET = (0.0, 0.0, -6.0)
FOV = 50.0
LIGHT = (0.3, 1.0, 0.4)


def floor_scene(segments: int = 1, light=LIGHT, camera=None) -> Scene:
    """A receding floor y = 0, z in [-16, 0], seen from above: depth spans ~[2.2, 19]."""
    mesh = plane(width=16.0, depth=16.0, segments=segments)
    obj = SceneObject(mesh, transform_matrix(translate=(0.0, 0.0, -8.0)), name="floor")
    cam = camera or Camera.look_at(EYE, TARGET, (0.0, 1.0, 0.0), FOV, 0.1, 100.0)
    return Scene((obj,), cam, lights=(Light(direction=light),), name="floor")


def sphere_scene(n_u: int = 48, n_v: int = 24) -> Scene:
    cam = Camera.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 0.5, 20.0)
    obj = SceneObject(uv_sphere(1.0, n_u, n_v), name="ball")
    return Scene((obj,), cam, lights=(Light(direction=(1.0, 1.0, 1.0)),), name="ball")


def context(scene: Scene, style: XToonStyle, w: int = W, h: int = H, spp: int = 1):
    gb = rasterize(scene, scene.camera, w, h, sorted(style.requires(scene)), spp)
    return ShadeContext(gb, scene)


def floor_rays(scene: Scene, w: int = W, h: int = H):
    """Float64 ray cast of the floor y = 0 through every pixel centre, independent of the
    rasterizer: hit points (H, W, 3) and a mask of pixels that see the floor."""
    cam = scene.camera
    f = np.subtract(cam.target, cam.eye)
    f /= np.linalg.norm(f)
    right = np.cross(f, cam.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    t = math.tan(math.radians(cam.fov_y) / 2)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    ndc_x, ndc_y = 2 * xs / w - 1, 1 - 2 * ys / h
    d = f + (ndc_x * t * w / h)[..., None] * right + (ndc_y * t)[..., None] * up
    s = -cam.eye[1] / d[..., 1]
    p = cam.eye + s[..., None] * d
    inside = (
        (s > 0) & (np.abs(p[..., 0]) < 8 - 1e-3) & (p[..., 2] > -16 + 1e-3) & (p[..., 2] < -1e-3)
    )
    return p, s, inside  # s = view-axis distance since dot(d, f) = 1


def interior(mask: np.ndarray) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood is all inside (away from silhouettes)."""
    m = mask.copy()
    m[1:-1, 1:-1] = (
        mask[1:-1, 1:-1] & mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2] & mask[1:-1, 2:]
    )
    m[[0, -1], :] = False
    m[:, [0, -1]] = False
    return m


# --- registration and channels -----------------------------------------------------------------


def test_registered_with_description():
    assert "xtoon" in list_styles()
    assert isinstance(get_style("xtoon"), XToonStyle)


@pytest.mark.parametrize(
    ("params", "expected"),
    [
        ({}, {"mesh_id", "normal", "depth"}),
        ({"detail": "focus", "focus_point": [0, 0, -5]}, {"mesh_id", "normal", "position"}),
        ({"detail": "orientation"}, {"mesh_id", "normal", "position"}),
        ({"detail": "highlight"}, {"mesh_id", "normal", "position"}),
        (
            {"detail": "flow", "prev_camera": {"eye": [1, 2, 3], "target": [0, 0, -6]}},
            {"mesh_id", "normal", "position"},
        ),
        ({"detail": "map", "detail_map": np.ones((H, W))}, {"mesh_id", "normal"}),
        ({"detail": "none"}, {"mesh_id", "normal"}),
        ({"detail_mode": "vertex"}, {"mesh_id", "normal", "tri_id", "bary"}),
        (
            {"detail": "orientation", "detail_mode": "vertex"},
            {"mesh_id", "normal", "tri_id", "bary"},
        ),
        ({"detail": "none", "shape": "sphere"}, {"mesh_id", "tri_id", "bary"}),
        (
            {"detail": "none", "shape": "sphere", "shape_blend": "pixel"},
            {"mesh_id", "normal", "tri_id", "bary"},
        ),
        (
            {
                "shape": "sphere",
                "shape_blend": "pixel",
                "shape_weight": {"texture": "checkerboard"},
            },
            {"mesh_id", "normal", "depth", "tri_id", "bary", "uv"},
        ),
        ({"detail": "none", "shape": "sphere", "shape_weight": "detail"}, None),
    ],
)
def test_required_channels_are_exactly_what_the_map_needs(params, expected):
    scene = floor_scene()
    if expected is None:  # "detail" weight with detail "none" cannot give D per vertex
        with pytest.raises(ValueError, match="shape_weight: 'detail' with shape_blend='vertex'"):
            get_style("xtoon", **params)
        return
    style = get_style("xtoon", **params)
    got = required_channels(scene, style)
    assert got == frozenset(expected)
    assert not any(c.startswith("d") and c.endswith(("_dx", "_dy")) for c in got)


def test_point_light_needs_positions_for_the_tone():
    scene = floor_scene()
    scene = Scene(scene.objects, scene.camera, lights=(Light(kind="point", position=(0, 5, -4)),))
    assert "position" in required_channels(scene, get_style("xtoon"))


# --- attribute maps against independent oracles ----------------------------------------------


def _oracle_depth(z, z_min, r):
    return np.clip(1.0 - np.log(z / z_min) / math.log(r), 0.0, 1.0)  # X-Toon sec. 3.1


def test_depth_detail_is_log_of_view_axis_distance():
    scene = floor_scene()
    style = get_style("xtoon", z_min=4.0, r=3.0)
    ctx = context(scene, style)
    got = style.fields(ctx)["detail"]
    _, z, inside = floor_rays(scene)
    ok = interior(inside)
    np.testing.assert_allclose(got[ok], _oracle_depth(z[ok], 4.0, 3.0), atol=2e-6)
    assert got[ok].min() == 0.0 and got[ok].max() == 1.0  # the plane spans the whole range
    empty = ctx.gb["mesh_id"] < 0
    assert empty.any() and np.all(np.isnan(got[empty]))


def test_depth_defaults_come_from_the_scene_box():
    scene = floor_scene()
    style = get_style("xtoon")
    got = style.fields(context(scene, style))["detail"]
    lo, hi = scene.bounds()
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    f = scene.camera.forward
    depth = (corners - scene.camera.eye) @ f
    z_min = max(depth.min(), scene.camera.near)
    _, z, inside = floor_rays(scene)
    ok = interior(inside)
    np.testing.assert_allclose(got[ok], _oracle_depth(z[ok], z_min, depth.max() / z_min), atol=2e-6)


def _oracle_focus(z, z_c, z_min, r):
    # X-Toon sec. 3.1, the two printed branches with z^-+ = z_c -+ z_min, z_max^-+ = z_c -+ r z_min
    near = 1.0 - np.log(z / (z_c - z_min)) / np.log((z_c - r * z_min) / (z_c - z_min))
    far = np.log(z / (z_c + r * z_min)) / np.log((z_c + z_min) / (z_c + r * z_min))
    return np.clip(np.where(z < z_c, near, far), 0.0, 1.0)


def test_focus_detail_uses_euclidean_distance_to_the_eye():
    scene = floor_scene()
    c = (0.5, 0.0, -6.0)
    style = get_style("xtoon", detail="focus", focus_point=c, z_min=1.0, r=3.0)
    got = style.fields(context(scene, style))["detail"]
    p, _, inside = floor_rays(scene)
    ok = interior(inside)
    eye = np.asarray(EYE)
    z = np.linalg.norm(p - eye, axis=-1)
    z_c = float(np.linalg.norm(np.asarray(c) - eye))
    np.testing.assert_allclose(got[ok], _oracle_focus(z[ok], z_c, 1.0, 3.0), atol=1e-5)
    assert got[ok].max() == 1.0 and got[ok].min() == 0.0


def test_orientation_and_highlight_details():
    scene = floor_scene()
    p, _, inside = floor_rays(scene)
    ok = interior(inside)
    v = np.asarray(EYE) - p
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    n = np.array([0.0, 1.0, 0.0])
    style = get_style("xtoon", detail="orientation", r=2.5)
    got = style.fields(context(scene, style))["detail"]
    np.testing.assert_allclose(got[ok], np.abs(v[ok] @ n) ** 2.5, atol=1e-5)  # |n.v|^r
    light = np.asarray(LIGHT) / np.linalg.norm(LIGHT)
    refl = 2 * (n @ light) * n - light
    for one_sided, base in ((False, np.abs(v @ refl)), (True, np.maximum(v @ refl, 0.0))):
        style = get_style("xtoon", detail="highlight", s=5.0, one_sided=one_sided)
        got = style.fields(context(scene, style))["detail"]
        np.testing.assert_allclose(got[ok], base[ok] ** 5.0, atol=1e-5)  # |v.r|^s


def test_flow_detail_from_the_previous_camera():
    scene = floor_scene()
    prev = Camera.look_at((0.4, 2.3, 3.0), TARGET, (0.0, 1.0, 0.0), FOV, 0.1, 100.0)
    table = {"eye": [0.4, 2.3, 3.0], "target": list(TARGET), "fov_y": FOV}
    style = get_style("xtoon", detail="flow", prev_camera=table, flow_min=1.0, flow_max=5.0)
    got = style.fields(context(scene, style))["detail"]
    p, _, inside = floor_rays(scene)
    ok = interior(inside)
    clip = np.c_[p[ok], np.ones(ok.sum())] @ prev.view_projection(W, H).T
    px = (clip[:, 0] / clip[:, 3] + 1) * W / 2
    py = (1 - clip[:, 1] / clip[:, 3]) * H / 2
    ys, xs = np.nonzero(ok)
    length = np.hypot(xs + 0.5 - px, ys + 0.5 - py)
    expect = 1 - np.clip((length - 1.0) / 4.0, 0, 1)
    np.testing.assert_allclose(got[ok], expect, atol=1e-4)
    assert got[ok].min() < 0.5 < got[ok].max()
    same = get_style("xtoon", detail="flow", prev_camera=scene.camera)
    assert np.all(same.fields(context(scene, same))["detail"][ok] == 1.0)


def test_user_map_per_pixel_is_repeated_over_samples():
    scene = floor_scene()
    rng = np.random.default_rng(3)
    m = rng.uniform(0, 1, (H, W))
    style = get_style("xtoon", detail="map", detail_map=m)
    got = style.fields(context(scene, style, spp=4))["detail"]
    covered = np.isfinite(got)
    expect = np.repeat(np.repeat(m, 2, axis=0), 2, axis=1)
    np.testing.assert_allclose(got[covered], expect[covered], atol=1e-7)
    with pytest.raises(ValueError, match=r"detail_map: map of shape \(48, 64\) does not match"):
        style.fields(context(scene, style, w=32, h=24))


@settings(max_examples=12)
@given(z_min=st.floats(1.0, 12.0), r=st.floats(1.05, 20.0))
def test_depth_detail_property_range_and_oracle(z_min, r):
    scene = floor_scene()
    style = get_style("xtoon", z_min=z_min, r=r)
    got = style.fields(context(scene, style))["detail"]
    _, z, inside = floor_rays(scene)
    ok = interior(inside)
    assert np.all((got[ok] >= 0) & (got[ok] <= 1))
    np.testing.assert_allclose(got[ok], _oracle_depth(z[ok], z_min, r), atol=5e-6)


# --- per-vertex mode ---------------------------------------------------------------------------


def test_vertex_mode_is_the_interpolated_per_vertex_detail():
    scene = floor_scene(segments=3)
    style = get_style("xtoon", detail_mode="vertex", z_min=4.0, r=3.0)
    ctx = context(scene, style)
    got = style.fields(ctx)["detail"]
    mesh = scene.world_meshes()[0]
    view = scene.camera.view_matrix()
    d_vertex = []
    for x, y, z in mesh.positions:  # naive loop: the paper's vertex shader
        depth = -(view[2, 0] * x + view[2, 1] * y + view[2, 2] * z + view[2, 3])
        d_vertex.append(min(1.0, max(0.0, 1.0 - math.log(depth / 4.0) / math.log(3.0))))
    tri, bary = ctx.gb["tri_id"], ctx.gb["bary"]
    for y in range(0, H, 7):
        for x in range(0, W, 5):
            t = tri[y, x]
            if t < 0:
                assert math.isnan(got[y, x])
                continue
            f = mesh.faces[t]
            expect = sum(float(bary[y, x, k]) * d_vertex[f[k]] for k in range(3))
            assert got[y, x] == pytest.approx(expect, abs=1e-6)


def test_vertex_mode_error_shrinks_quadratically_with_triangle_size():
    errors = []
    for segments in (4, 8, 16):
        scene = floor_scene(segments=segments)
        d = {}
        for mode in ("pixel", "vertex"):
            # no clamping over the visible depths [2.2, 19]: D is smooth, the error O(h^2)
            style = get_style("xtoon", detail_mode=mode, z_min=2.0, r=10.0)
            d[mode] = style.fields(context(scene, style, 96, 72))["detail"]
        ok = np.isfinite(d["pixel"])
        errors.append(float(np.max(np.abs(d["pixel"][ok] - d["vertex"][ok]))))
    assert errors[0] > 0.02  # D = log(z) is not linear across a big triangle
    assert errors[0] / errors[1] > 2.6 and errors[1] / errors[2] > 3.0  # -> 4 as h -> 0


def test_vertex_attributes_through_the_rasterizer_match_the_style_interpolation():
    scene = load_scene("xtoon_row")
    style = get_style(
        "xtoon", detail_mode="vertex", z_min=18.0, r=3.0, shape="sphere", shape_weight=0.5
    )
    direct = render(scene, style, 80, 60).rgba
    prepared = style.prepare_scene(scene, width=80, height=60)
    channels = required_channels(prepared, style)
    assert channels == {"mesh_id", "xtoon_d", "xtoon_normal"}  # no tri_id/bary: the rasterizer
    np.testing.assert_allclose(render(prepared, style, 80, 60).rgba, direct, atol=2e-6)
    with pytest.raises(ValueError, match="xtoon_d: the vertex attribute carried by mesh"):
        render(prepared, style, 80, 60, camera=scene.camera.orbit(azimuth_deg=5.0))


def test_vertex_flow_interpolates_the_displacement_vector():
    scene = floor_scene(segments=4)
    prev = {"eye": [0.5, 2.0, 3.0], "target": list(TARGET), "fov_y": FOV}
    style = get_style("xtoon", detail="flow", detail_mode="vertex", prev_camera=prev, flow_max=12.0)
    ctx = context(scene, style)
    got = style.fields(ctx)["detail"]
    attrs = style.vertex_attributes(scene, width=W, height=H)[0]["xtoon_flow"]
    mesh = scene.world_meshes()[0]
    tri, bary = ctx.gb["tri_id"], ctx.gb["bary"]
    y, x = np.argwhere(tri >= 0)[len(np.argwhere(tri >= 0)) // 2]
    f = sum(float(bary[y, x, k]) * attrs[mesh.faces[tri[y, x]][k]] for k in range(3))
    assert got[y, x] == pytest.approx(1 - min(np.hypot(*f) / 12.0, 1.0), abs=1e-6)


# --- texture: orientation, images, tone, alpha -------------------------------------------------


def test_texture_rows_grow_with_detail():
    scene = floor_scene()
    tex = np.zeros((2, 4, 3))
    tex[0] = (1.0, 0.0, 0.0)  # row 0: D = 0 (far)
    tex[1] = (0.0, 0.0, 1.0)  # last row: D = 1 (near)
    style = get_style("xtoon", texture=tex, z_min=4.0, r=3.0)
    rgba = style.shade(context(scene, style))
    _, z, inside = floor_rays(scene)
    near = interior(inside) & (z < 3.9)
    far = interior(inside) & (z > 12.1)
    assert near.any() and far.any()
    np.testing.assert_allclose(rgba[near], [[0, 0, 1, 1]] * near.sum(), atol=1e-6)
    np.testing.assert_allclose(rgba[far], [[1, 0, 0, 1]] * far.sum(), atol=1e-6)


def test_image_textures_keep_file_rows_and_decode_srgb(tmp_path):
    img = np.zeros((2, 3, 3), dtype=np.uint8)
    img[0] = (255, 0, 0)
    img[1] = (128, 128, 128)
    path = tmp_path / "toon.png"
    iio.imwrite(path, img)
    tex = resolve_texture(str(path))
    assert tex.shape == (2, 3, 4)
    np.testing.assert_allclose(tex[0, 0], [1, 0, 0, 1], atol=1e-6)  # file row 0 -> D = 0
    grey = ((128 / 255 + 0.055) / 1.055) ** 2.4
    np.testing.assert_allclose(tex[1, 0, :3], grey, atol=1e-6)
    flipped = resolve_texture({"image": str(path), "flip": True})
    np.testing.assert_array_equal(flipped, tex[::-1])
    raw = resolve_texture({"image": str(path), "srgb": False})
    np.testing.assert_allclose(raw[1, 0, :3], 128 / 255, atol=1e-6)


@pytest.mark.parametrize(
    ("tone", "n_dot_l"), [("clamped", 0.6), ("clamped", -0.4), ("half_lambert", -0.4)]
)
def test_tone_is_n_dot_l_clamped_or_half_lambert(tone, n_dot_l):
    # light at angle with the floor normal (0, 1, 0): n.l = cos
    light = (math.sqrt(1 - n_dot_l**2), n_dot_l, 0.0)
    scene = floor_scene(light=light)
    style = get_style("xtoon", texture="lambert", detail="none", tone=tone)
    ctx = context(scene, style)
    rgba = style.shade(ctx)
    covered = ctx.gb["mesh_id"] >= 0
    expect = max(n_dot_l, 0.0) if tone == "clamped" else (n_dot_l + 1) / 2
    # the "lambert" texel j holds its tone (j + 0.5) / 4096: exact up to half a texel at the ends
    np.testing.assert_allclose(rgba[covered][:, :3], expect, atol=0.5 / 4096 + 1e-7)
    np.testing.assert_allclose(style.fields(ctx)["tone"][covered], expect, atol=1e-6)


def test_texture_alpha_composites_over_the_background():
    scene = floor_scene()
    scene = Scene(scene.objects, scene.camera, scene.lights, background=(0.2, 0.4, 0.6, 1.0))
    tex = np.ones((2, 2, 4))
    tex[..., :3] = (1.0, 0.0, 0.0)
    tex[..., 3] = 0.25
    img = render(scene, get_style("xtoon", texture=tex, detail="none"), W, H).rgba
    _, _, inside = floor_rays(scene)
    ok = interior(inside)
    np.testing.assert_allclose(img[ok][:, :3], [[0.4, 0.3, 0.45]] * ok.sum(), atol=1e-6)


def test_recipe_tables_and_presets_resolve():
    spec = {"recipe": "receding", "ramp": [[0.1, 0.1, 0.1], [0.9, 0.9, 0.9]], "shift": 0.5}
    tex = resolve_texture(spec)
    assert tex.shape == (64, 256, 4) and tex.dtype == np.float32
    ramp = np.repeat([[0.1] * 3, [0.9] * 3], 128, axis=0)
    np.testing.assert_allclose(
        tex[..., :3], fx.toon_texture_receding(ramp, 64, shift=0.5), atol=1e-7
    )
    from refnpr.styles.xtoon import PRESETS

    for name in PRESETS:
        t = resolve_texture(name)
        assert t.ndim == 3 and t.shape[2] == 4 and 0 <= t.min() and t.max() <= 1


# --- shape abstraction -------------------------------------------------------------------------


def test_shape_weight_zero_is_plain_shading_and_one_is_the_abstract_shape():
    scene = load_scene("xtoon_headlight")
    base = get_style("xtoon", texture="grey", detail="none")
    plain = render(scene, base, W, H).rgba
    for blend in ("vertex", "pixel"):
        zero = get_style(
            "xtoon",
            texture="grey",
            detail="none",
            shape="sphere",
            shape_weight=0.0,
            shape_blend=blend,
        )
        np.testing.assert_allclose(render(scene, zero, W, H).rgba, plain, atol=2e-6)
    one = {
        blend: get_style(
            "xtoon",
            texture="grey",
            detail="none",
            shape="sphere",
            shape_weight=1.0,
            shape_blend=blend,
        )
        for blend in ("vertex", "pixel")
    }
    a, b = (render(scene, s, W, H).rgba for s in one.values())
    np.testing.assert_allclose(a, b, atol=2e-6)  # both: normalize(interpolated sphere normal)
    assert np.abs(a - plain).max() > 0.2


def test_vertex_blend_is_the_papers_linear_blend_renormalized_per_pixel():
    scene = load_scene("xtoon_headlight")
    w = 0.6
    style = get_style("xtoon", detail="none", shape="ellipsoid", shape_weight=w)
    ctx = context(scene, style)
    got = style.fields(ctx)["normal"]
    mesh = scene.world_meshes()[0]
    n_hat = mesh.normals / np.linalg.norm(mesh.normals, axis=1, keepdims=True)
    n_abs = fx.ellipsoid_normals(mesh.positions, mesh.faces, mesh.normals)
    blend = (1 - w) * n_hat + w * n_abs  # per vertex, not normalized
    tri, bary = ctx.gb["tri_id"], ctx.gb["bary"]
    checked = 0
    for y, x in np.argwhere(tri >= 0)[::37]:
        f = mesh.faces[tri[y, x]]
        m = sum(float(bary[y, x, k]) * blend[f[k]] for k in range(3))
        np.testing.assert_allclose(got[y, x], m / np.linalg.norm(m), atol=2e-6)
        checked += 1
    assert checked > 10
    pixel = get_style(
        "xtoon", detail="none", shape="ellipsoid", shape_weight=w, shape_blend="pixel"
    )
    pctx = context(scene, pixel)
    n0 = pctx.gb["normal"].astype(np.float64)
    for y, x in np.argwhere(pctx.gb["tri_id"] >= 0)[::37]:
        f = mesh.faces[pctx.gb["tri_id"][y, x]]
        na = sum(float(pctx.gb["bary"][y, x, k]) * n_abs[f[k]] for k in range(3))
        m = (1 - w) * n0[y, x] / np.linalg.norm(n0[y, x]) + w * na / np.linalg.norm(na)
        np.testing.assert_allclose(
            pixel.fields(pctx)["normal"][y, x], m / np.linalg.norm(m), atol=2e-6
        )


def test_precomputed_abstracted_normals_are_reused_and_checked():
    scene = load_scene("xtoon_headlight")
    an = abstract_normals(scene, "cylinder")
    by_name = render(
        scene, get_style("xtoon", detail="none", shape="cylinder", shape_weight=0.7), W, H
    )
    by_value = render(scene, get_style("xtoon", detail="none", shape=an, shape_weight=0.7), W, H)
    np.testing.assert_array_equal(by_name.rgba, by_value.rgba)
    custom = render(
        scene,
        get_style("xtoon", detail="none", shape=lambda m: an.normals[0], shape_weight=0.7),
        W,
        H,
    )
    np.testing.assert_array_equal(custom.rgba, by_value.rgba)
    with pytest.raises(ValueError, match="shape: these AbstractedNormals were built for meshes"):
        render(sphere_scene(), get_style("xtoon", detail="none", shape=an), W, H)


def test_shape_objects_select_what_is_abstracted():
    scene = load_scene("xtoon_row")
    an = abstract_normals(scene, "sphere", objects=["teapot2"])
    assert [n is None for n in an.normals] == [True, True, False, True, True]
    with pytest.raises(ValueError, match=r"shape_objects: unknown object names \['lid'\]"):
        abstract_normals(scene, "sphere", objects=["lid"])


def test_local_weights_from_the_detail_map_and_a_texture():
    scene = floor_scene(segments=2)
    style = get_style(
        "xtoon", z_min=4.0, r=3.0, shape="sphere", shape_weight="detail", shape_blend="pixel"
    )
    f = style.fields(context(scene, style))
    ok = np.isfinite(f["detail"])
    np.testing.assert_allclose(f["weight"][ok], 1.0 - f["detail"][ok], atol=1e-6)  # depth: no n
    tex_style = get_style(
        "xtoon",
        detail="none",
        shape="sphere",
        shape_blend="pixel",
        shape_weight={"texture": "checkerboard", "uv_scale": 1.0},
    )
    ctx = context(scene, tex_style)
    weight = tex_style.fields(ctx)["weight"]
    from refnpr.texture import build_pyramid, load_texture, sample_level

    board = load_texture("checkerboard")
    covered = ctx.gb["mesh_id"] >= 0
    expect = sample_level(build_pyramid(board), ctx.gb["uv"][covered], 0, dtype=np.float64)
    np.testing.assert_allclose(weight[covered], expect, atol=1e-6)
    assert weight[covered].min() < 0.1 and weight[covered].max() > 0.9


# --- errors ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("params", "error", "match"),
    [
        ({"r": 1.0}, ValueError, r"r: expected a value > 1, got 1.0; r is the ratio z_max / z_min"),
        (
            {"detail": "focus", "focus_point": [0, 0, 0], "r": 0.5},
            ValueError,
            r"r: expected a value > 1",
        ),
        ({"z_min": 0.0}, ValueError, r"z_min: expected a value > 0, got 0.0; z_min is a distance"),
        ({"z_min": -2}, ValueError, r"z_min: expected a value > 0, got -2.0"),
        (
            {"texture": np.ones(8)},
            ValueError,
            r"texture: expected a 2D toon texture .* got shape \(8,\)",
        ),
        ({"texture": np.ones((2, 2, 2, 2))}, ValueError, r"texture: expected a 2D toon texture"),
        ({"texture": "sepia"}, ValueError, r"texture: unknown preset 'sepia'"),
        (
            {"texture": np.full((2, 2), 1.5)},
            ValueError,
            r"texture: texel values must be finite and lie in \[0, 1\]",
        ),
        (
            {"shape": "sphere", "shape_weight": 1.5},
            ValueError,
            r"shape_weight: expected a value in \[0, 1\], got 1.5",
        ),
        (
            {"shape": "sphere", "shape_weight": -0.1},
            ValueError,
            r"shape_weight: expected a value in \[0, 1\], got -0.1",
        ),
        (
            {"shape": "sphere", "shape_weight": np.full((4, 4), 2.0), "shape_blend": "pixel"},
            ValueError,
            r"shape_weight: values must be finite and lie in \[0, 1\]",
        ),
        (
            {"shape": "sphere", "shape_weight": np.ones((4, 4))},
            ValueError,
            r"shape_blend: a weight texture or array varies per pixel",
        ),
        ({"shape": "blob"}, ValueError, r"shape: expected None, one of \['cylinder', 'ellipsoid'"),
        ({"detail": "fog"}, ValueError, r"detail: expected one of"),
        ({"detail": "focus"}, ValueError, r"focus_point: detail='focus' needs the focus point"),
        (
            {"detail": "flow", "prev_transforms": [np.eye(3)]},
            ValueError,
            r"prev_transforms: expected one 4x4 matrix per scene object",
        ),
        (
            {"detail": "flow", "prev_transforms": [np.diag([1.0, 1.0, 0.0, 1.0])]},
            ValueError,
            r"prev_transforms\[0\]: the 3x3 part is singular",
        ),
        (
            {"detail": "flow", "prev_camera": {"eye": [0, 0, 1]}},
            ValueError,
            r"prev_camera: camera table keys",
        ),
        (
            {"detail": "flow", "prev_camera": {"eye": [0, 0, 1], "target": [0, 0, 1]}},
            ValueError,
            r"prev_camera: target: equals eye",
        ),
        (
            {"detail": "flow", "flow_min": 4.0, "flow_max": 4.0},
            ValueError,
            r"flow_max: expected a value > 4",
        ),
        ({"detail": "highlight", "s": 0.5}, ValueError, r"s: expected a value >= 1, got 0.5"),
        ({"detail": "orientation", "r": -1}, ValueError, r"r: expected a value >= 0, got -1.0"),
        ({"detail": "map"}, ValueError, r"detail_map: detail='map' needs"),
        (
            {"detail": "map", "detail_map": np.ones((4, 4)), "detail_mode": "vertex"},
            ValueError,
            r"detail_mode: a user-supplied detail_map is per pixel",
        ),
        ({"tone": "lambert"}, ValueError, r"tone: expected one of \['clamped', 'half_lambert'\]"),
        ({"one_sided": 1}, TypeError, r"one_sided: expected a bool"),
    ],
)
def test_bad_parameters_raise_clear_errors(params, error, match):
    with pytest.raises(error, match=match):
        get_style("xtoon", **params)


def test_frame_dependent_errors():
    scene = floor_scene()
    behind = get_style("xtoon", detail="focus", focus_point=[0.0, 2.0, 6.0])
    with pytest.raises(ValueError, match=r"focus_point: \[0.0, 2.0, 6.0\] is behind the camera"):
        render(scene, behind, W, H)
    too_wide = get_style("xtoon", detail="focus", focus_point=[0.0, 0.0, -4.0], z_min=3.0, r=4.0)
    with pytest.raises(ValueError, match=r"z_min: with r = 4 the blur reaches the eye"):
        render(scene, too_wide, W, H)
    with pytest.raises(ValueError, match=r"light: index 2 out of range; the scene has 1 light"):
        required_channels(scene, get_style("xtoon", light=2))


def test_toml_style_table_with_a_previous_camera_table():
    spec = {
        "name": "xtoon",
        "detail": "flow",
        "prev_camera": {"eye": [0.4, 2.0, 3.0], "target": [0.0, 0.0, -6.0], "fov_y": 50.0},
        "texture": {"preset": "loa_receding"},
        "contours": {"width": 1.0},
    }
    style = style_from_spec(spec)
    img = render(floor_scene(), style, W, H)
    assert np.all(np.isfinite(img.rgba))
    assert style.base.params()["prev_camera"]["eye"] == [0.4, 2.0, 3.0]


@pytest.mark.slow
def test_benchmark_quick_mode_writes_speed_and_accuracy_rows(tmp_path):
    import json
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_xtoon.py"
    out = tmp_path / "xtoon.json"
    proc = subprocess.run(
        [sys.executable, str(script), "--quick", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    report = json.loads(out.read_text())
    styles = {r["style"] for r in report["speed"]}
    assert {"toon", "xtoon-depth", "xtoon-depth-vertex"} <= styles
    for row in report["speed"]:
        assert len(row["runs_s"]) == 2 and row["median_s"] > 0
        if row["style"] == "xtoon-depth":
            assert row["channels"] == ["depth", "mesh_id", "normal"]
    assert {(r["scene"], r["detail"]) for r in report["accuracy"]} >= {("xtoon_teapot", "depth")}


def test_shape_iterations_is_bounded():
    from refnpr.styles import get_style

    with pytest.raises(ValueError, match=r"shape_iterations: expected an integer in \[0, 10000\]"):
        get_style("xtoon", shape="smoothed", shape_iterations=10**9)


def test_scene_without_lights_is_a_clear_error():
    import dataclasses

    from refnpr.render import render
    from refnpr.scenes import load_scene

    scene = dataclasses.replace(load_scene("sphere"), lights=())
    with pytest.raises(ValueError, match="light: X-Toon's tone is n.l of one light, but the scene"):
        render(scene, "xtoon", 16, 12)
