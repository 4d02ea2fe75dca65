"""The ``threshold`` style (Veryovka 2002): parameters, channels, eq. 2 against independent
oracles (naive per-pixel loops of eqs. 3-8, the toon and smooth styles), filtering against
supersampling, pyramid caching, strength blending, scene files and the CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.raster import rasterize
from refnpr.render import render
from refnpr.scenes import load_scene
from refnpr.styles import style_from_spec
from refnpr.styles.base import ShadeContext
from refnpr.styles.contours import Contoured
from refnpr.styles.smooth import SmoothStyle
from refnpr.styles.threshold import ThresholdStyle
from refnpr.styles.toon import ToonStyle
from refnpr.texture import clahe_pyramid, load_texture

from .test_threshold_tone import flat_scene, line_scale


def _shade(scene, style, w=64, h=48, spp=1):
    gb = rasterize(
        scene, scene.camera, w, h, sorted(style.requires(scene)), spp, **style.raster_options(scene)
    )
    return gb, style.shade(ShadeContext(gb, scene))


# ------------------------------------------------------------------------------ parameters


@pytest.mark.parametrize(
    "params, exc, match",
    [
        (dict(source="wood"), ValueError, r"source: expected one of .*'lines'.* got 'wood'"),
        (dict(source="image", filter="analytic"), ValueError, r"filter: 'analytic' .*lines"),
        (dict(filter="pcf", samples=3), ValueError, r"samples: expected a square number"),
        (
            dict(directions=[0.0, 90.0], onsets=[1.0]),
            ValueError,
            r"onsets: expected one onset per direction",
        ),
        (dict(onsets=[0.5]), ValueError, r"onsets: .*largest is 1"),
        (dict(tone_fade=[0.1]), ValueError, r"tone_fade: expected two widths"),
        (dict(tone_fade=[0.1, 0.7]), ValueError, r"tone_fade\[1\]: expected a value in \[0, 0.5\]"),
        (dict(period=0), ValueError, r"period: expected a value > 0"),
        (dict(n=0), ValueError, r"n: expected an integer in \[1, 256\], got 0"),
        (dict(uniform="yes"), TypeError, r"uniform: expected a bool"),
        (dict(directions="w"), ValueError, r"directions: each layer is 'u', 'v' or an angle"),
        (dict(directions=[]), ValueError, r"directions: expected at least one value"),
        (
            dict(directions=[0, 400]),
            ValueError,
            r"directions\[1\]: expected a value in \[-360, 360\]",
        ),
        (dict(uv_scale=0), ValueError, r"uv_scale: expected a positive number or two"),
        (dict(source="image", filter="pcf", mip="bilinear"), ValueError, r"mip: expected one of"),
        (dict(specular_threshold="lines"), ValueError, r"specular_threshold: expected 'texture'"),
        (dict(colour=1), TypeError, r"unknown parameter\(s\) \['colour'\]"),
        (dict(source="image", clahe_levels="some"), ValueError, r"clahe_levels: expected one of"),
    ],
)
def test_bad_parameters_name_the_parameter(params, exc, match):
    with pytest.raises(exc, match=match):
        ThresholdStyle(**params)


def test_bad_prebuilt_pyramid():
    with pytest.raises(TypeError, match=r"pyramid: expected a refnpr.texture.MipPyramid"):
        ThresholdStyle(source="image", pyramid=np.zeros((4, 4)))


def test_params_are_toml_representable_and_round_trip():
    style = ThresholdStyle(
        source="lines", directions=[30, -60], onsets=[1.0, 0.5], tone_fade=[0.1, 0.2]
    )
    params = style.params()
    assert params["directions"] == [30.0, -60.0] and params["tone_fade"] == [0.1, 0.2]
    assert all(isinstance(v, (str, int, float, bool, list)) for v in params.values())
    again = style_from_spec({"name": "threshold", **params})
    assert again.params() == params


# -------------------------------------------------------------------------------- channels


def test_requires_only_what_the_configuration_reads():
    scene = load_scene("sphere")  # one directional light
    req = ThresholdStyle(source="constant", specular=False).requires(scene)
    assert req == {"normal", "mesh_id"}
    single = ThresholdStyle(source="lines", specular=False)
    assert single.requires(scene) == {"normal", "mesh_id", "uv", "dyadic_scale"}
    assert single.raster_options(scene) == {"line_period": 8.0}
    cross = ThresholdStyle(source="lines", directions=[0, 90], specular=False)
    assert cross.requires(scene) == {"normal", "mesh_id", "uv", "duv_dx", "duv_dy"}
    assert cross.raster_options(scene) == {}
    assert "position" in ThresholdStyle(source="image").requires(scene)  # specular: V
    assert "position" in ThresholdStyle(specular=False, facing_fade=0.5).requires(scene)


def test_channel_dyadic_scale_and_derivative_paths_agree():
    scene = load_scene("torus_knot")
    _, a = _shade(scene, ThresholdStyle(source="lines", period=5.0, uv_scale=1.5))
    _, b = _shade(
        scene, ThresholdStyle(source="lines", period=5.0, uv_scale=1.5, filter="pcf", samples=1)
    )
    assert np.mean(a != b) < 1e-3


# ------------------------------------------------------------------ eq. 2 against oracles


def test_constant_source_is_the_toon_step():
    scene = load_scene("teapot")
    for n, t in ((1, 0.5), (3, 0.3)):
        _, a = _shade(scene, ThresholdStyle(source="constant", n=n, t=t))
        _, b = _shade(scene, ToonStyle(n=n, t=t, mode="step"))
        np.testing.assert_array_equal(a, b)


def test_zero_strength_is_smooth_shading():
    scene = load_scene("vase")
    _, a = _shade(scene, ThresholdStyle(source="lines", directions=[45, -45], strength=0.0))
    _, b = _shade(scene, SmoothStyle())
    np.testing.assert_allclose(a, b, atol=1e-6)


def _naive_line_white(v: float, s: float, x: float, uniform: bool) -> float:
    """Eqs. 6-8 (with the DESIGN.md correction) and eq. 3 for one pixel, scalar Python."""
    k = math.floor(s)
    t = s - k
    vr = (v * 2.0**k) % 1.0  # eq. 6
    v1 = (2 * vr) % 1.0  # eq. 7
    f = (1 - t) * vr + t * v1  # eq. 8
    if uniform:  # CDF of eq. 8's F
        lo, hi = (1 - t) / 2, (1 + t) / 2
        f = f / (1 + t) if f < lo else ((2 * f - lo) / (1 + t) if f < hi else (f + t) / (1 + t))
    return 1.0 if x >= f else 0.0  # eq. 3


@pytest.mark.parametrize("uniform", [False, True])
def test_binary_lines_match_naive_per_pixel_loop(uniform):
    scene = load_scene("sphere")
    style = ThresholdStyle(
        source="lines", period=4.0, uv_scale=3.0, uniform=uniform, specular=False
    )
    channels = sorted(style.requires(scene) | {"duv_dx", "duv_dy"})
    gb = rasterize(scene, scene.camera, 48, 40, channels, **style.raster_options(scene))
    out = style.shade(ShadeContext(gb, scene))
    light = np.asarray(scene.lights[0].direction)
    m_a = np.asarray(scene.objects[0].material.ambient) * np.asarray(scene.ambient)
    m_d = np.asarray(scene.objects[0].material.diffuse)
    checked = mismatched = 0
    for y in range(gb.height):
        for x in range(gb.width):
            if gb["mesh_id"][y, x] < 0:
                continue
            v = 3.0 * float(gb["uv"][y, x, 1])
            grad = 3.0 * math.hypot(float(gb["duv_dx"][y, x, 1]), float(gb["duv_dy"][y, x, 1]))
            s = math.log2((1.0 / grad) / 4.0)  # eq. 5
            nrm = gb["normal"][y, x].astype(np.float64)
            f_d = max(float(nrm @ light), 0.0)
            expect = m_a + m_d * _naive_line_white(v, s, f_d, uniform)  # eq. 2
            checked += 1
            mismatched += not np.allclose(out[y, x, :3], expect, atol=1e-5)
    assert checked > 500
    assert mismatched <= 0.002 * checked  # float32 uv: ties at line edges


def test_n_tones_give_only_k_over_n_levels():
    scene = flat_scene(0.55)
    _, rgba = _shade(scene, ThresholdStyle(source="lines", n=3, uniform=True, specular=False))
    levels = {round(float(v), 6) for v in np.unique(rgba[..., 0])}
    assert levels <= {0.0, round(1 / 3, 6), round(2 / 3, 6), 1.0}
    assert levels == {round(1 / 3, 6), round(2 / 3, 6)}  # x = 0.55 lies between 1/3 and 2/3


# ------------------------------------------------------------------------------ filtering


def _plane_lines(**extra):
    return ThresholdStyle(
        source="lines",
        period=4.0,
        uv_scale=line_scale(2.3, 4.0, size=64),
        specular=False,
        uniform=True,
        **extra,
    )


@pytest.mark.parametrize("angles", [[0.0], [30.0, -60.0]])
def test_pcf_on_an_affine_view_equals_supersampling(angles):
    # head-on plane: uv is affine in screen, so K = k*k threshold samples over the pixel are
    # exactly the k x k supersampling positions (x is constant on the plane)
    scene = flat_scene(0.4)
    pcf = render(scene, _plane_lines(directions=angles, filter="pcf", samples=16), 64, 64, 1).rgba
    ss = render(scene, _plane_lines(directions=angles), 64, 64, 16).rgba
    diff = np.abs(pcf[..., 0] - ss[..., 0])
    assert diff.mean() < 2e-3 and diff.max() <= 2 / 16 + 1e-6


def test_image_pcf_with_trilinear_thresholds_equals_supersampling_on_an_affine_view():
    scene = flat_scene(0.4)
    params = dict(source="image", texture="grass", uv_scale=0.7, specular=False)
    pcf = render(
        scene, ThresholdStyle(**params, filter="pcf", samples=16, mip="trilinear"), 48, 48
    ).rgba
    ss = render(scene, ThresholdStyle(**params), 48, 48, 16).rgba
    diff = np.abs(pcf[..., 0] - ss[..., 0])
    assert diff.mean() < 2e-3 and diff.max() <= 2 / 16 + 1e-6


def test_analytic_line_filter_equals_dense_supersampling():
    scene = flat_scene(0.4)
    ana = render(scene, _plane_lines(filter="analytic"), 64, 64, 1).rgba[..., 0]
    ref = render(scene, _plane_lines(), 64, 64, 256).rgba[..., 0]
    # 16 x 16 samples resolve coverage to ~1/16 per line edge crossing a row of samples
    assert np.abs(ana - ref).mean() < 0.01
    assert np.abs(ana - ref).max() < 0.07
    # ... while the binary image is far from it
    binary = render(scene, _plane_lines(), 64, 64, 1).rgba[..., 0]
    assert np.abs(binary - ref).mean() > 5 * np.abs(ana - ref).mean()


def test_analytic_filter_combines_with_supersampling():
    scene = flat_scene(0.4)
    ref = render(scene, _plane_lines(), 64, 64, 256).rgba[..., 0]
    a1 = render(scene, _plane_lines(filter="analytic"), 64, 64, 1).rgba[..., 0]
    a4 = render(scene, _plane_lines(filter="analytic"), 64, 64, 4).rgba[..., 0]
    assert np.abs(a4 - ref).mean() < 0.01 and np.abs(a4 - a1).mean() < 0.01


def _naive_bilinear(level: np.ndarray, u: float, v: float) -> float:
    rows, cols = level.shape
    x, y = u * cols - 0.5, v * rows - 0.5
    x0, y0 = math.floor(x), math.floor(y)
    a, b = x - x0, y - y0
    tex = lambda i, j: float(level[j % rows, i % cols])  # noqa: E731  GL_REPEAT
    return (
        (1 - a) * (1 - b) * tex(x0, y0)
        + a * (1 - b) * tex(x0 + 1, y0)
        + (1 - a) * b * tex(x0, y0 + 1)
        + a * b * tex(x0 + 1, y0 + 1)
    )


def test_image_two_level_filter_matches_naive_oracle():
    scene = load_scene("veryovka_room")
    style = ThresholdStyle(
        source="image", texture="gravel", filter="pcf", samples=1, specular=False
    )
    gb, rgba = _shade(scene, style, 40, 30)
    pyr = style.pyramids.get("gravel", style.p)
    light = np.asarray(scene.lights[0].direction)
    rng = np.random.default_rng(3)
    ys, xs = np.nonzero(gb["mesh_id"] >= 0)
    for i in rng.choice(len(ys), 40, replace=False):
        y, x = ys[i], xs[i]
        mat = scene.objects[gb["mesh_id"][y, x]].material
        su, sv = mat.uv_scale
        u, v = float(gb["uv"][y, x, 0]) * su, float(gb["uv"][y, x, 1]) * sv
        gx = np.array(gb["duv_dx"][y, x], dtype=np.float64) * (su, sv) * (512, 512)
        gy = np.array(gb["duv_dy"][y, x], dtype=np.float64) * (su, sv) * (512, 512)
        lam = min(max(math.log2(max(np.hypot(*gx), np.hypot(*gy))), 0.0), pyr.n_levels - 1)
        k0 = math.floor(lam)
        k1, f = min(k0 + 1, pyr.n_levels - 1), lam - k0
        f_d = max(float(gb["normal"][y, x].astype(np.float64) @ light), 0.0)
        t0 = _naive_bilinear(pyr.levels[k0], u, v)
        t1 = _naive_bilinear(pyr.levels[k1], u, v)
        tone = (1 - f) * (f_d >= t0) + f * (f_d >= t1)  # sec. 4: results of two levels
        expect = mat.ambient[0] + mat.diffuse[0] * tone
        assert rgba[y, x, 0] == pytest.approx(expect, abs=1e-4)


def test_pyramids_are_cached_per_texture_and_settings():
    scene = load_scene("veryovka_room")  # gravel floor, brick walls
    style = ThresholdStyle(source="image")
    _shade(scene, style, 32, 24)
    assert len(style.pyramids) == 2
    first = style.pyramids.get("brick", style.p)
    _shade(scene, style, 32, 24)
    assert len(style.pyramids) == 2 and style.pyramids.get("brick", style.p) is first


def test_prebuilt_pyramid_is_used_for_every_object():
    scene = load_scene("veryovka_room")
    pyr = clahe_pyramid(load_texture("grass"), window=8)
    style = ThresholdStyle(source="image", pyramid=pyr, specular=False)
    _, a = _shade(scene, style, 32, 24)
    _, b = _shade(
        scene, ThresholdStyle(source="image", texture="grass", window=8, specular=False), 32, 24
    )
    assert len(style.pyramids) == 0 and style.params()["pyramid"] == "prebuilt"
    np.testing.assert_array_equal(a, b)


def test_untextured_objects_fall_back_to_the_constant_threshold():
    scene = load_scene("sphere")  # no material texture
    _, a = _shade(scene, ThresholdStyle(source="image", t=0.4, specular=False))
    _, b = _shade(scene, ThresholdStyle(source="constant", t=0.4, specular=False))
    np.testing.assert_array_equal(a, b)


# --------------------------------------------------------------------------------- strength


def test_orientation_fade_removes_lines_where_the_surface_faces_the_camera():
    scene = flat_scene(0.4)  # n.v = 1 at the image centre, less towards the corners
    faded = render(scene, _plane_lines(facing_fade=1.0, facing_power=8.0), 64, 64).rgba[..., 0]
    centre = faded[28:36, 28:36]
    np.testing.assert_allclose(centre, 0.4, atol=0.02)  # ~continuous shading
    corner = faded[:6, :6]
    assert np.ptp(corner) > 0.3  # lines keep part of their contrast off-axis


def test_tone_fade_vanishes_in_darkest_and_brightest_tones():
    style = _plane_lines(tone_fade=[0.2, 0.2])
    for x in (0.01, 0.99):
        img = render(flat_scene(x), style, 32, 32).rgba[..., 0]
        # strength smoothstep(0.01 / 0.2) = 0.0072: lines at 0.7% of their contrast
        assert np.ptp(img) < 0.01 and img.mean() == pytest.approx(x, abs=0.01)
    mid = render(flat_scene(0.5), style, 32, 32).rgba[..., 0]
    assert set(np.unique(mid)) == {0.0, 1.0}


def test_noise_is_deterministic_and_moves_the_lines():
    scene = flat_scene(0.4)
    a = render(scene, _plane_lines(noise=0.3, noise_seed=1), 48, 48).rgba
    b = render(scene, _plane_lines(noise=0.3, noise_seed=1), 48, 48).rgba
    c = render(scene, _plane_lines(noise=0.3, noise_seed=2), 48, 48).rgba
    d = render(scene, _plane_lines(), 48, 48).rgba
    np.testing.assert_array_equal(a, b)
    assert np.mean(a != c) > 0.05 and np.mean(a != d) > 0.05


def test_specular_constant_threshold():
    scene = load_scene("sphere")
    _, a = _shade(scene, ThresholdStyle(source="lines", specular_threshold=0.5))
    _, b = _shade(scene, ThresholdStyle(source="lines", specular=False))
    m_s = scene.objects[0].material.specular[0]
    # the specular term is thresholded at 0.5: 0 or m_s (clipped at white), nothing in between
    off = np.isclose(a, b, atol=1e-6)
    on = np.isclose(a, np.minimum(b + m_s, 1.0), atol=1e-6)
    assert np.all((off | on)[..., :3]) and np.any(on & ~off)


# ---------------------------------------------------------------------- scenes, CLI, output


@pytest.mark.parametrize("name", ["veryovka_room", "veryovka_plane"])
def test_veryovka_scenes_carry_a_threshold_style(name):
    scene = load_scene(name)
    style = style_from_spec(scene.style)
    assert isinstance(style, ThresholdStyle)
    img = render(scene, None, 32, 24)
    assert img.rgba.dtype == np.float32 and np.all(np.isfinite(img.rgba))


def test_contours_key_wraps_the_style():
    style = style_from_spec({"name": "threshold", "source": "lines", "contours": {"width": 2.0}})
    assert isinstance(style, Contoured) and isinstance(style.base, ThresholdStyle)


def test_cli_reaches_the_parameters(tmp_path):
    from refnpr.cli import main

    out = tmp_path / "o.png"
    rc = main(
        [
            "render",
            "--scene",
            "vase",
            "--style",
            "threshold",
            "--param",
            'source="lines"',
            "--param",
            "directions=[45, -45]",
            "--param",
            'filter="analytic"',
            "--param",
            "contours={width=1.5}",
            "--size",
            "48x36",
            "-o",
            str(out),
            "-q",
        ]
    )
    assert rc == 0 and out.exists()


@pytest.mark.parametrize("source", ["constant", "image", "lines", "stipple"])
def test_output_is_float32_rgba_with_alpha_zero_where_empty(source):
    scene = load_scene("sphere")
    image = {"texture": "brick"} if source == "image" else {}  # texture: image thresholds only
    style = ThresholdStyle(source=source, **image, filter="pcf", samples=4)
    gb, rgba = _shade(scene, style, 40, 30, spp=4)
    assert rgba.dtype == np.float32 and rgba.shape == (60, 80, 4)
    assert np.all(np.isfinite(rgba)) and np.all((rgba >= 0) & (rgba <= 1))
    np.testing.assert_array_equal(rgba[..., 3], (gb["mesh_id"] >= 0).astype(np.float32))
