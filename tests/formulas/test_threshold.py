"""Tests of refnpr.formulas.threshold (Veryovka 2002): values from the paper, properties, and
agreement with naive Python loops and brute-force oracles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from refnpr.formulas import lighting, threshold
from refnpr.formulas.threshold import (
    combine_thresholds,
    dot_dyadic_scale,
    dot_function,
    dot_threshold,
    dot_tone_table,
    dyadic_remap,
    dyadic_scale,
    dyadic_scale_from_gradient,
    hatch_coordinate,
    hatch_threshold,
    line_coverage,
    line_threshold,
    mip_threshold,
    multiscale_line,
    multiscale_line_cdf,
    pcf_threshold,
    step,
    step_n,
    threshold_illumination,
)

unit = st.floats(0.0, 1.0, allow_nan=False)
finite = st.floats(-1e6, 1e6, allow_nan=False)


# ------------------------------------------------------------------ naive reference (pure Python)


def frac_py(x: float) -> float:
    r = x - math.floor(x)
    return r if r < 1.0 else math.nextafter(1.0, 0.0)  # tiny negative x: true value is below 1


def step_py(x: float, t: float) -> float:
    return 0.0 if x < t else 1.0  # eq. 3


def step_n_py(x: float, t: float, n: int) -> float:
    level = math.floor(x * n) + step_py(x * n - math.floor(x * n), t)  # eq. 4
    return min(level, math.ceil(x * n)) / n  # refnpr's bound (docs/paper-notes.md)


def paper_f_py(v: float, t: float) -> float:
    """Eqs. 7-8 written case by case as printed, f(v) = v on [0, 1)."""
    v = frac_py(v)
    f0 = v
    f1 = 2 * v if v < 0.5 else 2 * v - 1  # eq. 7
    return (1 - t) * f0 + t * f1  # eq. 8


def design_cdf_py(y: float, t: float) -> float:
    """CDF from the density stated in DESIGN: 2/(1+t) on [(1-t)/2, (1+t)/2), 1/(1+t) elsewhere."""
    y = min(max(y, 0.0), 1.0)
    lo, hi = (1 - t) / 2, (1 + t) / 2
    total = min(y, lo) / (1 + t)
    total += max(0.0, min(y, hi) - lo) * 2 / (1 + t)
    total += max(0.0, y - hi) / (1 + t)
    return total


def uniform_f_py(v: float, t: float) -> float:
    return design_cdf_py(paper_f_py(v, t), t)


def line_py(v: float, s: float, uniform: bool = False) -> float:
    k = math.floor(s)
    t = s - k
    vb = frac_py(v * 2.0**k)  # eq. 6
    return uniform_f_py(vb, t) if uniform else paper_f_py(vb, t)


# --------------------------------------------------------------------------- eqs. 3 and 4


def test_step_matches_naive_loop():
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.5, 1.5, 300)
    t = rng.uniform(0, 1, 300)
    x[:5] = t[:5]  # ties: x == t is white (eq. 3: 0 only if x < t)
    expect = [step_py(a, b) for a, b in zip(x, t, strict=True)]
    np.testing.assert_array_equal(step(x, t), expect)


def test_step_broadcasts_and_keeps_float32():
    x = np.linspace(0, 1, 5, dtype=np.float32)
    t = np.array([[0.25], [0.75]], dtype=np.float32)
    out = step(x, t)
    assert out.shape == (2, 5) and out.dtype == np.float32
    assert step(0.3, 0.5).dtype == np.float64


def test_step_preserves_tone_on_fine_threshold_grid():
    # thresholds uniform on (0, 1): mean of T(x, t) over t is x (to the grid spacing)
    n = 4000
    t = (np.arange(n) + 0.5) / n
    for x in np.linspace(0, 1, 41):
        assert abs(step(x, t).mean() - x) <= 1 / n


def test_step_preserves_tone_on_random_thresholds():
    rng = np.random.default_rng(7)
    t = rng.uniform(0, 1, 200_000)
    x = np.linspace(0, 1, 21)[:, None]
    mean = step(x, t).mean(axis=1)
    sigma = np.sqrt(x[:, 0] * (1 - x[:, 0]) / t.size)
    assert np.all(np.abs(mean - x[:, 0]) <= 5 * sigma + 1e-12)


@given(st.integers(1, 12), st.lists(unit, min_size=1, max_size=30), unit)
def test_step_n_takes_only_values_k_over_n(n, xs, t):
    out = step_n(np.array(xs), t, n)
    k = out * n
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)
    assert np.all((k > -0.5) & (k < n + 0.5))


@given(st.integers(1, 12), unit, unit)
def test_step_n_rounds_to_a_bracketing_level(n, x, t):
    out = float(step_n(x, t, n))
    assert out in (math.floor(x * n) / n, math.ceil(x * n) / n)


def test_step_n_full_light_is_white_for_every_threshold():
    # eq. 4 read literally gives (n + 1) / n at x = 1, t = 0; refnpr keeps x = 1 white
    for n in (1, 2, 5):
        np.testing.assert_array_equal(step_n(1.0, np.array([0.0, 0.5, 1.0]), n), 1.0)
    assert float(step_n(0.5, 0.0, 2)) == 0.5 and float(step_n(0.5 + 1e-12, 0.0, 2)) == 1.0


@given(st.integers(1, 12), unit)
def test_step_n_is_monotone_in_x(n, t):
    x = np.linspace(-0.2, 1.2, 2001)
    assert np.all(np.diff(step_n(x, t, n)) >= 0)


def test_step_n_matches_naive_loop():
    rng = np.random.default_rng(2)
    x = rng.uniform(-1, 2, 400)
    t = rng.uniform(0, 1, 400)
    for n in (1, 2, 3, 7):
        expect = [step_n_py(a, b, n) for a, b in zip(x, t, strict=True)]
        np.testing.assert_array_equal(step_n(x, t, n), expect)


@pytest.mark.parametrize("n", [1, 2, 5])
def test_step_n_preserves_tone(n):
    grid = (np.arange(2000) + 0.5) / 2000
    x = np.linspace(0, 1, 33)[:, None]
    np.testing.assert_allclose(step_n(x, grid, n).mean(axis=1), x[:, 0], atol=1 / 2000)
    rng = np.random.default_rng(n)
    t = rng.uniform(0, 1, 100_000)
    np.testing.assert_allclose(step_n(x, t, n).mean(axis=1), x[:, 0], atol=5 * 0.5 / n / 316)


def test_step_n_two_gives_three_colours():
    # paper, eq. 4 / Fig. 1: T_n with n = 2 gives discrete three-colour shading
    x = np.linspace(0, 1, 1001)
    assert set(np.unique(step_n(x, 0.5, 2)).tolist()) == {0.0, 0.5, 1.0}
    assert set(np.unique(step(x, 0.5)).tolist()) == {0.0, 1.0}  # single threshold: 2 colours


# --------------------------------------------------------------------------------- eq. 2


def test_threshold_illumination_matches_naive_loop():
    rng = np.random.default_rng(3)
    fd = [rng.uniform(0, 1, 50), rng.uniform(0, 1, 50)]
    fs = [rng.uniform(0, 1, 50), rng.uniform(0, 1, 50)]
    t = rng.uniform(0, 1, 50)
    ts = rng.uniform(0, 1, 50)
    m_a, l_a = np.array([0.1, 0.2, 0.3]), 0.5
    m_d, m_s = np.array([0.8, 0.5, 0.2]), 0.9
    ls = [np.array([1.0, 0.9, 0.8]), np.array([0.2, 0.3, 0.4])]
    out = threshold_illumination(fd, fs, t, m_a=m_a, l_a=l_a, m_d=m_d, m_s=m_s, l=ls, n=2, t_s=ts)
    assert out.shape == (50, 3)
    for p in range(50):
        for c in range(3):
            i = m_a[c] * l_a  # ambient kept
            for j in range(2):
                i += m_d[c] * step_n_py(fd[j][p], t[p], 2) * ls[j][c]
                i += m_s * step_n_py(fs[j][p], ts[p], 2) * ls[j][c]
            assert out[p, c] == pytest.approx(i, abs=1e-12)


def test_threshold_illumination_half_threshold_is_lake_two_tone():
    # paper sec. 2: a single threshold t = 0.5 (Lake et al.) gives two-tone toon shading
    n_dot_l = np.linspace(-1, 1, 801)
    f_d = lighting.diffuse(np.stack([np.sqrt(1 - n_dot_l**2), 0 * n_dot_l, n_dot_l], -1), [0, 0, 1])
    out = threshold_illumination(f_d, None, 0.5, m_a=0.2, l_a=1.0, m_d=0.8)
    ramp = lighting.toon_ramp_texture([0.5], [0.2, 1.0], size=2)
    np.testing.assert_allclose(out, lighting.toon_ramp(n_dot_l, ramp), atol=1e-12)


def test_threshold_illumination_strength_blends_to_eq1():
    rng = np.random.default_rng(4)
    fd, fs, t = rng.uniform(0, 1, (3, 100))
    cont = lighting.illumination(fd, fs, m_a=0.1, l_a=1.0, m_d=0.7, m_s=0.3)
    zero = threshold_illumination(fd, fs, t, m_a=0.1, l_a=1.0, m_d=0.7, m_s=0.3, strength=0.0)
    full = threshold_illumination(fd, fs, t, m_a=0.1, l_a=1.0, m_d=0.7, m_s=0.3)
    half = threshold_illumination(fd, fs, t, m_a=0.1, l_a=1.0, m_d=0.7, m_s=0.3, strength=0.5)
    np.testing.assert_allclose(zero, cont, atol=1e-12)
    np.testing.assert_allclose(half, (cont + full) / 2, atol=1e-12)


def test_threshold_illumination_errors():
    with pytest.raises(
        ValueError, match="n: expected an integer in \\[1, 9007199254740992\\], got 0"
    ):
        threshold_illumination(0.5, None, 0.5, n=0)
    with pytest.raises(ValueError, match="strength: expected values in \\[0.0, 1.0\\]"):
        threshold_illumination(0.5, None, 0.5, strength=1.5)
    with pytest.raises(ValueError, match="f_s: expected 2 specular terms"):
        threshold_illumination([0.5, 0.4], [0.1], 0.5)
    with pytest.raises(ValueError, match="shapes do not broadcast"):
        threshold_illumination(np.zeros(3), None, np.zeros(4))


# ---------------------------------------------------------------------------- eqs. 5 and 6


def test_dyadic_scale_values_and_naive_loop():
    assert dyadic_scale(16.0, 8.0) == 1.0
    assert dyadic_scale(8.0, 8.0) == 0.0
    assert dyadic_scale(2.0, 8.0) == -2.0
    rng = np.random.default_rng(5)
    d = rng.uniform(0.01, 1000, 200)
    w = rng.uniform(0.5, 20, 200)
    np.testing.assert_allclose(
        dyadic_scale(d, w), [math.log2(a / b) for a, b in zip(d, w, strict=True)], rtol=1e-12
    )


def test_dyadic_scale_from_gradient_is_eq5_with_isoline_spacing():
    rng = np.random.default_rng(6)
    gx, gy = rng.normal(size=(2, 100))
    np.testing.assert_allclose(
        dyadic_scale_from_gradient(gx, gy, 8.0), dyadic_scale(1 / np.hypot(gx, gy), 8.0), 1e-12
    )
    s = dyadic_scale_from_gradient(0.0, 0.0, 8.0)
    assert np.isfinite(s) and s > 1000


def test_dyadic_remap_matches_naive_loop():
    rng = np.random.default_rng(8)
    v = rng.uniform(-50, 50, 300)
    s = rng.uniform(-6, 12, 300)
    expect = [frac_py(a * 2.0 ** math.floor(b)) for a, b in zip(v, s, strict=True)]
    np.testing.assert_allclose(dyadic_remap(v, s), expect, atol=1e-12)


def test_dyadic_remap_keeps_line_period_between_w_and_2w():
    # v = g x along a screen row: iso-lines of v are 1/g pixels apart; after eq. 6 the sawtooth
    # resets every w 2^Frac(s) pixels, in [w, 2 w)
    w = 6.0
    x = np.arange(0, 4000) + 0.5
    for g in (0.3, 0.01, 0.00123, 0.09):
        s = dyadic_scale(1 / g, w)
        resets = np.count_nonzero(np.diff(dyadic_remap(g * x, s)) < 0)
        period = x.size / resets
        assert w * 0.99 <= period <= 2 * w * 1.01
        assert period == pytest.approx(w * 2 ** (s - math.floor(s)), rel=0.01)


# ---------------------------------------------------------------------------- eqs. 7 and 8


def test_multiscale_line_matches_naive_loop():
    rng = np.random.default_rng(9)
    v = rng.uniform(-3, 3, 500)
    t = rng.uniform(0, 1, 500)
    np.testing.assert_allclose(
        multiscale_line(v, t), [paper_f_py(a, b) for a, b in zip(v, t, strict=True)], atol=1e-12
    )
    np.testing.assert_allclose(
        multiscale_line(v, t, uniform=True),
        [uniform_f_py(a, b) for a, b in zip(v, t, strict=True)],
        atol=1e-12,
    )


def test_multiscale_line_end_scales_are_eq7():
    v = np.linspace(0, 1, 1001, endpoint=False)
    for uniform in (False, True):
        np.testing.assert_array_equal(multiscale_line(v, 0.0, uniform=uniform), v)
        np.testing.assert_array_equal(
            multiscale_line(v, 1.0, uniform=uniform), np.where(v < 0.5, 2 * v, 2 * v - 1)
        )
        # F at t = 1 equals F of the next scale at t = 0
        np.testing.assert_array_equal(
            multiscale_line(v, 1.0, uniform=uniform),
            multiscale_line(np.where(v < 0.5, 2 * v, 2 * v - 1), 0.0, uniform=uniform),
        )


@given(st.floats(-100, 100, allow_nan=False), st.integers(-8, 12), st.booleans())
def test_line_threshold_has_no_jump_where_s_crosses_an_integer(v, k, uniform):
    eps = 1e-9
    below = float(line_threshold(v, k - eps, uniform=uniform))
    at = float(line_threshold(v, float(k), uniform=uniform))
    vb = frac_py(v * 2.0**k)
    if min(vb, 1 - vb) > 1e-6 and abs(vb - 0.5) > 1e-6:  # away from the sawtooth's own jumps
        assert abs(below - at) < 1e-6


def test_paper_blend_is_not_uniform_at_half_scale():
    # DESIGN: density 2/(1+t) on [(1-t)/2, (1+t)/2) and 1/(1+t) elsewhere, here t = 0.5
    t = 0.5
    v = (np.arange(400_000) + 0.5) / 400_000
    f = multiscale_line(v, t)
    hist, edges = np.histogram(f, bins=40, range=(0, 1), density=True)
    centres = (edges[:-1] + edges[1:]) / 2
    inside = (centres > (1 - t) / 2) & (centres < (1 + t) / 2)
    np.testing.assert_allclose(hist[inside], 2 / (1 + t), atol=0.02)
    edge_bins = np.isclose(centres, (1 - t) / 2, atol=0.0125) | np.isclose(
        centres, (1 + t) / 2, atol=0.0125
    )
    np.testing.assert_allclose(hist[~inside & ~edge_bins], 1 / (1 + t), atol=0.02)
    # measurable tone drift: at intensity 1/4 the white fraction is 1/6 instead of 1/4
    assert step(0.25, f).mean() == pytest.approx(1 / 6, abs=1e-4)


@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_multiscale_line_cdf_matches_design_density(y, t):
    assert float(multiscale_line_cdf(y, t)) == pytest.approx(design_cdf_py(y, t), abs=1e-12)


@pytest.mark.parametrize("t", [0.0, 0.2, 0.5, 0.77, 1.0])
def test_multiscale_line_cdf_matches_empirical_distribution(t):
    n = 200_000
    f = np.sort(multiscale_line((np.arange(n) + 0.5) / n, t))
    y = np.linspace(0, 1, 101)
    empirical = np.searchsorted(f, y, side="right") / n
    np.testing.assert_allclose(multiscale_line_cdf(y, t), empirical, atol=2e-5)


@pytest.mark.parametrize("t", [0.1, 0.5, 0.9])
def test_uniform_variant_is_uniform_and_order_preserving(t):
    n = 200_000
    v = (np.arange(n) + 0.5) / n
    paper = multiscale_line(v, t)
    fixed = multiscale_line(v, t, uniform=True)
    hist, _ = np.histogram(fixed, bins=50, range=(0, 1), density=True)
    np.testing.assert_allclose(hist, 1.0, atol=0.005)
    rng = np.random.default_rng(10)
    rnd = multiscale_line(rng.uniform(0, 1, 100_000), t, uniform=True)
    hist, _ = np.histogram(rnd, bins=20, range=(0, 1))
    expected = rnd.size / 20
    assert np.all(np.abs(hist - expected) < 5 * np.sqrt(expected))
    # monotone map of the paper's values: same order
    order = np.argsort(paper, kind="stable")
    assert np.all(np.diff(fixed[order]) >= -1e-15)
    # extremes where the paper has them: minima at v = 0, 1/2 and maxima just below them
    np.testing.assert_allclose(
        multiscale_line([0.0, 0.5], t, uniform=True), [0.0, (1 - t) / 2 / (1 + t)]
    )
    assert fixed.argmax() == paper.argmax() and fixed.argmin() == paper.argmin()


def test_uniform_line_preserves_tone_where_paper_drifts():
    v = (np.arange(100_000) + 0.5) / 100_000
    for t in (0.25, 0.5, 0.75):
        for x in (0.2, 0.4, 0.6, 0.8):
            assert abs(step(x, multiscale_line(v, t, uniform=True)).mean() - x) < 1e-4
            assert step(x, multiscale_line(v, t)).mean() == pytest.approx(
                design_cdf_py(x, t), abs=1e-4
            )


def test_line_threshold_matches_naive_loop():
    rng = np.random.default_rng(11)
    v = rng.uniform(-20, 20, 400)
    s = rng.uniform(-5, 9, 400)
    for uniform in (False, True):
        expect = [line_py(a, b, uniform) for a, b in zip(v, s, strict=True)]
        np.testing.assert_allclose(line_threshold(v, s, uniform=uniform), expect, atol=1e-9)


def test_line_noise_is_a_tone_preserving_phase_shift():
    v = (np.arange(200_000) + 0.5) / 200_000 * 3
    noise = 0.3 * np.sin(v * 1.3)  # smooth on the scale of the line period
    for s in (6.0, 6.4, 7.5):
        f = line_threshold(v, s, uniform=True, noise=noise)
        assert abs(step(0.35, f).mean() - 0.35) < 2e-3
    # at an integer scale the phase shift is a lateral shift by noise line periods
    np.testing.assert_allclose(
        line_threshold(v, 2.0, noise=0.25), line_threshold(v + 0.25 / 4, 2.0), atol=1e-9
    )


# -------------------------------------------------------------------------------- compositions


def test_hatch_coordinate_values():
    uv = np.array([[0.3, 0.7], [2.0, -1.0]])
    np.testing.assert_allclose(hatch_coordinate(uv, 0.0), uv[:, 1])
    np.testing.assert_allclose(hatch_coordinate(uv, np.pi / 2), -uv[:, 0], atol=1e-15)
    a = 0.4
    expect = [-u * math.sin(a) + v * math.cos(a) for u, v in uv]
    np.testing.assert_allclose(hatch_coordinate(uv, a), expect)


def _plane(h, w, angle, scale):
    """uv = rotation(angle) * pixel / scale over an h x w screen, with its derivatives."""
    y, x = np.mgrid[0:h, 0:w] + 0.5
    c, s = math.cos(angle), math.sin(angle)
    uv = np.stack([c * x - s * y, s * x + c * y], -1) / scale
    dx = np.broadcast_to(np.array([c, s]) / scale, uv.shape)
    dy = np.broadcast_to(np.array([-s, c]) / scale, uv.shape)
    return uv, dx, dy


def test_hatch_threshold_single_angle_is_line_threshold():
    uv, dx, dy = _plane(32, 40, 0.3, 13.0)
    s = dyadic_scale_from_gradient(dx[..., 1], dy[..., 1], 5.0)
    np.testing.assert_allclose(
        hatch_threshold(uv, dx, dy, w=5.0), line_threshold(uv[..., 1], s), atol=1e-12
    )


def test_cross_hatching_is_tone_preserving():
    uv, dx, dy = _plane(300, 300, 0.2, 37.0)
    f = hatch_threshold(uv, dx, dy, w=7.3, angles=(0.0, np.pi / 2), uniform=True)
    hist, _ = np.histogram(f, bins=10, range=(0, 1), density=True)
    np.testing.assert_allclose(hist, 1.0, atol=0.05)
    for x in (0.25, 0.5, 0.75):
        assert abs(step(x, f).mean() - x) < 0.02


@given(st.lists(st.floats(0.05, 1.0), min_size=1, max_size=4))
def test_combine_thresholds_uniform_and_onsets(raw):
    onsets = [1.0, *raw[1:]]
    rng = np.random.default_rng(len(raw))
    layers = list(rng.uniform(0, 1, (len(onsets), 40_000)))
    out = combine_thresholds(layers, onsets=onsets)
    hist, _ = np.histogram(out, bins=10, range=(0, 1))
    assert np.all(np.abs(hist - 4000) < 5 * math.sqrt(4000))
    # layer i alone at its maximum (others 0) gives exactly its onset intensity
    for i, o in enumerate(onsets):
        probe = [np.array([1.0 if j == i else 0.0]) for j in range(len(onsets))]
        assert float(combine_thresholds(probe, onsets=onsets)[0]) == pytest.approx(o, abs=1e-9)


def test_combine_thresholds_naive_loop_and_later_layer_hidden_above_onset():
    rng = np.random.default_rng(12)
    f1, f2 = rng.uniform(0, 1, (2, 500))
    out = combine_thresholds([f1, f2], onsets=[1.0, 0.5])
    # water-filling with onsets (1, 0.5), worked by hand in darkness -ln x: the first layer
    # alone down to x = 1/2, then the second alone until as wide (x = 1/4), then both share.
    # Inverting each layer's white fraction: h_1(F) = F above 1/2, F^2 below; h_2(F) = F / 2
    # above 1/2, F^2 below; the composite is their max (union of the dark lines).
    for a, b, o in zip(f1, f2, out, strict=True):
        h1 = a if a > 0.5 else a * a
        h2 = b / 2 if b > 0.5 else b * b
        assert o == pytest.approx(max(h1, h2), abs=1e-12)
    other = combine_thresholds([f1, rng.uniform(0, 1, 500)], onsets=[1.0, 0.5])
    for x in (0.55, 0.7, 0.9):  # above the second onset only the first layer draws
        np.testing.assert_array_equal(step(x, out), step(x, other))
    assert np.any(step(0.3, out) != step(0.3, other))


def test_dot_function_uniform_and_extremes():
    n = 600
    g = (np.arange(n) + 0.5) / n
    p = np.stack(np.meshgrid(g, g, indexing="ij"), -1)
    d = dot_function(p)
    hist, _ = np.histogram(d, bins=20, range=(0, 1), density=True)
    np.testing.assert_allclose(hist, 1.0, atol=0.02)
    np.testing.assert_allclose(
        dot_function(np.array([[0.0, 0.0], [3.0, -2.0], [0.5, 0.5]])), [1.0, 1.0, 0.0], atol=1e-12
    )
    r = 0.3  # inside the inscribed circle, D = 1 - pi r^2
    assert float(dot_function(np.array([r, 0.0]))) == pytest.approx(1 - math.pi * r * r)


def _corner_distance_py(px: float, py: float) -> float:
    dx, dy = frac_py(px), frac_py(py)
    return math.hypot(min(dx, 1 - dx), min(dy, 1 - dy))


def test_dot_function_and_dot_threshold_match_area_fraction_oracle():
    # D(p) = 1 - (fraction of the cell closer to a lattice point than p), counted on a grid
    n = 1000
    g = (np.arange(n) + 0.5) / n
    d = np.minimum(g, 1 - g)
    dist = np.sort(np.hypot(d[:, None], d[None, :]).ravel())

    def dot_py(px, py):
        return 1 - np.searchsorted(dist, _corner_distance_py(px, py)) / dist.size

    rng = np.random.default_rng(16)
    pts = rng.uniform(-3, 3, (60, 2))
    np.testing.assert_allclose(dot_function(pts), [dot_py(*p) for p in pts], atol=3e-3)
    s = rng.uniform(-2, 4, 60)
    expect = []
    for (u, v), si in zip(pts, s, strict=True):
        k = math.floor(si)
        t = si - k
        pu, pv = frac_py(u * 2.0**k), frac_py(v * 2.0**k)  # eq. 6 per axis
        expect.append((1 - t) * dot_py(pu, pv) + t * dot_py(2 * pu, 2 * pv))  # eq. 8
    np.testing.assert_allclose(dot_threshold(pts, s), expect, atol=3e-3)


def test_dot_threshold_scales_and_tone_table():
    n = 400
    g = (np.arange(n) + 0.5) / n
    uv = np.stack(np.meshgrid(g, g, indexing="ij"), -1) * 2
    # no jump where s crosses an integer; lattice points stay dot centres at every t
    np.testing.assert_allclose(dot_threshold(uv, 2.0 - 1e-10), dot_threshold(uv, 2.0), atol=1e-8)
    corners = np.array([[0.0, 0.0], [0.5, 0.25], [1.25, 0.75]])
    for s in (2.0, 2.3, 2.99):
        np.testing.assert_allclose(dot_threshold(corners, s), 1.0, atol=1e-12)
    # the paper's blend drifts at t = 0.5, the tabulated correction does not
    table = dot_tone_table()
    paper = dot_threshold(uv, 0.5)
    fixed = dot_threshold(uv, 0.5, tone_table=table)
    drift = max(abs(step(x, paper).mean() - x) for x in (0.2, 0.5, 0.8))
    assert drift > 0.02
    for x in (0.1, 0.3, 0.5, 0.7, 0.9):
        assert abs(step(x, fixed).mean() - x) < 0.01
    order = np.argsort(paper.ravel(), kind="stable")
    assert np.all(np.diff(fixed.ravel()[order]) >= -1e-12)


def test_dot_dyadic_scale_values():
    dx = np.array([0.1, 0.0])
    dy = np.array([0.0, 0.05])
    assert float(dot_dyadic_scale(dx, dy, 5.0)) == pytest.approx(math.log2(1 / (0.1 * 5)))


# ---------------------------------------------------------------------------------- filtering


def test_pcf_threshold_matches_naive_loop():
    rng = np.random.default_rng(13)
    x = rng.uniform(0, 1, 60)
    ts = rng.uniform(0, 1, (60, 5))
    wts = rng.uniform(0.1, 2, (60, 5))
    out = pcf_threshold(x, ts, weights=wts, n=2)
    for p in range(60):
        num = sum(wts[p, k] * step_n_py(x[p], ts[p, k], 2) for k in range(5))
        assert out[p] == pytest.approx(num / wts[p].sum(), abs=1e-12)
    eq = pcf_threshold(x, ts)
    np.testing.assert_allclose(eq, [np.mean([step_py(x[p], b) for b in ts[p]]) for p in range(60)])


def test_pcf_filters_results_not_thresholds():
    # sec. 4: filtering thresholds leaves a binary result; filtering results gives the coverage
    x = 0.4
    ts = np.linspace(0.05, 0.95, 10)
    assert step(x, ts.mean()) in (0.0, 1.0)
    assert float(pcf_threshold(x, ts)) == pytest.approx(0.4)


def test_mip_threshold_matches_naive_loop():
    rng = np.random.default_rng(14)
    x, t0, t1, f = rng.uniform(0, 1, (4, 200))
    out = mip_threshold(x, t0, t1, f, n=3)
    expect = [
        (1 - d) * step_n_py(a, b, 3) + d * step_n_py(a, c, 3)
        for a, b, c, d in zip(x, t0, t1, f, strict=True)
    ]
    np.testing.assert_allclose(out, expect, atol=1e-12)


# ---------------------------------------------------------------- analytic box filter (lines)


def _white_set_py(t: float, intensity: float, uniform: bool) -> list[tuple[float, float]]:
    """{u in [0, 1): F(u, t) <= intensity} by a dense scan and bisection (no closed forms)."""

    def white(u):
        f = uniform_f_py(u, t) if uniform else paper_f_py(u, t)
        return f <= intensity

    m = 2048
    grid = [i / m for i in range(m)] + [1.0 - 1e-16]
    state = [white(u) for u in grid]
    cuts = []
    for i in range(m):
        if state[i] != state[i + 1]:
            lo, hi = grid[i], grid[i + 1]
            for _ in range(60):
                mid = (lo + hi) / 2
                if white(mid) == state[i]:
                    lo = mid
                else:
                    hi = mid
            cuts.append(hi)
    intervals, start = [], (0.0 if state[0] else None)
    for c in cuts:
        if start is None:
            start = c
        else:
            intervals.append((start, c))
            start = None
    if start is not None:
        intervals.append((start, 1.0))
    return intervals


def coverage_oracle(v, s, intensity, dv_dx, dv_dy, uniform=False, rows=2000):
    """Exact measure along the steeper axis per row, midpoint rule over the other axis."""
    k = math.floor(s)
    t = s - k
    vb = frac_py(v * 2.0**k)
    a, b = dv_dx * 2.0**k, dv_dy * 2.0**k
    if abs(b) > abs(a):
        a, b = b, a
    if a == 0:
        f = uniform_f_py(vb, t) if uniform else paper_f_py(vb, t)
        return step_py(intensity, f)
    pieces = _white_set_py(t, intensity, uniform)
    total = 0.0
    for j in range(rows):
        c = vb + b * ((j + 0.5) / rows - 0.5)
        lo, hi = sorted((c - a / 2, c + a / 2))
        inside = 0.0
        for n in range(math.floor(lo) - 1, math.floor(hi) + 1):
            for p, q in pieces:
                inside += max(0.0, min(hi, n + q) - max(lo, n + p))
        total += inside / abs(a)
    return total / rows


@given(
    st.floats(-10, 10),
    st.floats(-4, 6),
    st.floats(-0.1, 1.1),
    st.floats(-1.5, 1.5),
    st.floats(-1.5, 1.5),
    st.booleans(),
)
def test_line_coverage_matches_row_exact_oracle(v, s, x, gx, gy, uniform):
    # footprint ~ line period; below 1e-3 periods the oracle's bisection width (1e-18) matters
    gx, gy = (0.0 if abs(g) < 1e-3 else g * 2.0 ** -math.floor(s) for g in (gx, gy))
    assume(gx != 0 or gy != 0)  # point samples: see test_line_coverage_limits_and_path_continuity
    got = float(line_coverage(v, s, x, gx, gy, uniform=uniform))
    assert got == pytest.approx(coverage_oracle(v, s, x, gx, gy, uniform), abs=2e-5)


@pytest.mark.parametrize("span", [0.2, 1.5, 6.0])
def test_line_coverage_matches_row_exact_oracle_on_seeded_cases(span):
    # footprints up to `span` line periods: both the b < 1 (ramps) and b >= 1 (closed) paths
    rng = np.random.default_rng(int(span * 10))
    for i in range(12):
        v, s, x = rng.uniform(-10, 10), rng.uniform(-4, 6), rng.uniform(-0.05, 1.05)
        gx, gy = rng.uniform(-span, span, 2) * 2.0 ** -math.floor(s)
        got = float(line_coverage(v, s, x, gx, gy, uniform=bool(i % 2)))
        assert got == pytest.approx(coverage_oracle(v, s, x, gx, gy, bool(i % 2)), abs=1e-6)


@pytest.mark.parametrize(
    ("v", "s", "x", "gx", "gy", "uniform"),
    [
        (0.37, 0.0, 0.5, 0.3, 0.1, False),
        (0.37, 0.6, 0.3, 0.25, -0.2, False),
        (1.91, 2.5, 0.6, 0.1, 0.07, True),
        (0.05, 1.2, 0.45, 0.9, 0.0, True),
        (0.5, -1.3, 0.7, 1.6, 1.6, False),
        (3.3, 3.8, 0.2, 0.02, 0.3, True),
    ],
)
def test_line_coverage_equals_brute_force_supersampling(v, s, x, gx, gy, uniform):
    n = 1024
    o = (np.arange(n) + 0.5) / n - 0.5
    vv = v + gx * o[None, :] + gy * o[:, None]
    brute = step(x, line_threshold(vv, s, uniform=uniform)).mean()
    got = float(line_coverage(v, s, x, gx, gy, uniform=uniform))
    assert got == pytest.approx(brute, abs=1e-3)  # midpoint-rule error ~ lines / (2 n)


def test_line_coverage_limits_and_path_continuity():
    rng = np.random.default_rng(15)
    v, x = rng.uniform(0, 1, (2, 200))
    s = rng.uniform(0, 1, 200)
    for uniform in (False, True):
        point = line_coverage(v, s, x, 0.0, 0.0, uniform=uniform)
        np.testing.assert_array_equal(point, step(x, line_threshold(v, s, uniform=uniform)))
        tone = x if uniform else multiscale_line_cdf(x, s - np.floor(s))
        np.testing.assert_allclose(line_coverage(v, s, x, 1e16, 3.0, uniform=uniform), tone)
        np.testing.assert_allclose(
            line_coverage(v, s, x, 4e4, 3e4, uniform=uniform), tone, atol=1e-8
        )
        # the b >= 1 closed form and the b < 1 ramps agree at b = 1; b -> 0 is continuous
        near = [line_coverage(v, s, x, 2.5, 1 + e, uniform=uniform) for e in (-1e-12, 1e-12)]
        np.testing.assert_allclose(near[0], near[1], atol=1e-9)
        tiny = line_coverage(v, s, x, 0.3, 1e-13, uniform=uniform)
        np.testing.assert_allclose(
            tiny, line_coverage(v, s, x, 0.3, 0.0, uniform=uniform), atol=1e-9
        )
        # symmetric in the derivatives and their signs
        np.testing.assert_allclose(
            line_coverage(v, s, x, 0.2, -0.7, uniform=uniform),
            line_coverage(v, s, x, 0.7, 0.2, uniform=uniform),
            atol=1e-12,
        )


@given(st.floats(-5, 5), st.floats(-3, 3), st.floats(0, 2), st.floats(0, 2))
def test_line_coverage_is_monotone_in_intensity(v, s, gx, gy):
    x = np.linspace(-0.1, 1.1, 121)
    cov = line_coverage(v, s, x, gx, gy, uniform=True)
    # documented conditioning: 1e-16 (1 + |v 2^k|) / footprint in periods
    scale = 2.0 ** math.floor(s)
    footprint = (gx + gy) * scale
    tol = 1e-15 * (1 + abs(v) * scale) / footprint if footprint > 0 else 0.0
    assert np.all(np.diff(cov) >= -tol - 1e-12)
    assert cov[0] == 0.0 and cov[-1] == 1.0


# ---------------------------------------------------------------------------------- bad input


def test_bad_parameters_raise_clear_errors():
    with pytest.raises(
        ValueError, match="n: expected an integer in \\[1, 9007199254740992\\], got 0"
    ):
        step_n(0.5, 0.5, 0)
    with pytest.raises(TypeError, match="n: expected an integer, got 2.5"):
        step_n(0.5, 0.5, 2.5)
    with pytest.raises(ValueError, match="w: expected values > 0, got 0.0 .*line period"):
        dyadic_scale(4.0, 0.0)
    with pytest.raises(ValueError, match="w: expected values > 0, got -1.0"):
        dyadic_scale_from_gradient(0.1, 0.1, -1.0)
    with pytest.raises(ValueError, match="d: expected values > 0, got 0.0 at flat index 1"):
        dyadic_scale(np.array([1.0, 0.0]), 8.0)
    with pytest.raises(ValueError, match="t: expected values in \\[0.0, 1.0\\], got 1.5"):
        multiscale_line(0.3, 1.5)
    with pytest.raises(
        ValueError, match="v, s: shapes do not broadcast \\(v \\(3,\\), s \\(4,\\)\\)"
    ):
        line_threshold(np.zeros(3), np.zeros(4))
    with pytest.raises(ValueError, match="s: must be finite, got inf"):
        line_threshold(0.3, np.inf)
    with pytest.raises(ValueError, match="v: must be finite, got nan"):
        dyadic_remap(np.nan, 1.0)
    with pytest.raises(TypeError, match="x: expected a real number"):
        step("0.5", 0.5)
    with pytest.raises(ValueError, match=r"uv: expected shape \(\.\.\., 2\)"):
        hatch_coordinate(np.zeros((4, 3)), 0.0)
    with pytest.raises(ValueError, match="w: expected values > 0"):
        hatch_threshold(np.zeros(2), np.ones(2), np.ones(2), w=0.0)
    with pytest.raises(ValueError, match="angles: expected a non-empty sequence"):
        hatch_threshold(np.zeros(2), np.ones(2), np.ones(2), w=4.0, angles=())
    with pytest.raises(ValueError, match="onsets: expected values in \\(0, 1\\] with maximum 1"):
        combine_thresholds([np.zeros(2), np.zeros(2)], onsets=[0.8, 0.5])
    with pytest.raises(ValueError, match="onsets: expected 2 values"):
        combine_thresholds([np.zeros(2), np.zeros(2)], onsets=[1.0])
    with pytest.raises(ValueError, match=r"layers\[1\]: expected values in \[0.0, 1.0\]"):
        combine_thresholds([np.zeros(2), np.full(2, 1.5)])
    with pytest.raises(TypeError, match="layers: expected a non-empty list"):
        combine_thresholds(np.zeros((2, 3)))
    with pytest.raises(TypeError, match="tone_table: expected a DotToneTable"):
        dot_threshold(np.zeros(2), 0.0, tone_table=np.eye(3))
    with pytest.raises(ValueError, match="n_t: expected an integer in \\[2, inf\\], got 1"):
        dot_tone_table(n_t=1)
    with pytest.raises(ValueError, match="weights: expected values >= 0"):
        pcf_threshold(0.5, np.zeros(3), weights=[1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="weights: the weights of some pixel sum to 0"):
        pcf_threshold(0.5, np.zeros(3), weights=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="t_samples: expected shape \\(\\.\\.\\., K\\)"):
        pcf_threshold(0.5, 0.5)
    with pytest.raises(ValueError, match="lod_frac: expected values in \\[0.0, 1.0\\]"):
        mip_threshold(0.5, 0.2, 0.7, 1.2)
    with pytest.raises(
        ValueError,
        match="intensity, dv_dx, dv_dy: shapes do not broadcast|"
        "v, s, intensity, dv_dx, dv_dy: shapes do not broadcast",
    ):
        line_coverage(0.1, 0.0, np.zeros(2), np.zeros(3), 0.0)


# ------------------------------------------------------------------------------------ stress

extreme_s = st.floats(-2000, 2000, allow_nan=False)
extreme_v = st.floats(-1e30, 1e30, allow_nan=False)


@pytest.mark.stress
@given(st.lists(st.tuples(extreme_v, extreme_s), min_size=1, max_size=20), st.booleans())
def test_stress_extreme_inputs_stay_finite_and_in_range(pairs, uniform):
    v = np.array([p[0] for p in pairs])
    s = np.array([p[1] for p in pairs])
    for dtype in (np.float32, np.float64):
        vv, ss = v.astype(dtype), s.astype(dtype)
        vv = np.where(np.isfinite(vv), vv, 0).astype(dtype)
        for f in (
            dyadic_remap(vv, ss),
            line_threshold(vv, ss, uniform=uniform),
            line_threshold(vv, ss, uniform=uniform, noise=vv * dtype(1e-20)),
            dot_threshold(np.stack([vv, vv[::-1]], -1), ss),
        ):
            assert f.dtype == dtype
            assert np.all(np.isfinite(f)) and np.all((f >= 0) & (f <= 1))
        cov = line_coverage(vv, ss, dtype(0.4), vv * dtype(1e-3), dtype(0.5))
        assert cov.dtype == dtype and np.all(np.isfinite(cov)) and np.all((cov >= 0) & (cov <= 1))


@pytest.mark.stress
@given(
    st.lists(st.tuples(st.floats(-1e4, 1e4), st.floats(-40, 40), unit), min_size=1, max_size=30),
    st.booleans(),
)
def test_stress_float32_within_documented_bound_of_float64(rows, uniform):
    # documented: float32 agrees with float64 on the same inputs to 1e-6, except within 1e-6
    # (in units of the line period) of the sawtooth's jumps at Frac(v 2^floor(s)) = 0 and 1/2
    v32 = np.array([r[0] for r in rows], dtype=np.float32)
    s32 = np.array([r[1] for r in rows], dtype=np.float32)
    x32 = np.array([r[2] for r in rows], dtype=np.float32)
    f32 = line_threshold(v32, s32, uniform=uniform)
    f64 = line_threshold(v32.astype(np.float64), s32.astype(np.float64), uniform=uniform)
    vb = dyadic_remap(v32.astype(np.float64), s32.astype(np.float64))
    far = (np.minimum(vb, 1 - vb) > 1e-6) & (np.abs(vb - 0.5) > 1e-6)
    assert f32.dtype == np.float32
    assert np.all(np.abs(f32.astype(np.float64) - f64)[far] <= 1e-6)
    t32 = multiscale_line(v32, x32, uniform=uniform)
    t64 = multiscale_line(v32.astype(np.float64), x32.astype(np.float64), uniform=uniform)
    vf = v32.astype(np.float64) - np.floor(v32.astype(np.float64))
    far = (np.minimum(vf, 1 - vf) > 1e-6) & (np.abs(vf - 0.5) > 1e-6)
    assert np.all(np.abs(t32.astype(np.float64) - t64)[far] <= 1e-6)
    # the analytic filter computes in float64 and only rounds the result
    g = np.float32(0.3) * np.exp2(-np.floor(s32)).astype(np.float32)
    c32 = line_coverage(v32, s32, x32, g, g / 3)
    c64 = line_coverage(*(a.astype(np.float64) for a in (v32, s32, x32, g, g / 3)))
    assert np.all(np.abs(c32.astype(np.float64) - c64) <= 6e-8)


def test_public_api_and_import_boundary():
    import ast
    from pathlib import Path

    from refnpr.formulas import halftone

    for mod in (threshold, halftone, lighting):
        assert all(hasattr(mod, name) for name in mod.__all__)
    # refnpr.formulas imports nothing of refnpr but the numba flags and the device layer
    # (imports point downward only); tests/test_layout.py checks the whole package graph, this
    # pins the formula layer itself
    allowed = ("refnpr._jit", "refnpr.device")
    root = Path(lighting.__file__).parent
    files = sorted(root.rglob("*.py"))
    assert root / "threshold" / "lines.py" in files
    for path in files:
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level == 0:
                mod = node.module or ""
                assert not mod.startswith("refnpr") or mod.startswith(allowed), (path, mod)
            if isinstance(node, ast.Import):
                assert not any(
                    a.name.startswith("refnpr") and not a.name.startswith(allowed)
                    for a in node.names
                ), path


def test_pcf_threshold_needs_at_least_one_sample():
    with pytest.raises(ValueError, match=r"t_samples: expected K >= 1 threshold samples"):
        threshold.pcf_threshold(np.ones(2), np.zeros((2, 0)))


@pytest.mark.parametrize("k", [1, 2, 7, 8, 9, 16, 31, 64, 127, 128, 129, 256, 257, 512])
def test_pcf_threshold_sums_in_numpys_order(k):
    """The PCF average is numpy's mean of the thresholding results, bit for bit (pairwise
    summation, 8 accumulators, halves past 128), K up to 2 x 256 (image PCF at two levels)."""
    rng = np.random.default_rng(k)
    x = rng.uniform(0, 1, 20)
    ts = rng.uniform(0, 1, (20, k))
    w = rng.uniform(0.1, 2.0, (20, k))
    for n in (1, 3):
        hits = np.array(
            [
                [step_n_py(a, b, n) if n > 1 else step_py(a, b) for b in r]
                for a, r in zip(x, ts, strict=True)
            ]
        )
        assert np.array_equal(pcf_threshold(x, ts, n=n), np.mean(hits, axis=-1))
        want = np.sum(hits * w, axis=-1) / np.sum(w, axis=-1)
        assert np.array_equal(pcf_threshold(x, ts, weights=w, n=n), want)


def test_strength_faces_match_naive_loops():
    rng = np.random.default_rng(17)
    c, x, tx, st = (
        rng.uniform(-1, 1, 50),
        rng.uniform(0, 1, 50),
        rng.uniform(0, 1, 50),
        rng.uniform(0, 1, 50),
    )

    def smooth(a):
        a = min(max(a, 0.0), 1.0)
        return a * a * (3 - 2 * a)

    for power in (0.5, 1.0, 2.0, 3.7):
        want = [1 - 0.8 * abs(a) ** power for a in c]
        np.testing.assert_allclose(threshold.facing_strength(c, 0.8, power), want, rtol=1e-14)
    for dark, bright in ((0.0, 0.0), (0.2, 0.0), (0.0, 0.3), (0.25, 0.5)):
        want = [
            (smooth(a / dark) if dark else 1.0) * (smooth((1 - a) / bright) if bright else 1.0)
            for a in x
        ]
        np.testing.assert_allclose(threshold.tone_strength(x, dark, bright), want, rtol=1e-14)
    np.testing.assert_allclose(threshold.strength_blend(x, tx, st), x + st * (tx - x), rtol=1e-15)
    assert threshold.tone_strength(np.array([0.0, 1.0]), 0.1, 0.1).tolist() == [0.0, 0.0]
    with pytest.raises(ValueError, match="dark: expected a value in \\[0.0, 0.5\\]"):
        threshold.tone_strength(x, 0.6, 0.0)
    with pytest.raises(ValueError, match="power: expected a value in \\(0.0, inf\\]"):
        threshold.facing_strength(c, 0.5, 0.0)


def test_float32_faces_of_unit_interval_formulas_stay_below_one():
    """Computed in float64, a value just below 1 would round to 1 in float32: clamped."""
    v = np.array([np.nextafter(1.0, 0.0), 0.9999999, -1e-9], dtype=np.float32)
    for f in (multiscale_line(v, np.float32(0.0)), dyadic_remap(v, np.float32(0.0))):
        assert f.dtype == np.float32 and np.all(f < 1.0)


# ---------------------------------------------------------------------- edges of the faces


def test_pcf_threshold_weights_broadcast_with_the_samples():
    """Weights (M, K) beside samples (K,) give M pixels (oracle: the weighted mean per row)."""
    ts = np.array([0.3, 0.6, 0.7])
    wts = np.array([[1.0, 1.0, 1.0], [3.0, 1.0, 0.5]])
    got = pcf_threshold(0.5, ts, weights=wts)
    want = [
        sum(w * step_py(0.5, t) for w, t in zip(row, ts, strict=True)) / sum(row) for row in wts
    ]
    assert got.shape == (2,)
    np.testing.assert_allclose(got, want, rtol=1e-15)
    assert pcf_threshold(0.5, ts, weights=[[2.0], [5.0]]).tolist() == [1 / 3, 1 / 3]


@pytest.mark.parametrize("shape", [(2,), (4,), (2, 2)])
def test_pcf_threshold_names_weights_of_another_sample_count(shape):
    with pytest.raises(
        ValueError, match=r"^weights: expected shape \(K,\) or \(\.\.\., K\) with K = 3"
    ):
        pcf_threshold(0.5, np.full(3, 0.3), weights=np.ones(shape))


@pytest.mark.parametrize(
    "weights",
    [
        [1e308, 1e308, 1e308],
        [1.7e308, 1e308, 5e307],
        [np.finfo(float).max, 1.0, 1e-300],
        [1e308, 0.0, 1e308],
        [5e307, 5e307, 5e307],  # the sum is finite, the weighted sum at x = 3 is not
    ],
)
def test_pcf_threshold_with_weights_whose_sum_overflows(weights):
    """Oracle: the weighted mean in exact rational arithmetic, rounded once."""
    from fractions import Fraction

    ts = [0.3, 0.6, 0.7]
    for x, n in ((0.5, 1), (0.65, 1), (0.65, 2), (3.0, 2)):
        hits = [Fraction(step_n_py(x, t, n)) for t in ts]
        want = float(
            sum(Fraction(w) * h for w, h in zip(weights, hits, strict=True))
            / sum(map(Fraction, weights))
        )
        got = float(pcf_threshold(x, np.array(ts), weights=weights, n=n))
        assert got == pytest.approx(want, rel=1e-15)


def test_pcf_threshold_keeps_the_kernels_bits_for_ordinary_weights():
    rng = np.random.default_rng(31)
    ts, w = rng.uniform(0, 1, (50, 7)), rng.uniform(0, 1e300, (50, 7))
    x = rng.uniform(0, 1, 50)
    got = pcf_threshold(x, ts, weights=w, n=3)
    want = [pcf_threshold.scalar(x[i], ts[i], w[i], 3) for i in range(50)]
    assert got.tolist() == want


@pytest.mark.parametrize(
    "call",
    [
        lambda n: step_n(0.5, 0.5, n),
        lambda n: pcf_threshold(0.5, np.full(3, 0.3), n=n),
        lambda n: mip_threshold(0.5, 0.3, 0.6, 0.5, n=n),
        lambda n: threshold_illumination(0.5, None, 0.5, n=n),
    ],
)
def test_step_counts_are_bounded_by_exact_float64_integers(call):
    for n in (2**53 + 1, 2**63, 2**64):
        with pytest.raises(ValueError, match=r"^n: expected an integer in \[1, 9007199254740992\]"):
            call(n)
    with pytest.raises(TypeError, match="^n: expected an integer, got 2.0"):
        call(2.0)
    assert float(call(2**53)) == 0.5  # x n = 2^52 exactly: floor(x n) / n (eq. 4)


@pytest.mark.parametrize(
    "angles", [np.float32(0.3), np.array(0.3), 0.3, 1, np.zeros((1, 1)), "ab", [], None]
)
def test_hatch_threshold_names_angles_that_are_not_a_sequence(angles):
    with pytest.raises(ValueError, match="^angles: expected a non-empty sequence of radians"):
        hatch_threshold(np.zeros(2), np.ones(2), np.ones(2), w=4.0, angles=angles)


def test_hatch_threshold_takes_angles_as_a_numpy_array():
    rng = np.random.default_rng(32)
    uv, dx, dy = rng.uniform(0, 4, (20, 2)), rng.normal(size=(20, 2)), rng.normal(size=(20, 2))
    want = hatch_threshold(uv, dx, dy, w=5.0, angles=(0.25, 1.5))
    got = hatch_threshold(uv, dx, dy, w=5.0, angles=np.array([0.25, 1.5]))
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize(
    "onsets, error, message",
    [
        (1.0, ValueError, "expected a non-empty sequence of intensities"),
        ([], ValueError, "expected a non-empty sequence of intensities"),
        ([[1.0, 0.5]], ValueError, "expected a non-empty sequence of intensities"),
        ("ab", TypeError, "expected a real number or array"),
        ([1.0, math.nan], ValueError, "must be finite"),
    ],
)
def test_layer_schedule_names_onsets(onsets, error, message):
    with pytest.raises(error, match=f"^onsets: {message}"):
        threshold.layer_schedule(onsets)


@pytest.mark.parametrize("limit", [np.float32(0.25), np.float64(0.25), np.int64(1), np.uint8(1)])
def test_clahe_pyramid_takes_any_real_clip_limit(limit):
    from refnpr.texture import clahe_pyramid

    img = np.random.default_rng(33).uniform(0, 1, (16, 16))
    got = clahe_pyramid(img, window=8, clip_limit=limit, nbins=16)
    want = clahe_pyramid(img, window=8, clip_limit=float(limit), nbins=16)
    for a, b in zip(got.levels, want.levels, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    "limit", [True, np.bool_(True), "0.1", np.float32(0.0), np.float64(1.5), math.nan]
)
def test_clahe_pyramid_refuses_a_clip_limit_that_is_not_a_number_in_range(limit):
    from refnpr.texture import clahe_pyramid

    with pytest.raises(ValueError, match=r"^clip_limit: expected a number in \(0, 1\]"):
        clahe_pyramid(np.zeros((8, 8)), clip_limit=limit)
