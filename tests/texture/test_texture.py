"""Mip pyramids, CLAHE pyramids and samplers against naive loops."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.texture import (
    build_pyramid,
    clahe_pyramid,
    level_weights,
    load_texture,
    rank_equalize,
    sample_level,
    sample_trilinear,
    texture_lod,
)


def naive_bilinear(tex: np.ndarray, u: float, v: float) -> np.ndarray:
    """GL_LINEAR + GL_REPEAT by the book (OpenGL 4.6 sec. 8.14.2), one sample at a time."""
    rows, cols = tex.shape[:2]
    x, y = u * cols - 0.5, v * rows - 0.5
    i0, j0 = math.floor(x), math.floor(y)
    a, b = x - i0, y - j0
    acc = 0.0
    for dj, wy in ((0, 1 - b), (1, b)):
        for di, wx in ((0, 1 - a), (1, a)):
            acc = acc + wx * wy * tex[(j0 + dj) % rows, (i0 + di) % cols].astype(np.float64)
    return acc


def test_level_sizes_follow_gl_rule():
    p = build_pyramid(np.zeros((37, 100), np.float32))
    sizes = [lv.shape for lv in p.levels]
    assert sizes[0] == (37, 100) and sizes[-1] == (1, 1)
    for (h0, w0), (h1, w1) in zip(sizes, sizes[1:], strict=False):
        assert (h1, w1) == (max(1, h0 // 2), max(1, w0 // 2))


@given(st.integers(1, 40), st.integers(1, 40), st.integers(0, 2**31 - 1))
def test_box_filter_preserves_mean(h, w, seed):
    img = np.random.default_rng(seed).random((h, w)).astype(np.float32)
    p = build_pyramid(img)
    for lv in p.levels:
        assert lv.mean() == pytest.approx(img.mean(), abs=1e-5)


def test_bilinear_matches_naive_loop():
    rng = np.random.default_rng(1)
    tex = rng.random((8, 12, 3)).astype(np.float32)
    p = build_pyramid(tex)
    uv = rng.uniform(-2, 3, (200, 2))
    got = sample_level(p, uv, 0)
    want = np.array([naive_bilinear(tex, u, v) for u, v in uv])
    np.testing.assert_allclose(got, want, atol=1e-6)


def test_trilinear_blends_two_levels_and_clamps():
    rng = np.random.default_rng(2)
    p = build_pyramid(rng.random((16, 16)).astype(np.float32))
    uv = rng.random((50, 2))
    lod = rng.uniform(-3, 8, 50)
    got = sample_trilinear(p, uv, lod)
    k0, k1, f = level_weights(p, lod)
    a = np.array([naive_bilinear(p.levels[k], *t) for k, t in zip(k0, uv, strict=True)])
    b = np.array([naive_bilinear(p.levels[k], *t) for k, t in zip(k1, uv, strict=True)])
    np.testing.assert_allclose(got, (1 - f) * a + f * b, atol=1e-6)
    assert np.all(k0 >= 0) and np.all(k1 <= p.n_levels - 1)


@given(
    st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=1, max_size=40),
    st.integers(0, 5),
)
def test_level_weights_are_floor_clamp_and_frac(lods, log_size):
    """The levels trilinear filtering blends, by the book: lambda clamped to [0, L - 1]."""
    p = build_pyramid(np.zeros((2**log_size, 2**log_size), dtype=np.float32))
    lam = np.clip(np.array(lods), 0.0, p.n_levels - 1)
    k0, k1, f = level_weights(p, np.array(lods))
    assert k0.dtype == k1.dtype == np.int64 and f.dtype == np.float64
    np.testing.assert_array_equal(k0, [math.floor(x) for x in lam])
    np.testing.assert_array_equal(k1, np.minimum(k0 + 1, p.n_levels - 1))
    np.testing.assert_array_equal(f, lam - k0)


def test_texture_lod_counts_texels_per_pixel():
    """GL sec. 8.14: one texel per pixel is LOD 0, two texels 1, half a texel -1; the larger of
    the two derivatives' lengths, each in the texture's own (cols, rows) texels."""
    p = build_pyramid(np.zeros((32, 64), dtype=np.float32))  # 64 columns (u), 32 rows (v)
    dx = np.array(
        [[1 / 64, 0.0], [2 / 64, 0.0], [0.5 / 64, 0.0], [0.0, 4 / 32], [3 / 640, 4 / 320]]
    )
    dy = np.array([[0.0, 1 / 32], [0.0, 1 / 32], [0.0, 0.25 / 32], [1 / 64, 0.0], [0.0, 0.0]])
    np.testing.assert_allclose(
        texture_lod(p, dx, dy), [0.0, 1.0, -1.0, 2.0, math.log2(0.5)], atol=1e-15
    )
    assert texture_lod(p, np.zeros((1, 2)), np.zeros((1, 2)))[0] == -64.0  # the 2^-64 floor
    assert texture_lod(p, dx.reshape(5, 1, 2), dy.reshape(5, 1, 2)).shape == (5, 1)


@given(st.lists(st.tuples(*[st.floats(-10, 10, allow_nan=False)] * 4), min_size=1, max_size=30))
def test_texture_lod_matches_a_float64_numpy_oracle(rows):
    p = build_pyramid(np.zeros((16, 8), dtype=np.float32))
    d = np.array(rows)
    rho = np.maximum(np.hypot(d[:, 0] * 8, d[:, 1] * 16), np.hypot(d[:, 2] * 8, d[:, 3] * 16))
    want = np.log2(np.maximum(rho, 2.0**-64))
    np.testing.assert_allclose(texture_lod(p, d[:, :2], d[:, 2:]), want, rtol=1e-14, atol=1e-14)


def test_texture_lod_names_bad_arguments():
    p = build_pyramid(np.zeros((8, 8), dtype=np.float32))
    with pytest.raises(ValueError, match="dy: expected shape"):
        texture_lod(p, np.zeros((3, 2)), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="dx: contains NaN"):
        texture_lod(p, np.full((1, 2), np.nan), np.zeros((1, 2)))
    with pytest.raises(TypeError, match="pyramid: expected"):
        texture_lod(np.zeros((8, 8)), np.zeros((1, 2)), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="lod: contains NaN"):
        level_weights(p, [np.inf])


def test_texel_centre_returns_the_texel():
    tex = np.arange(12, dtype=np.float32).reshape(3, 4) / 12
    p = build_pyramid(tex)
    uv = np.array([[(2 + 0.5) / 4, (1 + 0.5) / 3]])
    assert sample_level(p, uv, 0)[0] == pytest.approx(tex[1, 2])


def test_rank_equalize_is_uniform_and_monotone():
    x = np.random.default_rng(3).random((32, 32)) ** 3
    r = rank_equalize(x)
    assert r.mean() == pytest.approx(0.5, abs=1e-6)
    order = np.argsort(x, axis=None)
    assert np.all(np.diff(r.ravel()[order]) > 0)


def test_clahe_pyramid_is_uniform_per_level_and_paper_mode_is_not():
    brick = load_texture("brick")
    exact = clahe_pyramid(brick, window=16)
    for lv in exact.levels:
        if lv.size >= 64:
            hist, _ = np.histogram(lv, bins=8, range=(0, 1))
            assert hist.min() >= 0.95 * hist.max()  # uniform within rank ties
    paper = clahe_pyramid(brick, window=16, uniform=False)
    hist, _ = np.histogram(paper.levels[0], bins=8, range=(0, 1))
    assert hist.min() < 0.5 * hist.max()  # CLAHE alone only approximates uniformity


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"window": 1}, ValueError, r"window: expected an integer >= 2"),
        ({"clip_limit": 0.0}, ValueError, r"clip_limit: expected a number in \(0, 1\]"),
        ({"uniform": "yes"}, TypeError, r"uniform: expected a bool"),
    ],
)
def test_clahe_bad_parameters(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        clahe_pyramid(np.zeros((8, 8), np.float32), **kwargs)


def test_sampling_errors():
    p = build_pyramid(np.zeros((4, 4), np.float32))
    with pytest.raises(ValueError, match=r"uv: expected shape \(\.\.\., 2\)"):
        sample_trilinear(p, np.zeros((3, 3)), np.zeros(3))
    with pytest.raises(ValueError, match="uv: contains NaN"):
        sample_trilinear(p, np.full((1, 2), np.nan), np.zeros(1))
    with pytest.raises(ValueError, match=r"lod: expected shape \(2,\)"):
        sample_trilinear(p, np.zeros((2, 2)), np.zeros(3))
    with pytest.raises(TypeError, match="pyramid: expected refnpr.texture.MipPyramid"):
        sample_trilinear(np.zeros((4, 4)), np.zeros((1, 2)), np.zeros(1))
    with pytest.raises(ValueError, match="texture: 'nope' is neither a built-in texture"):
        load_texture("nope")
    with pytest.raises(ValueError, match=r"float pixels must lie in \[0, 1\]"):
        build_pyramid(np.full((2, 2), 2.0))


def test_huge_coordinates_wrap_without_overflow():
    p = build_pyramid(np.random.default_rng(4).random((4, 4)).astype(np.float32))
    uv = np.array([[1e300, -1e300], [2.0**60 + 0.25, 3.75], [1e30, 7.5]])
    got = sample_trilinear(p, uv, np.zeros(3))
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, sample_trilinear(p, uv - np.floor(uv), np.zeros(3)), atol=1e-6)


def test_samplers_are_the_device_functions():
    """sample_trilinear and sample_level run refnpr.device.sampling's lookups, bit for bit, at
    the edges of the GL_REPEAT wrap too (texel centres and borders, a period, just below 1,
    -0.0, huge coordinates)."""
    from refnpr.device.sampling import level, trilinear

    rng = np.random.default_rng(7)
    p = build_pyramid(rng.random((37, 64, 3)).astype(np.float32))
    pyr = p.packed()
    uv = rng.uniform(-3, 3, (300, 2))
    edge = [0.0, -0.0, 0.5 / 64, 1.0 / 64, 1.0, 1.0 - 2**-53, -1.0 + 2**-53, 2.0**60, -1e300]
    uv[: len(edge) ** 2] = np.array([(a, b) for a in edge for b in edge])
    lod = rng.uniform(-1, 8, 300)
    lv = rng.integers(-1, 9, 300)
    tri = sample_trilinear(p, uv, lod, dtype=np.float64)
    lev = sample_level(p, uv, lv, dtype=np.float64)
    for i in range(300):
        for c in range(3):
            assert tri[i, c] == trilinear(pyr, uv[i, 0], uv[i, 1], lod[i], c)
            assert lev[i, c] == level(pyr, lv[i], uv[i, 0], uv[i, 1], c)


def test_anisotropic_probes_match_naive_loop():
    """device.sampling.probes / level_probes: the mean of n lookups spread along the footprint's
    major axis at (j + 1/2) / n - 1/2 (EXT_texture_filter_anisotropic)."""
    from refnpr.device.sampling import footprint, level_probes, probes

    rng = np.random.default_rng(11)
    p = build_pyramid(rng.random((64, 64)).astype(np.float32))
    pyr = p.packed()
    for _ in range(200):
        uv = rng.uniform(0, 4, 2)
        dx, dy = rng.normal(0, 0.05, 2), rng.normal(0, 0.005, 2)
        lod, n, axis = footprint(tuple(dx), tuple(dy), 64.0, 64.0, 8)
        px, py = np.hypot(*(dx * 64)), np.hypot(*(dy * 64))
        assert n == max(1, min(math.ceil(max(px, py) / min(px, py) - 1e-9), 8))
        assert lod == pytest.approx(math.log2(max(px, py) / n), abs=1e-12)
        pts = [uv + np.asarray(axis) * ((j + 0.5) / n - 0.5) for j in range(n)]
        k0, k1, f = level_weights(p, lod)
        want = np.mean(
            [
                (1 - f) * naive_bilinear(p.levels[k0], *q) + f * naive_bilinear(p.levels[k1], *q)
                for q in pts
            ]
        )
        assert probes(pyr, uv[0], uv[1], lod, n, axis, 0) == pytest.approx(want, abs=1e-9)
        want0 = np.mean([naive_bilinear(p.levels[int(k0)], *q) for q in pts])
        assert level_probes(pyr, int(k0), uv[0], uv[1], n, axis) == pytest.approx(want0, abs=1e-9)


def test_writable_and_read_only_inputs_share_one_compiled_sampler():
    """numba types an array's writability: the samplers pass their inputs read-only, so a
    broadcast (read-only) uv or lod does not compile the kernel a second time."""
    from refnpr.texture import _kernels as K

    p = build_pyramid(np.random.default_rng(0).random((8, 8)).astype(np.float32))
    uv = np.full((4, 2), 0.3)
    sample_trilinear(p, uv, np.zeros(4))
    sample_level(p, uv, np.zeros(4, dtype=np.int64))
    before = (len(K.sample_trilinear.body.signatures), len(K.sample_level.body.signatures))
    got = sample_trilinear(p, np.broadcast_to([0.3, 0.3], (4, 2)), np.broadcast_to(0.0, (4,)))
    sample_level(p, np.broadcast_to([0.3, 0.3], (4, 2)), np.broadcast_to(np.int64(0), (4,)))
    assert (len(K.sample_trilinear.body.signatures), len(K.sample_level.body.signatures)) == before
    np.testing.assert_array_equal(got, sample_trilinear(p, uv, np.zeros(4)))
