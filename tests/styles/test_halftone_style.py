"""The ``halftone`` style (Freudenberg et al. 2002): per-sample agreement with a naive oracle,
channel requests, scene files and the CLI, sec. 5 effects, parameter errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.cli import main as cli_main
from refnpr.formulas.halftone import tangent_frame
from refnpr.raster import rasterize
from refnpr.render import render, required_channels
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext, get_style, style_from_spec

from .test_halftone_scenes import wall

# ---------------------------------------------------------------------------------------------
# naive oracle: GL_REPEAT bilinear / trilinear lookups and the thresholds, one sample at a time
# ---------------------------------------------------------------------------------------------


def _bilinear(level: np.ndarray, u: float, v: float) -> float:
    rows, cols = level.shape
    x, y = u * cols - 0.5, v * rows - 0.5
    i0, j0 = math.floor(x), math.floor(y)
    fx, fy = x - i0, y - j0
    total = 0.0
    for dj, wy in ((0, 1 - fy), (1, fy)):
        for di, wx in ((0, 1 - fx), (1, fx)):
            total += wx * wy * float(level[(j0 + dj) % rows, (i0 + di) % cols])
    return total


def _trilinear(levels, u: float, v: float, lod: float) -> float:
    lam = min(max(lod, 0.0), len(levels) - 1)
    k0 = math.floor(lam)
    k1 = min(k0 + 1, len(levels) - 1)
    w = lam - k0
    return (1 - w) * _bilinear(levels[k0], u, v) + w * _bilinear(levels[k1], u, v)


def _oracle(style, scene, gb, idx, *, direction=None):
    """Output of sample ``idx`` (flat) computed naively: uv, LOD, screen, intensity, threshold."""
    screen = style.screen_for(style.screen_spec, None)
    levels = screen.pyramid.levels
    cols, rows = levels[0].shape[1], levels[0].shape[0]
    scale = np.asarray(style.uv_scale)
    uv = gb["uv"].reshape(-1, 2)[idx].astype(float) * scale
    dx = gb["duv_dx"].reshape(-1, 2)[idx].astype(float) * scale
    dy = gb["duv_dy"].reshape(-1, 2)[idx].astype(float) * scale
    if direction is not None:  # engraving: a 1D texture along t = uv . d
        d = np.array(direction)
        uv, dx, dy = np.array([uv @ d, 0.5]), np.array([dx @ d, 0.0]), np.array([dy @ d, 0.0])
    rho = max(math.hypot(dx[0] * cols, dx[1] * rows), math.hypot(dy[0] * cols, dy[1] * rows))
    lod = math.log2(rho) - (math.log2(gb.n) if style.p.sample_lod else 0.0)
    s = _trilinear(levels, uv[0], uv[1], lod)
    n = gb["normal"].reshape(-1, 3)[idx].astype(float)
    light = np.asarray(scene.lights[0].direction)
    mat = scene.objects[0].material
    intensity = mat.ambient[0] * scene.ambient[0] + mat.diffuse[0] * max(float(n @ light), 0.0)
    intensity = min(max(intensity, 0.0), 1.0)
    if style.p.threshold == "binary":
        return (1.0 if s + intensity > 1.0 else 0.0), s + intensity - 1.0
    top = 0.5 if style.p.centred else 1.0
    return min(max(top - style.p.c * (1.0 - s - intensity), 0.0), 1.0), 1.0


@pytest.mark.parametrize(
    "screen,direction,threshold,centred,spp,sample_lod",
    [
        ({"kind": "engraving", "profile": "triangle", "angle": 30.0}, 30.0, "binary", False, 1, 0),
        ({"kind": "engraving", "profile": "ramp", "angle": 90.0}, 90.0, "smooth", False, 4, 1),
        ({"kind": "engraving", "profile": "triangle", "angle": 0.0}, 0.0, "binary", False, 4, 0),
        ("grass", None, "binary", False, 1, False),
        ("grass", None, "smooth", True, 1, False),
        (
            {"kind": "strokes", "set": "hatching", "size": 64, "lines": 8},
            None,
            "smooth",
            False,
            4,
            1,
        ),
    ],
)
def test_samples_match_naive_oracle(screen, direction, threshold, centred, spp, sample_lod):
    # a tilted light and a tilted wall: intensity and LOD vary over the image
    scene = wall(0.8, light=(0.4, 0.3, 1.0), ambient=0.1, distance=3.2, fov=40.0)
    style = get_style(
        "halftone",
        screen=screen,
        threshold=threshold,
        centred=centred,
        uv_scale=[3.0, 2.0],
        specular=False,
    )
    gb = rasterize(scene, scene.camera, 48, 40, sorted(style.requires(scene)), spp)
    out = style.shade(ShadeContext(gb, scene))[..., 0].reshape(-1)
    covered = np.flatnonzero(gb["mesh_id"].reshape(-1) >= 0)
    rng = np.random.default_rng(11)
    d = None
    if direction is not None:
        a = math.radians(direction)
        d = (math.cos(a), math.sin(a))
    checked = 0
    for idx in rng.choice(covered, size=120, replace=False):
        expected, margin = _oracle(style, scene, gb, int(idx), direction=d)
        if abs(margin) < 1e-5:  # a tie of the binary threshold: float32 uv decides
            continue
        assert out[idx] == pytest.approx(expected, abs=2e-5), idx
        checked += 1
    assert checked > 100


def test_binary_output_is_black_or_white_and_smooth_has_grey():
    scene = wall(0.5, light=(0.5, 0.2, 1.0))
    binary = render(scene, {"name": "halftone", "threshold": "binary", "screen": "grass"}, 40, 40)
    values = np.unique(binary.rgba[..., 0])
    assert set(values.tolist()) <= {0.0, 1.0} and len(values) == 2
    smooth = render(scene, {"name": "halftone", "screen": "grass"}, 40, 40)
    grey = smooth.rgba[..., 0]
    assert np.any((grey > 0.05) & (grey < 0.95))


def test_ink_and_paper_colours():
    scene = wall(0.5, distance=1.5, fov=40.0)  # the wall fills the view
    st = {"name": "halftone", "threshold": "binary", "screen": "engraving"}
    img = render(scene, {**st, "ink": [0.2, 0.1, 0.0], "paper": [1.0, 0.9, 0.8]}, 24, 24)
    colours = np.unique(img.rgba[..., :3].reshape(-1, 3), axis=0)
    np.testing.assert_allclose(colours, [[0.2, 0.1, 0.0], [1.0, 0.9, 0.8]], atol=1e-6)


# ---------------------------------------------------------------------------------------------
# channels: only what the scene needs
# ---------------------------------------------------------------------------------------------
def test_requires_only_what_the_scene_needs():
    scene = wall(0.5)
    base = {"mesh_id", "normal", "uv", "duv_dx", "duv_dy"}
    assert get_style("halftone", specular=False).requires(scene) == frozenset(base)
    assert get_style("halftone").requires(scene) == frozenset(base | {"position"})
    bricks = get_style("halftone", screen="bricks", specular=False)
    assert bricks.requires(scene) == frozenset(base | {"dposition_dx", "dposition_dy"})
    unlit = get_style("halftone", screen={"kind": "strokes", "set": "bricks", "lighting": False})
    assert "dposition_dx" not in unlit.requires(scene)
    room = load_scene("halftone_room")  # point light: positions even without specular
    assert "position" in required_channels(room, {"name": "halftone", "specular": False})


def test_screen_lod_equals_the_rasterizer_lod_channel():
    """The kernel's isotropic LOD (``device.sampling.footprint`` of the uv derivatives in the
    screen's texels) is the rasterizer's ``lod`` channel for a texture of that size."""
    from refnpr.device.sampling import footprint
    from refnpr.styles.halftone import screens as HS

    scene = wall(0.5, distance=2.5, fov=50.0)
    gb = rasterize(
        scene,
        scene.camera,
        40,
        30,
        ["uv", "duv_dx", "duv_dy", "lod", "mesh_id"],
        texture_size=(256, 256),
    )
    m = gb["mesh_id"].reshape(-1) >= 0
    screen = HS.build_screen(HS.normalize_spec("hatching"), None)
    rows, cols = screen.pyramid.levels[0].shape[:2]
    dx = gb["duv_dx"].reshape(-1, 2)[m].astype(float)
    dy = gb["duv_dy"].reshape(-1, 2)[m].astype(float)
    pairs = zip(dx, dy, strict=True)
    lod = [footprint(tuple(a), tuple(b), float(rows), float(cols), 1)[0] for a, b in pairs]
    np.testing.assert_allclose(lod, gb["lod"].reshape(-1)[m], atol=1e-4)


def test_sample_lod_uses_each_samples_footprint():
    """With n x n samples, sample_lod shifts the LOD by -log2 n (finer screen levels)."""
    scene = wall(0.5, distance=4.0)
    spec = {"name": "halftone", "screen": "grass", "uv_scale": 4.0, "threshold": "binary"}
    fine = render(scene, {**spec, "sample_lod": True}, 32, 32, 4)
    coarse = render(scene, spec, 32, 32, 4)
    assert not np.array_equal(fine.rgba, coarse.rgba)
    biased = render(scene, {**spec, "lod_bias": -1.0}, 32, 32, 4)
    np.testing.assert_array_equal(fine.rgba, biased.rgba)


# ---------------------------------------------------------------------------------------------
# sec. 5 effects
# ---------------------------------------------------------------------------------------------
def test_indication_lightens_darkens_and_zero_changes_nothing():
    scene = wall(0.5, distance=1.5, fov=40.0)  # fills the view: u in [0.23, 0.77]
    spec = {"name": "halftone", "screen": "engraving", "threshold": "binary", "uv_scale": 6.0}
    plain = render(scene, spec, 48, 48).rgba[..., 0]
    zero = render(scene, {**spec, "indication": [[0.0, 0.0], [0.0, 0.0]]}, 48, 48).rgba[..., 0]
    np.testing.assert_array_equal(plain, zero)
    lighter = render(scene, {**spec, "indication": [[0.3]]}, 48, 48).rgba[..., 0]
    darker = render(scene, {**spec, "indication": [[-0.3]]}, 48, 48).rgba[..., 0]
    assert lighter.mean() > plain.mean() + 0.2 and darker.mean() < plain.mean() - 0.2
    # a four-texel map: columns 2-3 (u > 1/2) lighten, columns 0-1 leave the tone alone
    split = render(scene, {**spec, "indication": [[0.0, 0.0, 0.6, 0.6]]}, 48, 48).rgba[..., 0]
    assert split[:, 36:42].mean() > 0.95
    np.testing.assert_array_equal(split[:, 2:8], plain[:, 2:8])


def test_tangent_frame_on_a_known_plane():
    scene = wall(0.5, distance=3.0, fov=45.0)
    gb = rasterize(
        scene,
        scene.camera,
        24,
        24,
        ["mesh_id", "normal", "duv_dx", "duv_dy", "dposition_dx", "dposition_dy"],
    )
    m = gb["mesh_id"].reshape(-1) >= 0
    t, b, valid = tangent_frame(
        gb["normal"].reshape(-1, 3)[m].astype(float),
        gb["dposition_dx"].reshape(-1, 3)[m].astype(float),
        gb["dposition_dy"].reshape(-1, 3)[m].astype(float),
        gb["duv_dx"].reshape(-1, 2)[m].astype(float),
        gb["duv_dy"].reshape(-1, 2)[m].astype(float),
    )
    assert valid.all()
    np.testing.assert_allclose(t, np.tile([1.0, 0.0, 0.0], (t.shape[0], 1)), atol=1e-4)
    np.testing.assert_allclose(b, np.tile([0.0, 1.0, 0.0], (b.shape[0], 1)), atol=1e-4)


def _brick_bands(uv: np.ndarray):
    """Which samples lie in the left/right/low/high outline band of their brick (texture
    geometry of brick_set's defaults: 4 rows, 2 per row, running bond), from uv alone."""
    u, v = uv[:, 0] % 1.0, uv[:, 1] % 1.0
    row = np.floor(v * 4)
    uc = (u + np.where(row % 2 == 1, 0.25, 0.0)) * 2
    x = (uc - np.floor(uc)) * 0.5  # tile units from the brick's left border
    y = v - row / 4
    # inside the band at every level used (each level rounds the mortar gap and the outline to
    # whole texels: at 128 texels the band is [2, 5] / 128, at 64 [1, 2] / 64), off its fringes
    lo, hi = 0.0125 + 0.006, 0.0125 + 0.02 - 0.002
    far = 0.06  # away from the corners

    def within(d):
        return (d > lo) & (d < hi)

    mid_x = (x > far) & (x < 0.5 - far)
    mid_y = (y > far) & (y < 0.25 - far)
    return {
        "left": within(x) & mid_y,
        "right": within(0.5 - x) & mid_y,
        "low": within(y) & mid_x,
        "high": within(0.25 - y) & mid_x,
    }


def test_stroke_lighting_draws_only_lower_and_left_outlines():
    """Fig. 7: bricks lit from the upper right draw only their lower and left outlines."""
    scene = wall(0.85, light=(1.0, 1.0, 1.0), ambient=0.1, distance=2.2, fov=40.0)
    style = get_style("halftone", screen="bricks", threshold="binary", uv_scale=2.0, specular=False)
    gb = rasterize(scene, scene.camera, 160, 160, sorted(style.requires(scene)))
    out = style.shade(ShadeContext(gb, scene))[..., 0].reshape(-1)
    bands = _brick_bands(gb["uv"].reshape(-1, 2).astype(float) * 2.0)
    ink = {k: float(np.mean(out[sel] < 0.5)) for k, sel in bands.items()}
    assert all(bands[k].sum() > 50 for k in bands)
    assert ink["left"] > 0.9 and ink["low"] > 0.9, ink
    assert ink["right"] < 0.05 and ink["high"] < 0.05, ink
    flat = get_style(
        "halftone",
        screen={"kind": "strokes", "set": "bricks", "lighting": False},
        threshold="binary",
        uv_scale=2.0,
        specular=False,
    )
    out_flat = flat.shade(ShadeContext(gb, scene))[..., 0].reshape(-1)
    flat_ink = {k: float(np.mean(out_flat[sel] < 0.5)) for k, sel in bands.items()}
    # without stroke lighting no side is preferred: opposite outlines get about the same ink
    assert abs(flat_ink["left"] - flat_ink["right"]) < 0.15, flat_ink
    assert abs(flat_ink["low"] - flat_ink["high"]) < 0.15, flat_ink


# ---------------------------------------------------------------------------------------------
# scene files and the CLI
# ---------------------------------------------------------------------------------------------
def test_scene_files_name_the_style_and_its_parameters():
    room = load_scene("halftone_room")
    style = style_from_spec(room.style)
    assert style.name == "contoured" and style.base.name == "halftone"
    assert style.base.objects["back_wall"]["screen"]["set"] == "bricks"
    assert style.base.objects["back_wall"]["indication"].shape == (3, 4)
    teapot = style_from_spec(load_scene("halftone_teapot").style)
    assert teapot.base.screen_spec["kind"] == "engraving"


def test_cli_renders_with_halftone_parameters(tmp_path):
    out = tmp_path / "h.png"
    code = cli_main(
        [
            "render",
            "--scene",
            "sphere",
            "--style",
            "halftone",
            "--size",
            "48x40",
            "-q",
            "--param",
            "threshold='binary'",
            "--param",
            "screen={kind='engraving', angle=0.0}",
            "--param",
            "uv_scale=[16, 1]",
            "-o",
            str(out),
        ]
    )
    assert code == 0 and out.is_file()
    import imageio.v3 as iio

    img = iio.imread(out)
    assert img.shape == (40, 48, 4)
    assert {0, 255} <= set(np.unique(img[..., 0]).tolist())


# ---------------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "params,exc,match",
    [
        ({"threshold": "dither"}, ValueError, r"threshold: expected one of \['smooth', 'binary'\]"),
        ({"c": 0.0}, ValueError, r"c: expected a value > 0, got 0.0"),
        ({"c": "fwidth"}, ValueError, r"c: expected 'auto' or a value > 0, got 'fwidth'"),
        ({"centred": "yes"}, TypeError, r"centred: expected a bool"),
        ({"screen": "voronoi"}, ValueError, r"screen: unknown screen name, got 'voronoi'"),
        ({"screen": {"kind": "halftone"}}, ValueError, r"a screen table needs kind in"),
        ({"screen": {"kind": "engraving", "width": 2}}, ValueError, r"screen.width: unknown key"),
        ({"screen": {"kind": "engraving", "profile": "sine"}}, ValueError, r"screen.profile"),
        ({"screen": {"kind": "strokes", "set": "waves"}}, ValueError, r"screen.set: expected one"),
        ({"screen": {"kind": "strokes", "layers": "a.png"}}, TypeError, r"screen.layers"),
        ({"uv_scale": [1.0, -2.0]}, ValueError, r"uv_scale: expected a positive number or two"),
        ({"indication": [[0.0, 1.5]]}, ValueError, r"indication: expected signed values in"),
        ({"indication": "nowhere.png"}, ValueError, r"indication: 'nowhere.png' is not an"),
        ({"objects": {"wall": {"tone": 1}}}, ValueError, r"objects.wall.tone: unknown key"),
        ({"ink": [0, 0]}, ValueError, r"ink: expected 3 values in \[0, 1\] \(linear RGB\)"),
        ({"mip": "nearest"}, ValueError, r"mip: expected one of \['trilinear', 'per_level'\]"),
    ],
)
def test_parameter_errors(params, exc, match):
    with pytest.raises(exc, match=match):
        get_style("halftone", **params)


def test_scene_dependent_errors():
    scene = wall(0.5)
    style = get_style("halftone", objects={"floor": {"screen": "engraving"}})
    with pytest.raises(ValueError, match=r"objects.floor: the scene has no object of that name"):
        style.requires(scene)
    with pytest.raises(ValueError, match=r"texture = 'material' but the object's material has no"):
        render(scene, {"name": "halftone", "screen": "material"}, 8, 8)
    with pytest.raises(TypeError, match=r"screen \('hatching' options\): .*unexpected keyword"):
        render(scene, {"name": "halftone", "screen": {"kind": "strokes", "sides": 3}}, 8, 8)


def test_material_texture_is_the_default_dither_screen():
    scene = wall(0.5, texture="gravel")
    a = render(scene, {"name": "halftone", "screen": "material", "threshold": "binary"}, 32, 32)
    b = render(scene, {"name": "halftone", "screen": "gravel", "threshold": "binary"}, 32, 32)
    np.testing.assert_array_equal(a.rgba, b.rgba)


def test_auto_slope_antialiases_like_supersampling():
    """``c = "auto"`` (ramp = one sample's footprint) on resolved engraving lines: close to the
    box-filtered coverage of a 16 x 16 supersampled binary render, far closer than 1-spp binary."""
    scene = wall(0.6, light=(0.3, 0.5, 1.0), distance=1.5, fov=40.0)  # fills the view
    base = {
        "name": "halftone",
        "screen": {"kind": "engraving", "profile": "triangle", "angle": 80.0, "size": 32},
        "uv_scale": 12.0,
        "specular": False,
    }
    ref = render(scene, {**base, "threshold": "binary"}, 48, 48, 256).rgba[..., 0]
    binary = render(scene, {**base, "threshold": "binary"}, 48, 48).rgba[..., 0]
    auto = render(scene, {**base, "threshold": "smooth", "c": "auto"}, 48, 48).rgba[..., 0]
    err_binary, err_auto = np.abs(binary - ref).mean(), np.abs(auto - ref).mean()
    assert err_auto < 0.25 * err_binary, (err_auto, err_binary)


@pytest.mark.parametrize(
    "params, warned",
    [
        ({"tone_correct": True}, "tone_correct: True is ignored with stroke-map screens only"),
        ({"tone_correct": True, "screen": "engraving"}, None),
        ({"anisotropy": 8, "screen": "engraving"}, "anisotropy: 8 is ignored with engraving"),
        ({"anisotropy": 8}, None),
    ],
)
def test_a_parameter_no_screen_in_view_reads_warns_once(params, warned):
    import warnings

    style = get_style("halftone", **params)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = render("halftone_teapot", style, 24, 16, 1)
        render("halftone_teapot", style, 24, 16, 1)  # the same style again: no second warning
    messages = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert messages == ([] if warned is None else [messages[0]])
    assert warned is None or warned in messages[0]
    plain = {"name": "halftone", **{k: v for k, v in params.items() if k == "screen"}}
    if warned is not None:  # ignored indeed: the image is the one without it
        np.testing.assert_array_equal(first.rgba, render("halftone_teapot", plain, 24, 16, 1).rgba)
