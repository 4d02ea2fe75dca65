"""Tests of refnpr.formulas.halftone (Freudenberg, Masuch, Strothotte 2002)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.formulas.halftone import (
    apply_indication,
    binary_threshold,
    decode_stroke_map,
    encode_stroke_map,
    engraving_ramp,
    engraving_screen,
    layer_onsets,
    sample_indication,
    smooth_threshold,
    smooth_threshold_tone,
    stroke_levels,
    stroke_lighting,
    tangent_frame,
)

unit = st.floats(0.0, 1.0, allow_nan=False)
SCREEN = (np.arange(20_000) + 0.5) / 20_000  # a screen uniform on [0, 1]


def mux_py(a: float, b: float, c: float) -> float:
    return b if a <= 0.5 else c  # sec. 3.1: mux(a, b, c) = (a <= 0.5) ? b : c


def binary_py(tex: float, col: float) -> float:
    return mux_py(tex + (col - 0.5), 0.0, 1.0)


def smooth_py(tex: float, col: float, c: float) -> float:
    tmp = (1 - tex - col) * c  # sec. 3.2
    return min(max(1 - tmp, 0.0), 1.0)


# ------------------------------------------------------------------------------ thresholds


def test_binary_threshold_matches_mux_loop():
    rng = np.random.default_rng(1)
    tex = rng.uniform(0, 1, 500)
    col = rng.uniform(-0.2, 1.2, 500)
    col[:10] = 1 - tex[:10]  # ties: screen + intensity == 1 is black
    expect = [binary_py(a, b) for a, b in zip(tex, col, strict=True)]
    np.testing.assert_array_equal(binary_threshold(tex, col), expect)


def test_binary_threshold_preserves_tone_and_dtype():
    for x in np.linspace(0, 1, 11):
        assert binary_threshold(SCREEN, x).mean() == pytest.approx(x, abs=1e-4)
    out = binary_threshold(SCREEN.astype(np.float32), np.float32(0.3))
    assert out.dtype == np.float32


def test_smooth_threshold_matches_naive_loop():
    rng = np.random.default_rng(2)
    tex, col = rng.uniform(0, 1, (2, 500))
    for c in (1.0, 4.0, 9.5):
        expect = [smooth_py(a, b, c) for a, b in zip(tex, col, strict=True)]
        np.testing.assert_allclose(smooth_threshold(tex, col, c), expect, atol=1e-12)
        expect = [min(max(0.5 - (1 - a - b) * c, 0), 1) for a, b in zip(tex, col, strict=True)]
        np.testing.assert_allclose(smooth_threshold(tex, col, c, centred=True), expect, atol=1e-12)


def test_smooth_threshold_paper_breakpoints():
    # one-sided: black at screen + intensity <= 1 - 1/c, white at >= 1 (c = 4 as in the paper)
    assert float(smooth_threshold(0.25, 0.5, 4.0)) == 0.0
    assert float(smooth_threshold(0.5, 0.5, 4.0)) == 1.0
    assert float(smooth_threshold(0.375, 0.5, 4.0)) == pytest.approx(0.5)


@given(unit, unit)
def test_smooth_threshold_tends_to_binary(screen, x):
    gap = abs(screen + x - 1)
    for c in (10.0, 1e3, 1e6):
        for centred in (False, True):
            smooth = float(smooth_threshold(screen, x, c, centred=centred))
            if gap > 1 / c:
                assert smooth == float(binary_threshold(screen, x))


def test_smooth_threshold_mean_difference_to_binary_shrinks_like_one_over_c():
    x = np.linspace(0, 1, 51)[:, None]
    binary = binary_threshold(SCREEN, x)
    for c in (2.0, 8.0, 32.0, 128.0):
        diff = np.abs(smooth_threshold(SCREEN, x, c) - binary).mean()
        assert diff <= 1 / (2 * c) + 1e-4


@pytest.mark.parametrize("c", [2.0, 4.0, 10.0])
def test_smooth_threshold_tone_bias_is_one_over_2c(c):
    # measured on a uniform screen: the paper's form is lighter by 1/(2c); centred has no bias
    xs = np.linspace(0, 1 - 1 / c, 17)
    bias = smooth_threshold(SCREEN, xs[:, None], c).mean(axis=1) - xs
    np.testing.assert_allclose(bias, 1 / (2 * c), atol=1e-6)
    xs = np.linspace(1 / (2 * c), 1 - 1 / (2 * c), 17)
    bias = smooth_threshold(SCREEN, xs[:, None], c, centred=True).mean(axis=1) - xs
    np.testing.assert_allclose(bias, 0.0, atol=1e-6)


@given(st.floats(-0.3, 1.3), st.floats(0.5, 50.0), st.booleans())
def test_smooth_threshold_tone_equals_measured_mean(x, c, centred):
    measured = smooth_threshold(SCREEN, x, c, centred=centred).mean()
    assert float(smooth_threshold_tone(x, c, centred=centred)) == pytest.approx(measured, abs=2e-5)


# ------------------------------------------------------------------------------ stroke maps


def encode_py(layers, levels):
    h, w = layers[0].shape
    out = np.ones((h, w))
    for i in range(h):
        for j in range(w):
            g = 1.0
            for k in reversed(range(len(layers))):  # lightest first, darkest last (on top)
                a = layers[k][i, j]
                g = (1 - a) * g + a * levels[k]
            out[i, j] = g
    return out


def test_encode_stroke_map_matches_naive_loop():
    rng = np.random.default_rng(3)
    layers = rng.uniform(0, 1, (3, 9, 11)) * (rng.uniform(0, 1, (3, 9, 11)) < 0.4)
    np.testing.assert_allclose(encode_stroke_map(layers), encode_py(layers, [0, 1 / 3, 2 / 3]))
    levels = [0.0, 0.5, 0.8]
    np.testing.assert_allclose(
        encode_stroke_map(list(layers), levels=levels), encode_py(layers, levels)
    )


def test_encode_stroke_map_of_float32_layers_is_float32_arithmetic():
    """Float32 layers (the texture builders') encode in float32, as numpy computes them."""
    rng = np.random.default_rng(6)
    layers = (rng.uniform(0, 1, (4, 33, 17)) * (rng.uniform(0, 1, (4, 33, 17)) < 0.5)).astype(
        np.float32
    )
    g = stroke_levels(4)
    want = np.ones((33, 17), np.float32)
    for i in range(3, -1, -1):
        want = (1 - layers[i]) * want + layers[i] * np.float32(g[i])
    got = encode_stroke_map(layers)
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got.view(np.uint32), want.view(np.uint32))


def test_stroke_levels_and_onsets():
    np.testing.assert_allclose(stroke_levels(4), [0, 0.25, 0.5, 0.75])
    np.testing.assert_allclose(layer_onsets(stroke_levels(4)), [1, 0.75, 0.5, 0.25])


@given(st.integers(1, 5), st.integers(0, 2**32 - 1))
def test_stroke_map_round_trip(m, seed):
    # binary layers: decoding at an intensity between the onsets of layers i and i + 1 draws
    # exactly the union of layers 0..i (Fig. 4: darker regions add lighter-encoded layers)
    rng = np.random.default_rng(seed)
    layers = (rng.uniform(0, 1, (m, 12, 12)) < 0.3).astype(float)
    screen = encode_stroke_map(layers)
    onsets = layer_onsets(stroke_levels(m))
    bounds = [*onsets, 0.0]
    assert np.all(decode_stroke_map(screen, 1.0 + 1e-9) == 1)
    for i in range(m):
        x = (bounds[i] + bounds[i + 1]) / 2
        black = decode_stroke_map(screen, x) == 0
        np.testing.assert_array_equal(black, layers[: i + 1].max(axis=0) == 1)


@given(st.integers(1, 4), st.integers(0, 2**32 - 1), st.sampled_from([None, 4.0, 20.0]))
def test_stroke_visibility_is_nested_in_intensity(m, seed, c):
    rng = np.random.default_rng(seed)
    layers = rng.uniform(0, 1, (m, 10, 10)) * (rng.uniform(0, 1, (m, 10, 10)) < 0.5)
    screen = encode_stroke_map(layers)
    xs = np.linspace(0, 1, 41)
    out = decode_stroke_map(screen, xs[:, None, None], c=c)
    # what is visible (dark) at an intensity stays at least as dark at every darker intensity
    assert np.all(np.diff(out, axis=0) >= 0)


def test_stroke_map_layers_appear_in_order_of_darkness():
    layers = np.zeros((3, 1, 3))
    layers[0, 0, 0] = layers[1, 0, 1] = layers[2, 0, 2] = 1
    screen = encode_stroke_map(layers)
    assert decode_stroke_map(screen, 0.9).tolist() == [[0.0, 1.0, 1.0]]  # darkest layer only
    assert decode_stroke_map(screen, 0.5).tolist() == [[0.0, 0.0, 1.0]]
    assert decode_stroke_map(screen, 0.2).tolist() == [[0.0, 0.0, 0.0]]
    # at full intensity the binary threshold still draws the darkest layer (0 + 1 is not > 1);
    # the paper's smooth threshold turns it white (1 - c (1 - 0 - 1) = 1)
    assert decode_stroke_map(screen, 1.0).tolist() == [[0.0, 1.0, 1.0]]
    assert decode_stroke_map(screen, 1.0, c=4.0).tolist() == [[1.0, 1.0, 1.0]]


# --------------------------------------------------------------------------- special effects


def test_apply_indication_and_engraving_match_naive_loops():
    rng = np.random.default_rng(5)
    x = rng.uniform(-0.2, 1.2, 200)
    ind = rng.uniform(-1, 1, 200)
    expect = [min(max(a + b, 0.0), 1.0) for a, b in zip(x, ind, strict=True)]
    np.testing.assert_allclose(apply_indication(x, ind), expect)
    v = rng.uniform(-10, 10, 200)
    f = [a - math.floor(a) for a in v]
    np.testing.assert_allclose(engraving_screen(v), f, atol=1e-12)
    np.testing.assert_allclose(
        engraving_screen(v, profile="triangle"), [abs(2 * a - 1) for a in f], atol=1e-12
    )


def test_apply_indication_values():
    x = np.array([0.2, 0.5, 0.9, 0.4])
    ind = np.array([0.0, 0.3, 0.3, -0.6])
    np.testing.assert_allclose(apply_indication(x, ind), [0.2, 0.8, 1.0, 0.0])
    np.testing.assert_array_equal(apply_indication(x, 0.0), x)


def test_stroke_lighting_matches_naive_loop():
    rng = np.random.default_rng(4)
    rgb = rng.uniform(0, 1, (50, 3))
    light = np.array([0.3, -0.5, 0.8])
    lu = light / np.linalg.norm(light)
    out = stroke_lighting(rgb, light)
    for p in range(50):
        n = [2 * c - 1 for c in rgb[p]]
        d = sum(a * b for a, b in zip(n, lu, strict=True))
        assert out[p] == pytest.approx(min(max(d, 0), 1), abs=1e-12)
    flat = np.array([0.5, 0.5, 1.0])  # encodes (0, 0, 1)
    assert float(stroke_lighting(flat, [0, 0, 2])) == 1.0
    tilt = math.radians(60)
    assert float(stroke_lighting(flat, [math.sin(tilt), 0, math.cos(tilt)])) == pytest.approx(0.5)


def naive_indication(imap: np.ndarray, u: float, v: float) -> float:
    """Bilinear, clamp-to-edge, texel centres at (i + 1/2) / size: by the book."""
    rows, cols = imap.shape
    x = min(max(u * cols - 0.5, 0.0), cols - 1.0)
    y = min(max(v * rows - 0.5, 0.0), rows - 1.0)
    i0, j0 = int(math.floor(x)), int(math.floor(y))
    i1, j1 = min(i0 + 1, cols - 1), min(j0 + 1, rows - 1)
    a, b = x - i0, y - j0
    top = (1 - a) * imap[j0, i0] + a * imap[j0, i1]
    bottom = (1 - a) * imap[j1, i0] + a * imap[j1, i1]
    return (1 - b) * top + b * bottom


def test_sample_indication_matches_naive_loop_and_its_texels():
    rng = np.random.default_rng(8)
    imap = rng.uniform(-1, 1, (3, 5))
    uv = rng.uniform(-0.3, 1.3, (300, 2))
    want = [naive_indication(imap, u, v) for u, v in uv]
    np.testing.assert_allclose(sample_indication(imap, uv), want, atol=1e-12)
    centres = np.array([[(i + 0.5) / 5, (j + 0.5) / 3] for j in range(3) for i in range(5)])
    np.testing.assert_allclose(sample_indication(imap, centres), imap.ravel(), atol=1e-12)
    with pytest.raises(ValueError, match=r"indication_map: expected a \(rows, cols\) map"):
        sample_indication([0.1, 0.2], uv)
    with pytest.raises(ValueError, match=r"indication_map: expected values in \[-1.0, 1.0\]"):
        sample_indication([[2.0]], uv)


def _random_frames(seed: int, k: int):
    """k random unit normals, position and uv derivatives: ``(n, dpdx, dpdy, dudx, dudy)``."""
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(k, 3))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return n, rng.normal(size=(k, 3)), rng.normal(size=(k, 3)), *rng.normal(size=(2, k, 2))


def test_tangent_frame_matches_the_solved_jacobian():
    n, dpdx, dpdy, dudx, dudy = _random_frames(9, 200)
    t, b, valid = tangent_frame(n, dpdx, dpdy, dudx, dudy)
    assert valid.all()
    for k in range(200):  # [dP/dx dP/dy] = [dP/du dP/dv] J, then Gram-Schmidt against N
        jac = np.array([[dudx[k, 0], dudy[k, 0]], [dudx[k, 1], dudy[k, 1]]])
        pu, pv = (np.stack([dpdx[k], dpdy[k]], axis=1) @ np.linalg.inv(jac)).T
        tk = pu - (pu @ n[k]) * n[k]
        tk /= np.linalg.norm(tk)
        bk = pv - (pv @ n[k]) * n[k] - (pv @ tk) * tk
        np.testing.assert_allclose(t[k], tk, atol=1e-9)
        np.testing.assert_allclose(b[k], bk / np.linalg.norm(bk), atol=1e-9)
    singular = tangent_frame(n[:1], dpdx[:1], dpdy[:1], [[1.0, 2.0]], [[2.0, 4.0]])
    assert not singular[2][0] and not singular[0].any() and not singular[1].any()


def test_tangent_frame_is_orthonormal_with_the_unit_normal():
    n, dpdx, dpdy, dudx, dudy = _random_frames(10, 300)
    t, b, valid = tangent_frame(n, dpdx, dpdy, dudx, dudy)
    assert valid.all()
    for u, v in ((t, n), (b, n), (t, b)):
        np.testing.assert_allclose(np.einsum("ij,ij->i", u, v), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(t, axis=-1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(b, axis=-1), 1.0, rtol=1e-12)
    # a G-buffer normal is a unit vector rounded to float32: accepted as it is
    assert tangent_frame(n.astype(np.float32), dpdx, dpdy, dudx, dudy)[2].all()


@pytest.mark.parametrize(
    "normal, length",
    [
        ([0.0, 0.0, 2.0], r"2\.0"),
        ([0.0, 0.0, 1e200], r"1e\+200"),
        ([0.0, 0.0, 1e-200], r"1e-200"),
        ([0.0, 0.0, 0.0], r"0\.0"),
        ([0.6, 0.8, 1e-2], r"1\.00004999"),
    ],
)
def test_tangent_frame_refuses_a_normal_that_is_not_unit(normal, length):
    """Gram-Schmidt against N projects onto the tangent plane only for a unit N (N = (0, 0, 2)
    would give T.N = -1.9 with a valid frame)."""
    match = rf"^normal: expected unit vectors \(length 1 within 1e-05\), got .* of length {length}"
    with pytest.raises(ValueError, match=match):
        tangent_frame(normal, [1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [1.0, 0.0], [0.0, 1.0])
    with pytest.raises(ValueError, match=r"at index \(1,\)"):
        tangent_frame(
            [[0.0, 0.0, 1.0], normal], [1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [1.0, 0.0], [0.0, 1.0]
        )


@pytest.mark.parametrize(
    "face, args",
    [
        (binary_threshold, (0.3, 0.7000000000000001)),
        (smooth_threshold, (0.3, 0.55, 4.0, True)),
        (apply_indication, (0.4, -0.7)),
    ],
)
def test_device_functions_are_the_faces(face, args):
    """The kernels call ``f.scalar``; the numpy face gives its value, bit for bit."""
    kwargs = {"centred": args[3]} if face is smooth_threshold else {}
    assert float(face(*args[:3] if kwargs else args, **kwargs)) == face.scalar(*args)


def test_stroke_lighting_thins_strokes_on_the_lit_side():
    # a stroke across x in [-1, 1] with a rounded (ridge) normal profile; light from +x
    x = np.linspace(-1, 1, 201)
    normals = np.stack([np.sin(x), np.zeros_like(x), np.cos(x)], -1)
    lit = stroke_lighting(normals, [1.0, 0.0, 1.0], encoded=False)
    black = binary_threshold(0.35, lit) == 0  # the stroke's screen value is 0.35
    assert black[x < -0.5].all() and not black[x > 0.5].any()


@pytest.mark.parametrize("profile", ["ramp", "triangle"])
def test_engraving_screen_preserves_tone(profile):
    v = (np.arange(20_000) + 0.5) / 20_000 * 5
    scr = engraving_screen(v, profile=profile)
    for x in (0.1, 0.5, 0.8):
        assert binary_threshold(scr, x).mean() == pytest.approx(x, abs=1e-3)


def test_engraving_triangle_lines_are_centred_with_width_one_minus_intensity():
    v = (np.arange(10_000) + 0.5) / 10_000
    for x in (0.2, 0.6):
        black = binary_threshold(engraving_screen(v, profile="triangle"), x) == 0
        assert abs(v[black].mean() - 0.5) < 1e-3
        assert black.mean() == pytest.approx(1 - x, abs=1e-3)


def test_engraving_ramp_texels():
    np.testing.assert_allclose(engraving_ramp(4), [0.125, 0.375, 0.625, 0.875])
    np.testing.assert_allclose(engraving_ramp(4, profile="triangle"), [0.75, 0.25, 0.25, 0.75])


# ---------------------------------------------------------------------------------- bad input


def test_bad_parameters_raise_clear_errors():
    with pytest.raises(ValueError, match="c: expected a value in \\(0, inf\\], got 0.0"):
        smooth_threshold(0.5, 0.5, 0.0)
    with pytest.raises(ValueError, match="c: expected a value in \\(0, inf\\], got -2.0"):
        smooth_threshold_tone(0.5, -2.0)
    with pytest.raises(ValueError, match="screen, intensity: shapes do not broadcast"):
        binary_threshold(np.zeros(3), np.zeros(2))
    with pytest.raises(ValueError, match="intensity: must be finite, got nan"):
        smooth_threshold(0.5, np.nan)
    with pytest.raises(ValueError, match=r"layers\[0\]: expected values in \[0.0, 1.0\]"):
        encode_stroke_map(np.full((2, 3, 3), 2.0))
    with pytest.raises(ValueError, match="levels: expected strictly increasing values"):
        encode_stroke_map(np.zeros((2, 3, 3)), levels=[0.5, 0.2])
    with pytest.raises(ValueError, match="levels: expected 2 grey levels"):
        encode_stroke_map(np.zeros((2, 3, 3)), levels=[0.0, 0.2, 0.4])
    with pytest.raises(ValueError, match="layers: got no stroke layers"):
        encode_stroke_map([])
    with pytest.raises(ValueError, match="m: expected an integer in \\[1, inf\\], got 0"):
        stroke_levels(0)
    with pytest.raises(ValueError, match="indication: expected values in \\[-1.0, 1.0\\]"):
        apply_indication(0.5, 1.5)
    with pytest.raises(ValueError, match=r"normal_map: expected shape \(\.\.\., 3\)"):
        stroke_lighting(np.zeros((4, 2)), [0, 0, 1])
    with pytest.raises(ValueError, match="profile: expected one of \\('ramp', 'triangle'\\)"):
        engraving_screen(0.3, profile="sine")


@pytest.mark.stress
@given(st.floats(-1e30, 1e30), st.floats(-1e3, 1e3), st.floats(1e-6, 1e6))
def test_stress_extremes_stay_finite_and_in_range(v, x, c):
    for dtype in (np.float32, np.float64):
        vv = np.array([v, -v], dtype=dtype)
        vv = np.where(np.isfinite(vv), vv, 0).astype(dtype)
        xx = np.array([x, 0.5], dtype=dtype)
        for out in (
            engraving_screen(vv),
            engraving_screen(vv, profile="triangle"),
            smooth_threshold(engraving_screen(vv), xx, c),
            smooth_threshold(engraving_screen(vv), xx, c, centred=True),
            smooth_threshold_tone(xx, c),
        ):
            assert out.dtype == dtype
            assert np.all(np.isfinite(out)) and np.all((out >= 0) & (out <= 1))
        s32 = smooth_threshold(np.float32(0.3), xx.astype(np.float32), c)
        s64 = smooth_threshold(0.3, xx.astype(np.float32).astype(np.float64), c)
        # documented float32 bound: the ramp amplifies a rounding of the sum by c
        assert np.all(np.abs(s32 - s64) <= 4e-7 * max(c, 1.0) * (1 + np.abs(xx)))
