"""Tests of refnpr.formulas.lighting (Veryovka 2002 eq. 1, Lake et al. 2000 toon ramp)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.formulas.lighting import (
    ambient,
    diffuse,
    illumination,
    luminance,
    specular,
    toon_ramp,
    toon_ramp_texture,
)

comp = st.floats(-1.0, 1.0, allow_nan=False)
vec = st.tuples(comp, comp, comp).filter(lambda v: math.hypot(*v) > 1e-3)


def unit_py(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def dot_py(a, b):
    return sum(x * y for x, y in zip(a, b, strict=True))


def specular_py(n, l, v, p, model):
    n, l, v = unit_py(n), unit_py(l), unit_py(v)
    if dot_py(n, l) <= 0:
        return 0.0
    if model == "phong":
        r = [2 * dot_py(n, l) * a - b for a, b in zip(n, l, strict=True)]
        base = dot_py(r, v)
    else:
        h = [a + b for a, b in zip(l, v, strict=True)]
        if math.hypot(*h) == 0:
            return 0.0
        base = dot_py(n, unit_py(h))
    return max(base, 0.0) ** p


def test_diffuse_matches_naive_loop_and_broadcasts_lights():
    rng = np.random.default_rng(1)
    normals = rng.normal(size=(6, 7, 3))
    lights = rng.normal(size=(4, 3))
    out = diffuse(normals[..., None, :], lights)
    assert out.shape == (6, 7, 4)
    for i in range(6):
        for j in range(7):
            for k in range(4):
                expect = max(dot_py(unit_py(normals[i, j]), unit_py(lights[k])), 0.0)
                assert out[i, j, k] == pytest.approx(expect, abs=1e-12)


@given(vec, vec, st.floats(0.01, 100.0))
def test_diffuse_is_scale_invariant_and_in_unit_range(n, l, scale):
    a = float(diffuse(n, l))
    assert 0.0 <= a <= 1.0
    assert float(diffuse(np.array(n) * scale, l)) == pytest.approx(a, abs=1e-12)


def test_diffuse_zero_vector_gives_zero_and_unnormalized_option():
    assert float(diffuse([0, 0, 0], [0, 0, 1])) == 0.0
    assert float(diffuse([0, 0, 2], [0, 0, 3], normalize=False)) == 6.0
    assert diffuse(np.ones((2, 3), np.float32), np.float32([0, 0, 1])).dtype == np.float32


@pytest.mark.parametrize("model", ["blinn-phong", "phong"])
@given(vec, vec, vec, st.floats(0.5, 64.0))
def test_specular_matches_naive_loop(model, n, l, v, p):
    got = float(specular(n, l, v, shininess=p, model=model))
    assert got == pytest.approx(specular_py(n, l, v, p, model), abs=1e-9)


def test_specular_values():
    n = [0, 0, 1]
    # mirror configuration: both models give 1
    for model in ("blinn-phong", "phong"):
        assert float(specular(n, [1, 0, 1], [-1, 0, 1], shininess=20, model=model)) == (
            pytest.approx(1.0)
        )
        # light below the horizon: 0 even if the eye sees the reflection
        assert float(specular(n, [1, 0, -0.1], [-1, 0, 0.1], shininess=5, model=model)) == 0.0
    # eye along the normal, light at 60 degrees: Phong R.V = cos 60, Blinn N.H = cos 30
    l = [math.sin(math.pi / 3), 0, math.cos(math.pi / 3)]
    assert float(specular(n, l, n, shininess=2, model="phong")) == pytest.approx(0.25)
    assert float(specular(n, l, n, shininess=2)) == pytest.approx(0.75)


def test_ambient_and_illumination_match_naive_loop():
    assert float(ambient(0.5, 0.4)) == pytest.approx(0.2)
    np.testing.assert_allclose(ambient([0.5, 1.0, 0.0], 0.4), [0.2, 0.4, 0.0])
    rng = np.random.default_rng(2)
    fd = list(rng.uniform(0, 1, (3, 20)))
    fs = list(rng.uniform(0, 1, (3, 20)))
    m_a, l_a = [0.1, 0.2, 0.3], [1.0, 0.5, 0.5]
    m_d, m_s = [0.9, 0.6, 0.3], 0.5
    ls = [[1.0, 1.0, 1.0], 0.5, [0.2, 0.4, 0.6]]
    out = illumination(
        fd,
        fs,
        m_a=np.array(m_a),
        l_a=np.array(l_a),
        m_d=np.array(m_d),
        m_s=m_s,
        l=[np.array(c) if isinstance(c, list) else c for c in ls],
    )
    assert out.shape == (20, 3)
    for p in range(20):
        for c in range(3):
            expect = m_a[c] * l_a[c]
            for i in range(3):
                lc = ls[i][c] if isinstance(ls[i], list) else ls[i]
                expect += m_d[c] * fd[i][p] * lc + m_s * fs[i][p] * lc  # eq. 1
            assert out[p, c] == pytest.approx(expect, abs=1e-12)
    grey = illumination(fd[0], None, m_a=0.1, l_a=1.0, m_d=0.5)
    np.testing.assert_allclose(grey, 0.1 + 0.5 * fd[0])


def test_toon_ramp_texture_and_lookup_match_naive_loop():
    boundaries = [0.25, 0.6]
    tones = [0.1, 0.5, 1.0]
    ramp = toon_ramp_texture(boundaries, tones, size=20)
    expect = [tones[sum(b <= (i + 0.5) / 20 for b in boundaries)] for i in range(20)]
    np.testing.assert_array_equal(ramp, expect)
    x = np.linspace(-0.5, 1.5, 401)
    out = toon_ramp(x, ramp)
    for a, o in zip(x, out, strict=True):
        texel = min(int(math.floor(min(max(a, 0.0), 1.0) * 20)), 19)
        assert o == ramp[texel]
    # hard-edged n-tone shading: only the ramp's tones, changing exactly at the boundaries
    assert set(np.unique(out).tolist()) == set(tones)
    np.testing.assert_array_equal(toon_ramp([0.2499, 0.25, 0.5999, 0.6], ramp), [0.1, 0.5, 0.5, 1])


def test_toon_ramp_rgb_and_lake_two_tone():
    ramp = toon_ramp_texture([0.5], [[0.2, 0.1, 0.0], [1.0, 0.9, 0.8]], size=2)
    assert ramp.shape == (2, 3)
    np.testing.assert_array_equal(toon_ramp([0.2, 0.7], ramp), [[0.2, 0.1, 0.0], [1.0, 0.9, 0.8]])


def test_bad_parameters_raise_clear_errors():
    with pytest.raises(ValueError, match=r"normal: expected shape \(\.\.\., 3\)"):
        diffuse(np.zeros((4, 2)), [0, 0, 1])
    with pytest.raises(ValueError, match="normal, light: shapes do not broadcast"):
        diffuse(np.zeros((4, 3)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="shininess: expected a value in \\(0, inf\\], got 0.0"):
        specular([0, 0, 1], [0, 0, 1], [0, 0, 1], shininess=0.0)
    with pytest.raises(ValueError, match="model: expected one of"):
        specular([0, 0, 1], [0, 0, 1], [0, 0, 1], shininess=8, model="cook-torrance")
    with pytest.raises(ValueError, match="l: expected one light colour or 2"):
        illumination([0.5, 0.5], None, l=[1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="colours have different channel counts"):
        illumination(0.5, None, m_d=[1.0, 1.0, 1.0], l=[1.0, 1.0])
    with pytest.raises(ValueError, match="boundaries: expected a 1-D increasing sequence"):
        toon_ramp_texture([0.6, 0.3], [0, 0.5, 1])
    with pytest.raises(ValueError, match=r"tones: expected shape \(3,\) or \(3, C\)"):
        toon_ramp_texture([0.3, 0.6], [0, 1])
    with pytest.raises(ValueError, match="size: expected an integer in \\[1, inf\\], got 0"):
        toon_ramp_texture([0.5], [0, 1], size=0)
    with pytest.raises(ValueError, match="n_dot_l: must be finite"):
        toon_ramp(np.nan, np.array([0.0, 1.0]))


@pytest.mark.stress
@given(st.tuples(*[st.floats(-1e30, 1e30)] * 3), st.floats(1e-3, 1e4))
def test_stress_extreme_vectors_stay_finite(n, p):
    for dtype in (np.float32, np.float64):
        nn = np.array(n, dtype=dtype)
        nn = np.where(np.isfinite(nn), nn, 0).astype(dtype)
        light = np.array([0.3, -0.2, 0.9], dtype=dtype)
        for out in (
            diffuse(nn, light),
            specular(nn, light, light[::-1], shininess=p),
            specular(nn, light, light[::-1], shininess=p, model="phong"),
        ):
            assert out.dtype == dtype and np.isfinite(out) and 0 <= out <= 1


unit_comp = st.floats(0.0, 1.0, allow_nan=False)


@given(st.lists(st.tuples(unit_comp, unit_comp, unit_comp, unit_comp), min_size=1, max_size=20))
def test_luminance_sums_r_g_then_b_in_float64(pixels):
    """Oracle: the Python float loop in the documented order (bit for bit), for float64 and
    float32 input (computed in float64), alpha ignored; grey maps to itself within rounding."""
    rgba = np.array(pixels, dtype=np.float64)
    want = [(r * 0.2126 + g * 0.7152) + b * 0.0722 for r, g, b, _ in pixels]
    got = luminance(rgba)
    assert got.dtype == np.float64 and got.shape == (len(pixels),)
    assert got.tolist() == want
    low = rgba.astype(np.float32)
    want32 = [(float(r) * 0.2126 + float(g) * 0.7152) + float(b) * 0.0722 for r, g, b, _ in low]
    assert luminance(low.reshape(1, -1, 4)).ravel().tolist() == want32
    grey = rgba[:, :1].repeat(3, axis=1)
    np.testing.assert_allclose(luminance(grey), rgba[:, 0], rtol=1e-15, atol=1e-16)


def test_luminance_needs_three_channels():
    with pytest.raises(
        ValueError, match=r"rgb: expected an array of shape \(\.\.\., C\) with C >= 3"
    ):
        luminance(np.zeros((4, 2)))


@pytest.mark.parametrize(
    "rgb, error, message",
    [
        (np.array([1 + 1j, 0.5, 0.25]), TypeError, "expected real values, got complex"),
        (np.array(["a", "b", "c"]), TypeError, "expected a real number or numeric array"),
        ("abc", TypeError, "expected a real number or array"),
        ([math.nan, 0.5, 0.25], ValueError, "must be finite, got nan"),
        ([[0.5, math.inf, 0.25, 1.0]], ValueError, "must be finite, got inf"),
    ],
)
def test_luminance_refuses_non_real_or_non_finite_colours(rgb, error, message):
    with pytest.raises(error, match=f"^rgb: {message}"):
        luminance(rgb)


def test_luminance_reads_integer_and_bool_colours_as_float64():
    got = luminance(np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1]]))
    assert got.dtype == np.float64 and got.tolist() == [0.2126, 0.7152, 0.0722]
    assert luminance(np.array([True, True, True])) == (0.2126 + 0.7152) + 0.0722
