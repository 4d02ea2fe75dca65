"""Tests of refnpr.formulas.xtoon (Barla, Thollot, Markosian 2006, X-Toon).

Oracles: the paper's formulas written out literally with ``math`` in Python loops, a naive
tent-weight bilinear filter, analytic normals of spheres, ellipsoids and cylinders.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from refnpr.formulas import xtoon

finite = st.floats(-1e6, 1e6, allow_nan=False)
positive = st.floats(1e-3, 1e4, allow_nan=False)
ratio = st.floats(1.0001, 100.0, allow_nan=False)


# ---------------------------------------------------------------------------------------------
# depth-based detail (sec. 3.1)


def naive_depth(z: float, z_min: float, r: float) -> float:
    """Paper, sec. 3.1, first printed form, then clamped (footnote 1)."""
    z_max = r * z_min
    if math.isinf(z):
        return 0.0
    d = 1.0 - math.log(z / z_min) / math.log(z_max / z_min)
    return min(max(d, 0.0), 1.0)


def naive_focus(z: float, z_c: float, z_min: float, r: float) -> float:
    """Paper, sec. 3.1, depth-of-field, both branches as printed, then clamped."""
    zmin_m, zmax_m = z_c - z_min, z_c - r * z_min
    zmin_p, zmax_p = z_c + z_min, z_c + r * z_min
    if z < z_c:
        d = 1.0 - math.log(z / zmin_m) / math.log(zmax_m / zmin_m)
    elif z > z_c:
        if math.isinf(z):
            return 0.0
        d = math.log(z / zmax_p) / math.log(zmin_p / zmax_p)
    else:
        d = 1.0
    return min(max(d, 0.0), 1.0)


def test_detail_depth_paper_values():
    z_min, r = 2.0, 4.0
    z = np.array([0.5, 2.0, 4.0, 8.0, 100.0, np.inf])
    # 1 up to z_min, 0 from z_max = r z_min, 1/2 at the geometric midpoint sqrt(r) z_min
    np.testing.assert_allclose(xtoon.detail_depth(z, z_min, r), [1, 1, 0.5, 0, 0, 0], atol=1e-15)
    # the paper's two printed forms agree: log(z/z_min)/log(z_max/z_min) = log_r(z/z_min)
    for zi in (2.5, 3.0, 7.9):
        assert xtoon.detail_depth(zi, z_min, r) == pytest.approx(naive_depth(zi, z_min, r))
        assert 1 - math.log(zi / z_min, r) == pytest.approx(naive_depth(zi, z_min, r))


@given(
    z=hnp.arrays(np.float64, st.integers(1, 40), elements=st.floats(1e-3, 1e5)),
    z_min=positive,
    r=ratio,
)
def test_detail_depth_matches_loop_in_range_and_monotone(z, z_min, r):
    d = xtoon.detail_depth(z, z_min, r)
    expect = [naive_depth(float(v), z_min, r) for v in z]
    np.testing.assert_allclose(d, expect, rtol=1e-12, atol=1e-12)
    assert np.all((d >= 0) & (d <= 1))
    order = np.argsort(z)
    assert np.all(np.diff(d[order]) <= 0)  # detail decreases with depth


def test_detail_depth_float32_in_float32_out():
    z = np.array([1.0, 3.0, 9.0], dtype=np.float32)
    out = xtoon.detail_depth(z, 2.0, 4.0)
    assert out.dtype == np.float32
    np.testing.assert_allclose(out, [naive_depth(float(v), 2.0, 4.0) for v in z], atol=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "err", "match"),
    [
        ({"z_min": 1.0, "r": 1.0}, ValueError, r"r: expected a value in \(1\.0, inf\], got 1\.0"),
        ({"z_min": 1.0, "r": 0.5}, ValueError, r"r: .* must exceed 1"),
        ({"z_min": 0.0, "r": 2.0}, ValueError, r"z_min: expected a value in \(0\.0, inf\]"),
        ({"z_min": -1.0, "r": 2.0}, ValueError, r"z_min: .*got -1\.0"),
        ({"z_min": "1", "r": 2.0}, TypeError, r"z_min: expected a real number"),
        ({"z_min": 10**400, "r": 2.0}, ValueError, r"z_min: .*integer beyond the float range"),
    ],
)
def test_detail_depth_rejects_bad_parameters(kwargs, err, match):
    with pytest.raises(err, match=match):
        xtoon.detail_depth(np.ones(3), **kwargs)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_detail_depth_rejects_non_positive_depth(bad):
    with pytest.raises(ValueError, match=r"z: expected positive distances .* at flat index 1"):
        xtoon.detail_depth(np.array([1.0, bad]), 1.0, 2.0)


def test_detail_focus_paper_values():
    z_c, z_min, r = 10.0, 1.0, 4.0
    z = np.array([6.0, 9.0, 10.0, 11.0, 14.0, 3.0, 20.0, np.inf])
    np.testing.assert_allclose(
        xtoon.detail_focus(z, z_c, z_min, r), [0, 1, 1, 1, 0, 0, 0, 0], atol=1e-15
    )


@given(
    z=hnp.arrays(np.float64, st.integers(1, 40), elements=st.floats(1e-3, 1e3)),
    z_min=st.floats(1e-2, 10.0),
    r=st.floats(1.001, 20.0),
    margin=st.floats(1e-3, 100.0),
)
def test_detail_focus_matches_loop_in_range_and_monotone(z, z_min, r, margin):
    z_c = r * z_min + margin  # footnote 2: 0 < z_max^- = z_c - r z_min
    d = xtoon.detail_focus(z, z_c, z_min, r)
    expect = [naive_focus(float(v), z_c, z_min, r) for v in z]
    np.testing.assert_allclose(d, expect, rtol=1e-10, atol=1e-10)
    assert np.all((d >= 0) & (d <= 1))
    near, far = np.sort(z[z < z_c]), np.sort(z[z > z_c])
    dn = xtoon.detail_focus(near, z_c, z_min, r)
    df = xtoon.detail_focus(far, z_c, z_min, r)
    assert np.all(np.diff(dn) >= 0) and np.all(np.diff(df) <= 0)


def test_detail_focus_edges_hit_one_and_zero():
    z_c, z_min, r = 7.0, 0.5, 3.0
    z = np.array([z_c - z_min, z_c + z_min, z_c - r * z_min, z_c + r * z_min])
    np.testing.assert_allclose(xtoon.detail_focus(z, z_c, z_min, r), [1, 1, 0, 0], atol=1e-14)


@pytest.mark.parametrize(("z_c", "z_min", "r"), [(4.0, 1.0, 4.0), (4.0, 1.0, 5.0), (1.0, 1.0, 2.0)])
def test_detail_focus_rejects_focus_too_close(z_c, z_min, r):
    with pytest.raises(ValueError, match=r"z_focus - r\*z_min: expected > 0 .*footnote 2"):
        xtoon.detail_focus(np.ones(2), z_c, z_min, r)


def test_detail_focus_rejects_r_not_above_one():
    with pytest.raises(ValueError, match=r"r: expected a value in \(1\.0, inf\]"):
        xtoon.detail_focus(np.ones(2), 10.0, 1.0, 1.0)


# ---------------------------------------------------------------------------------------------
# orientation-based detail (sec. 3.2)


@given(
    c=hnp.arrays(np.float64, st.integers(1, 30), elements=st.floats(-1, 1)),
    r=st.floats(0, 50),
)
def test_detail_orientation_is_abs_power(c, r):
    d = xtoon.detail_orientation(c, r)
    np.testing.assert_allclose(d, [abs(float(v)) ** r for v in c], rtol=1e-12, atol=1e-300)
    assert np.all((d >= 0) & (d <= 1))
    order = np.argsort(np.abs(c))
    assert np.all(np.diff(d[order]) >= 0)  # more detail facing the camera
    np.testing.assert_array_equal(d, xtoon.detail_orientation(-c, r))


def test_detail_orientation_limits_and_errors():
    np.testing.assert_array_equal(xtoon.detail_orientation(np.array([0.0, 0.3, 1.0]), 0.0), 1.0)
    assert xtoon.detail_orientation(1.0000001, 3.0) == 1.0  # overshoot clipped
    assert xtoon.detail_orientation(np.float32(0.5), 2.0).dtype == np.float32
    with pytest.raises(ValueError, match=r"r: expected a value in \[0\.0, inf\].*r >= 0"):
        xtoon.detail_orientation(0.5, -1.0)
    with pytest.raises(ValueError, match=r"n_dot_v: must not contain NaN"):
        xtoon.detail_orientation(np.array([0.1, np.nan]), 1.0)


@given(
    c=hnp.arrays(np.float64, st.integers(1, 30), elements=st.floats(-1, 1)),
    s=st.floats(1, 200),
)
def test_detail_highlight_is_phong(c, s):
    np.testing.assert_allclose(
        xtoon.detail_highlight(c, s), [abs(float(v)) ** s for v in c], rtol=1e-12, atol=1e-300
    )
    np.testing.assert_allclose(
        xtoon.detail_highlight(c, s, one_sided=True),
        [max(float(v), 0.0) ** s for v in c],
        rtol=1e-12,
        atol=1e-300,
    )


def test_detail_highlight_abs_lights_the_anti_mirror_direction():
    # DESIGN: |v.r| also gives full detail where v.r = -1; the one-sided option does not.
    assert xtoon.detail_highlight(-1.0, 30.0) == 1.0
    assert xtoon.detail_highlight(-1.0, 30.0, one_sided=True) == 0.0
    with pytest.raises(ValueError, match=r"s: expected a value in \[1\.0, inf\].*s >= 1"):
        xtoon.detail_highlight(0.5, 0.5)


# ---------------------------------------------------------------------------------------------
# 2D toon lookup


def naive_lookup(tex: np.ndarray, tone: float, detail: float) -> np.ndarray:
    """Tent-filter reconstruction with texel centres at (k + 0.5) / n, clamped to the edge."""
    rows, cols = tex.shape[:2]
    x = min(max(min(max(tone, 0.0), 1.0) * cols - 0.5, 0.0), cols - 1)
    y = min(max(min(max(detail, 0.0), 1.0) * rows - 0.5, 0.0), rows - 1)
    acc = np.zeros(tex.shape[2:])
    for i in range(rows):
        for j in range(cols):
            w = max(0.0, 1 - abs(x - j)) * max(0.0, 1 - abs(y - i))
            acc = acc + w * tex[i, j]
    return acc


@given(
    rows=st.integers(1, 6),
    cols=st.integers(1, 6),
    channels=st.sampled_from([None, 1, 3]),
    seed=st.integers(0, 2**32 - 1),
)
def test_toon_lookup_matches_naive_bilinear(rows, cols, channels, seed):
    rng = np.random.default_rng(seed)
    shape = (rows, cols) if channels is None else (rows, cols, channels)
    tex = rng.uniform(0, 1, shape)
    tone = rng.uniform(-0.2, 1.2, 25)
    detail = rng.uniform(-0.2, 1.2, 25)
    out = xtoon.toon_lookup(tex, tone, detail)
    expect = np.array([naive_lookup(tex, a, b) for a, b in zip(tone, detail, strict=True)])
    np.testing.assert_allclose(out, expect, rtol=1e-12, atol=1e-12)


def test_toon_lookup_orientation_and_texel_centres():
    rows, cols = 4, 5
    tex = np.arange(rows * cols, dtype=float).reshape(rows, cols)
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    np.testing.assert_array_equal(xtoon.toon_lookup(tex, (j + 0.5) / cols, (i + 0.5) / rows), tex)
    # row index grows with D, column index with tone
    assert xtoon.toon_lookup(tex, 0.0, 1.0) == tex[-1, 0]
    assert xtoon.toon_lookup(tex, 1.0, 0.0) == tex[0, -1]


def test_toon_lookup_shapes_and_dtype():
    tex = np.zeros((3, 4, 2), dtype=np.float32)
    out = xtoon.toon_lookup(tex, np.zeros((5, 1), np.float32), np.zeros(6, np.float32))
    assert out.shape == (5, 6, 2) and out.dtype == np.float32
    assert xtoon.toon_lookup(tex, 0.5, 0.5).shape == (2,)
    assert xtoon.toon_lookup(tex.astype(np.float64), 0.5, 0.5).dtype == np.float64
    with pytest.raises(ValueError, match=r"texture: expected shape \(rows, cols\)"):
        xtoon.toon_lookup(np.zeros(4), 0.5, 0.5)
    with pytest.raises(ValueError, match=r"tone: must not contain NaN"):
        xtoon.toon_lookup(np.zeros((2, 2)), np.nan, 0.5)


# ---------------------------------------------------------------------------------------------
# texture builders


def step_ramp(cols: int = 16, edge: float = 0.5) -> np.ndarray:
    tone = (np.arange(cols) + 0.5) / cols
    return np.where(tone < edge, 0.1, 0.9)


def test_blur_rows_match_naive_mirror_convolution():
    ramp = np.random.default_rng(3).uniform(0, 1, (9, 3))
    tex = xtoon.toon_texture_blur(ramp, 5, max_sigma=6.0)
    for i in range(5):
        sigma = 6.0 * (1 - (i + 0.5) / 5)
        radius = int(math.ceil(4 * 6.0))
        padded = np.pad(ramp, ((radius, radius), (0, 0)), mode="symmetric")
        w = np.array([math.exp(-0.5 * (o / sigma) ** 2) for o in range(-radius, radius + 1)])
        w /= w.sum()
        for j in range(9):
            expect = sum(w[k] * padded[j + k] for k in range(2 * radius + 1))
            np.testing.assert_allclose(tex[i, j], expect, rtol=1e-12)


def test_blur_preserves_mean_and_converges_to_constant():
    ramp = step_ramp()
    tex = xtoon.toon_texture_blur(ramp, 8, max_sigma=400.0)
    np.testing.assert_allclose(tex.mean(axis=1), ramp.mean(), rtol=1e-12)
    assert np.ptp(tex[0]) < 1e-3  # Fig. 8a: converges to a constant colour
    np.testing.assert_array_equal(xtoon.toon_texture_blur(ramp, 3, max_sigma=0.0), [ramp] * 3)
    spread = np.ptp(xtoon.toon_texture_blur(ramp, 8, max_sigma=4.0), axis=1)
    assert np.all(np.diff(spread) >= -1e-12)  # contrast returns as D grows


def test_levels_bands_and_hard_steps():
    ramps = np.stack([np.full(6, 0.2), np.linspace(0, 1, 6), step_ramp(6)])
    tex = xtoon.toon_texture_levels(ramps, 12, transition=0.0)
    np.testing.assert_array_equal(tex[:4], [ramps[0]] * 4)
    np.testing.assert_allclose(tex[4:8], [ramps[1]] * 4, atol=1e-15)
    np.testing.assert_allclose(tex[8:], [ramps[2]] * 4, atol=1e-15)
    smooth = xtoon.toon_texture_levels(ramps, 12, transition=1.0)
    assert np.all(np.abs(np.diff(smooth[:, 0])) <= 0.2 * 0.5 + 1e-12)  # smooth transitions
    np.testing.assert_allclose(smooth[0], ramps[0], atol=1e-15)
    np.testing.assert_allclose(smooth[-1], ramps[-1], atol=1e-15)


def test_receding_shadows_slide_left():
    cols, rows, shift = 64, 8, 0.4
    tex = xtoon.toon_texture_receding(step_ramp(cols), rows, shift=shift)
    tone = (np.arange(cols) + 0.5) / cols
    for i in range(rows):
        D = (i + 0.5) / rows
        dark = tone[tex[i] < 0.5]
        edge = dark.max() + 0.5 / cols if dark.size else 0.0
        assert abs(edge - max(0.5 - shift * (1 - D), 0.0)) <= 1.0 / cols
    ramp = step_ramp(cols)
    lit = xtoon.toon_texture_receding(ramp, rows, shift=0.0, lighten=1.0)
    a0 = 1 - 0.5 / rows
    np.testing.assert_allclose(lit[0], ramp + (0.9 - ramp) * a0, rtol=1e-12)
    np.testing.assert_allclose(xtoon.toon_texture_receding(ramp, rows, shift=0.0), [ramp] * rows)


def test_fade_contrast_opacity_and_tone_weight():
    rgba = np.concatenate([np.linspace(0, 1, 8)[:, None].repeat(3, 1), np.ones((8, 1))], 1)
    keep = np.array([0, 1, 1, 1, 1, 1, 1, 0.0])
    tex = xtoon.toon_texture_fade(rgba, 4, contrast=1.0, opacity=1.0, tone_weight=keep)
    a0 = 1 - 0.5 / 4
    mean = rgba[:, :3].mean(0)
    np.testing.assert_allclose(tex[0, 3, :3], rgba[3, :3] + (mean - rgba[3, :3]) * a0, 1e-12)
    np.testing.assert_allclose(tex[0, 3, 3], 1 - a0)
    np.testing.assert_array_equal(tex[:, 0], [rgba[0]] * 4)  # weight 0: shadows stay opaque
    np.testing.assert_array_equal(tex[:, -1], [rgba[-1]] * 4)
    with pytest.raises(ValueError, match=r"opacity: a fade of 0\.5 needs an alpha channel"):
        xtoon.toon_texture_fade(rgba[:, :3], 4, opacity=0.5)
    with pytest.raises(ValueError, match=r"tone_weight: expected 8 non-negative values"):
        xtoon.toon_texture_fade(rgba, 4, tone_weight=np.ones(3))


def test_hue_shift_and_desaturation():
    rgb = np.stack([np.linspace(0, 1, 5), np.linspace(1, 0, 5), np.full(5, 0.3)], 1)
    grey = xtoon.toon_texture_hue(rgb, 64, target=[0, 0, 1], amount=0.0, desaturate=1.0)
    luma = rgb @ np.array([0.2126, 0.7152, 0.0722])
    np.testing.assert_allclose(grey[0], rgb + (luma[:, None] - rgb) * (1 - 0.5 / 64), 1e-12)
    blue = xtoon.toon_texture_hue(rgb, 64, target=[0, 0, 1], amount=2.0)
    np.testing.assert_allclose(blue[:32], np.broadcast_to([0, 0, 1.0], (32, 5, 3)), atol=1e-12)
    np.testing.assert_allclose(blue[-1], rgb + ([0, 0, 1] - rgb) * 2 * (0.5 / 64), 1e-12)
    with pytest.raises(ValueError, match=r"ramp: expected an RGB \(cols, 3\)"):
        xtoon.toon_texture_hue(np.linspace(0, 1, 5), 4, target=[0, 0, 1])


def test_backlight_grows_thinner_in_dark_tones():
    cols, rows = 16, 64
    ramp = np.linspace(0.2, 0.6, cols)
    tex = xtoon.toon_texture_backlight(ramp, rows, color=1.0, width=0.4, thinning=0.75)
    lit = tex == 1.0
    D = (np.arange(rows) + 0.5) / rows
    tone = (np.arange(cols) + 0.5) / cols
    np.testing.assert_array_equal(lit, D[:, None] < 0.4 * (1 - 0.75 * (1 - tone))[None, :])
    assert np.all(np.diff(lit.sum(0)) >= 0)


def test_plastic_highlight_shrinks_with_detail_and_keeps_hard_edges():
    ramp = np.linspace(0, 0.8, 32)
    tex = xtoon.toon_texture_plastic(ramp, 16, color=1.0, size=0.5)
    hi = tex == 1.0
    assert np.all(np.diff(hi.sum(1)) >= 0) and hi[-1].sum() > 0 and hi[0].sum() <= 1
    np.testing.assert_array_equal(tex[~hi], np.broadcast_to(ramp, tex.shape)[~hi])


def test_metal_highlight_only_near_mirror_direction():
    ramp = np.linspace(0, 0.8, 32)
    tex = xtoon.toon_texture_metal(ramp, 20, color=1.0, onset=0.8)
    D = (np.arange(20) + 0.5) / 20
    np.testing.assert_array_equal(tex[D <= 0.8], np.broadcast_to(ramp, tex[D <= 0.8].shape))
    assert np.all(np.diff(tex[:, -1]) >= 0) and tex[-1, -1] > 0.8


def test_builders_keep_float32_and_validate():
    ramp = np.linspace(0, 1, 8, dtype=np.float32)
    for build in (
        lambda: xtoon.toon_texture_blur(ramp, 4, max_sigma=2),
        lambda: xtoon.toon_texture_receding(ramp, 4),
        lambda: xtoon.toon_texture_plastic(ramp, 4),
        lambda: xtoon.toon_texture_metal(ramp, 4),
        lambda: xtoon.toon_texture_backlight(ramp, 4),
        lambda: xtoon.toon_texture_fade(ramp, 4),
    ):
        out = build()
        assert out.dtype == np.float32 and out.shape == (4, 8)
    with pytest.raises(ValueError, match=r"rows: expected an integer in \[1, inf\], got 0"):
        xtoon.toon_texture_blur(ramp, 0, max_sigma=1)
    with pytest.raises(ValueError, match=r"ramp: expected a 1D toon ramp"):
        xtoon.toon_texture_blur(np.zeros((2, 2, 2)), 3, max_sigma=1)


# ---------------------------------------------------------------------------------------------
# shape abstraction (sec. 4)

unit3 = hnp.arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(
    lambda v: np.linalg.norm(v) > 1e-3
)


@given(n=unit3, a=unit3, w=st.floats(0, 1))
def test_blend_normals_unit_endpoints_and_loop(n, a, w):
    out = xtoon.blend_normals(n, a, w)
    assert abs(np.linalg.norm(out) - 1) < 1e-12
    nh, ah = n / np.linalg.norm(n), a / np.linalg.norm(a)
    np.testing.assert_allclose(xtoon.blend_normals(n, a, 0.0), nh, atol=1e-15)
    np.testing.assert_allclose(xtoon.blend_normals(n, a, 1.0), ah, atol=1e-15)
    m = [(1 - w) * nh[k] + w * ah[k] for k in range(3)]
    norm = math.sqrt(sum(v * v for v in m))
    if norm > 1e-9:
        np.testing.assert_allclose(out, [v / norm for v in m], atol=1e-12)
        # the blend moves monotonically towards the abstract normal
        later = xtoon.blend_normals(n, a, min(1.0, w + 0.1))
        assert later @ ah >= out @ ah - 1e-12


def test_blend_normals_unnormalized_per_vertex_form():
    rng = np.random.default_rng(11)
    n, a, w = rng.normal(size=(5, 3)), rng.normal(size=(5, 3)), rng.uniform(0, 1, 5)
    raw = xtoon.blend_normals(n, a, w, normalize=False)
    nh = n / np.linalg.norm(n, axis=1, keepdims=True)
    ah = a / np.linalg.norm(a, axis=1, keepdims=True)
    np.testing.assert_allclose(raw, (1 - w)[:, None] * nh + w[:, None] * ah, atol=1e-15)
    np.testing.assert_allclose(
        xtoon.blend_normals(n, a, w), raw / np.linalg.norm(raw, axis=1, keepdims=True), atol=1e-15
    )


def test_blend_normals_opposite_fallback_broadcast_and_errors():
    n = np.array([[0, 0, 1.0]])
    out = xtoon.blend_normals(n, -n, np.array([0.49, 0.5, 0.51]))
    assert out.shape == (3, 3)
    np.testing.assert_allclose(out[0], [0, 0, 1])
    np.testing.assert_allclose(out[1:], [[0, 0, -1]] * 2)
    f32 = xtoon.blend_normals(n.astype(np.float32), n.astype(np.float32), 0.5)
    assert f32.dtype == np.float32
    with pytest.raises(ValueError, match=r"weight: expected values in \[0, 1\]"):
        xtoon.blend_normals(n, n, 1.5)
    with pytest.raises(ValueError, match=r"n_abstract: expected non-zero vectors"):
        xtoon.blend_normals(n, np.zeros(3), 0.5)
    with pytest.raises(ValueError, match=r"n: expected shape \(\.\.\., 3\)"):
        xtoon.blend_normals(np.ones(2), n, 0.5)


def latlong_ellipsoid(a, rot=None, center=None):
    """Points on an ellipsoid with extremes on its axes, hull-triangulated; analytic normals."""
    rot = np.eye(3) if rot is None else rot
    center = np.zeros(3) if center is None else center
    th, ph = np.meshgrid(np.linspace(0, np.pi, 9)[1:-1], np.linspace(0, 2 * np.pi, 16, False))
    u = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3)
    u = np.concatenate([u, [[0, 0, 1.0], [0, 0, -1.0]]])
    local = u * a
    hull = trimesh.convex.convex_hull(local)
    order = np.array([np.flatnonzero(np.all(local == v, axis=1))[0] for v in hull.vertices])
    faces = order[hull.faces]
    normals = u / np.asarray(a)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return local @ rot.T + center, faces, normals @ rot.T


def random_rotation(seed):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_ellipsoid_normals_are_analytic_in_any_orientation():
    a = np.array([3.0, 2.0, 1.0])
    p, f, n_true = latlong_ellipsoid(a)
    noisy = n_true + np.random.default_rng(0).normal(0, 0.3, n_true.shape)
    np.testing.assert_allclose(
        xtoon.ellipsoid_normals(p, f, noisy, frame="aabb"), n_true, atol=1e-12
    )
    rot, c = random_rotation(5), np.array([10.0, -4.0, 2.5])
    p2, f2, n2 = latlong_ellipsoid(a, rot, c)
    np.testing.assert_allclose(xtoon.ellipsoid_normals(p2, f2, noisy), n2, atol=1e-9)
    center, axes, half = xtoon.shape_frame(p2, f2)
    np.testing.assert_allclose(center, c, atol=1e-9)
    np.testing.assert_allclose(half, a, atol=1e-9)
    np.testing.assert_allclose(np.abs(axes @ rot), np.eye(3), atol=1e-9)


def test_sphere_normals_and_fallback_at_centre():
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    p = mesh.vertices + [1.0, 2.0, 3.0]
    out = xtoon.sphere_normals(p, mesh.faces, -mesh.vertex_normals)
    np.testing.assert_allclose(out, mesh.vertices / 2.0, atol=1e-9)
    p = np.array([[-1.0, 0, 0], [1.0, 0, 0], [0, 0, 0], [0, 1.0, 0], [0, -1.0, 0]])
    out = xtoon.sphere_normals(p, np.array([[0, 1, 3], [0, 4, 1]]), np.tile([0, 0, 2.0], (5, 1)))
    np.testing.assert_allclose(out[2], [0, 0, 1])  # vertex at the centre keeps its normal


def test_cylinder_normals_radial_about_principal_axis():
    mesh = trimesh.creation.cylinder(radius=1.0, height=5.0, sections=12)
    rot = random_rotation(2)
    p = mesh.vertices @ rot.T
    n = mesh.vertex_normals @ rot.T
    out = xtoon.cylinder_normals(p, mesh.faces, n)
    rho = np.linalg.norm(mesh.vertices[:, :2], axis=1)
    side = rho > 0.5
    radial = mesh.vertices[side, :2] / rho[side, None]
    expect = np.concatenate([radial, np.zeros((side.sum(), 1))], 1) @ rot.T
    np.testing.assert_allclose(out[side], expect, atol=1e-9)
    np.testing.assert_allclose(out[~side], n[~side], atol=1e-12)  # cap centres: on the axis
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, atol=1e-12)


def naive_smooth_once(n: np.ndarray, faces: np.ndarray) -> np.ndarray:
    nbrs = [set() for _ in range(len(n))]
    for tri in faces:
        for a in tri:
            for b in tri:
                if a != b:
                    nbrs[a].add(int(b))
    out = np.zeros_like(n)
    for i in range(len(n)):
        acc = n[i] + sum((n[j] for j in nbrs[i]), np.zeros(3))
        out[i] = acc / np.linalg.norm(acc)
    return out


def test_smoothed_normals_match_loop_and_smooth():
    mesh = trimesh.creation.icosphere(subdivisions=2)
    rng = np.random.default_rng(1)
    noisy = mesh.vertex_normals + rng.normal(0, 0.4, mesh.vertices.shape)
    unit = noisy / np.linalg.norm(noisy, axis=1, keepdims=True)
    once = xtoon.smoothed_normals(mesh.vertices, mesh.faces, noisy, iterations=1)
    np.testing.assert_allclose(once, naive_smooth_once(unit, mesh.faces), atol=1e-12)
    np.testing.assert_allclose(
        xtoon.smoothed_normals(mesh.vertices, mesh.faces, noisy, iterations=0), unit, atol=1e-15
    )

    def err(x):
        return np.mean(np.arccos(np.clip(np.sum(x * mesh.vertex_normals, 1), -1, 1)))

    assert err(once) < err(unit)
    more = xtoon.smoothed_normals(mesh.vertices, mesh.faces, noisy, weighting="inverse_length")
    assert np.allclose(np.linalg.norm(more, axis=1), 1)


def test_smoothed_normals_weld_crosses_duplicated_seams():
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    f = np.array([[0, 1, 2], [3, 5, 4]])  # two triangles, seam vertices duplicated
    n = np.array([[0, 0, 1.0], [0, 0, 1], [0, 0, 1], [1, 0, 0], [1, 0, 0], [1, 0, 0]])
    welded = xtoon.smoothed_normals(p, f, n, iterations=1)
    split = xtoon.smoothed_normals(p, f, n, iterations=1, weld_tol=None)
    np.testing.assert_allclose(welded[1], welded[3])
    np.testing.assert_allclose(split[5], [1, 0, 0])
    assert welded[5][2] > 0  # smoothing reached across the seam


def test_mesh_input_errors():
    p = np.zeros((3, 3))
    with pytest.raises(ValueError, match=r"faces: indices must lie in \[0, 2\], got min 0, max 3"):
        xtoon.sphere_normals(p, np.array([[0, 1, 3]]), p)
    with pytest.raises(ValueError, match=r"normals: expected shape \(3, 3\)"):
        xtoon.sphere_normals(p, np.array([[0, 1, 2]]), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"frame: expected 'pca' or 'aabb', got 'obb'"):
        xtoon.ellipsoid_normals(p, np.array([[0, 1, 2]]), p, frame="obb")


# ---------------------------------------------------------------------------------------------
# numerical stress


@pytest.mark.stress
@given(
    z_min=st.floats(1e-6, 1e6),
    r=st.floats(1.0 + 1e-6, 1e6),
    ulps=st.integers(-4, 4),
)
def test_stress_depth_at_the_edges_float32(z_min, r, ulps):
    z_max = r * z_min
    eps = np.finfo(np.float64).eps
    z = np.array([z_min, z_max, np.inf, z_min * (1 + ulps * eps), z_max * (1 + ulps * eps)])
    for dt in (np.float64, np.float32):
        zz = z.astype(dt)
        zz = zz[zz > 0]
        d = xtoon.detail_depth(zz, z_min, r)
        assert d.dtype == dt and np.all(np.isfinite(d)) and np.all((d >= 0) & (d <= 1))
    z32 = np.float32(z_min)  # D = 1 at and below z_min, whatever the dtype
    assert xtoon.detail_depth(z32, max(z_min, float(z32)), r) == 1.0
    assert xtoon.detail_depth(z_min, z_min, r) == 1.0
    # float32 in -> float32 out: the float64 result rounded once (the arithmetic is float64)
    zs = np.geomspace(z_min, z_max, 50).astype(np.float32)
    d64 = xtoon.detail_depth(zs.astype(np.float64), z_min, r)
    d32 = xtoon.detail_depth(zs, z_min, r)
    assert np.array_equal(d32, d64.astype(np.float32))


@pytest.mark.stress
@given(z_min=st.floats(1e-4, 1e3), r=st.floats(1.0001, 50.0), margin=st.floats(1e-6, 1e3))
def test_stress_focus_finite_float32(z_min, r, margin):
    z_c = r * z_min + margin
    z = np.concatenate(
        [np.geomspace(1e-6, 1e7, 64), [z_c, z_c - z_min, z_c + z_min, z_c + r * z_min, np.inf]]
    )
    for dt in (np.float64, np.float32):
        zz = z.astype(dt)
        d = xtoon.detail_focus(zz[zz > 0], z_c, z_min, r)
        assert d.dtype == dt and np.all(np.isfinite(d)) and np.all((d >= 0) & (d <= 1))
    assert xtoon.detail_focus(z_c, z_c, z_min, r) == 1.0
    z32 = np.float32(z_c)  # float32 in: the float64 result of the float32 value, rounded once
    d32 = xtoon.detail_focus(z32, z_c, z_min, r)
    assert d32 == np.float32(xtoon.detail_focus(float(z32), z_c, z_min, r))


def test_blend_normals_extreme_lengths_stay_unit():
    big = np.array([1e20, 0.0, 0.0], np.float32)
    tiny = np.array([1e-30, 0.0, 0.0], np.float32)
    up = np.array([0.0, 0.0, 1.0], np.float32)
    np.testing.assert_allclose(xtoon.blend_normals(big, big, np.float32(0.5)), [1, 0, 0], atol=1e-6)
    out = xtoon.blend_normals(tiny, up, np.float32(0.5))
    np.testing.assert_allclose(out, np.array([1, 0, 1]) / np.sqrt(2), atol=1e-6)


def test_toon_lookup_refuses_a_texture_without_channels():
    with pytest.raises(ValueError, match=r"^texture: expected shape \(rows, cols, C\) with C >= 1"):
        xtoon.toon_lookup(np.zeros((2, 2, 0)), 0.5, 0.5)
