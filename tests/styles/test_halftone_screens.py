"""Procedural halftone screens and stroke layers (refnpr.texture.screens; Freudenberg sec. 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.formulas import halftone
from refnpr.texture import screens as S


@pytest.fixture(scope="module")
def hatching():
    return S.hatching_set(128, layers=6, lines=8)


@pytest.fixture(scope="module")
def bricks():
    return S.brick_set(128)


# ---------------------------------------------------------------------------------------------
# antialiased lines
# ---------------------------------------------------------------------------------------------
def _supersampled_band(size: int, b: int, width: float, phase: float, q: int = 64) -> np.ndarray:
    """Oracle: lines of constant v (wave vector (0, b)), coverage of each texel row by q point
    samples along v (brute force, independent of the box-overlap formula)."""
    v = (np.arange(size * q) + 0.5) / (size * q)
    s = b * v - phase
    d = np.abs(s - np.round(s)) * size / b  # texels to the nearest line
    inside = (d <= width / 2).reshape(size, q).mean(axis=1)
    return np.broadcast_to(inside[:, None], (size, size))


@pytest.mark.parametrize("width,phase", [(1.0, 0.0), (1.33, 0.1), (2.5, 0.37), (5.0, 0.5)])
def test_axis_lines_match_supersampled_oracle(width, phase):
    cov = S.line_coverage(64, 0, 4, width, phase=phase)
    oracle = _supersampled_band(64, 4, width, phase)
    assert cov.dtype == np.float32 and cov.shape == (64, 64)
    np.testing.assert_allclose(cov, oracle, atol=1.0 / 64 + 1e-6)


@given(
    a=st.integers(-6, 6),
    b=st.integers(-6, 6),
    frac=st.floats(0.05, 0.45),
    phase=st.floats(0.0, 1.0),
)
def test_mean_coverage_is_width_over_period(a, b, frac, phase):
    """Box filtering preserves ink: the mean coverage is width / period for any direction."""
    if a == 0 and b == 0:
        return
    size = 96
    period = size / math.hypot(a, b)
    cov = S.line_coverage(size, a, b, frac * period, phase=phase)
    assert abs(float(cov.mean()) - frac) < 0.02 + 1.0 / size


def test_hatching_layer_is_centred_on_texel_centres():
    """A 1-texel stroke at 0 degrees is solid ink on one texel row, not half ink on two."""
    lay = S.hatching_layer(64, 0.0, 8, 1.0)
    rows = np.unique(lay[:, 0])
    assert set(rows.tolist()) == {0.0, 1.0}
    assert np.count_nonzero(lay[:, 0]) == 8


# ---------------------------------------------------------------------------------------------
# hatching stroke set
# ---------------------------------------------------------------------------------------------
def test_hatching_set_shapes_levels_and_pyramid(hatching):
    assert hatching.m == 6 and hatching.size == (128, 128)
    assert [lv.shape for lv in hatching.layers] == [(6, s, s) for s in S.level_sizes(128)]
    np.testing.assert_array_equal(hatching.levels, np.arange(6) / 6)
    pyr = S.stroke_map_pyramid(hatching)
    assert pyr.n_levels == len(S.level_sizes(128))
    for lay, lv in zip(hatching.layers, pyr.levels, strict=True):
        # the stroke map of each level is the paper's encoding of that level's layers
        np.testing.assert_allclose(lv, halftone.encode_stroke_map(lay, levels=hatching.levels))
        assert lv.min() >= 0.0 and lv.max() <= 1.0


@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_hatching_tone_at_layer_midpoints(hatching, level):
    """Calibration: halfway between consecutive layer onsets, the binary threshold's white
    fraction equals the intensity (within 0.035 on levels of 16 texels and more)."""
    screen = S.stroke_map_pyramid(hatching).levels[level]
    m = hatching.m
    for i in range(m):
        i_mid = 1.0 - (i + 0.5) / m
        white = np.mean(screen + i_mid > 1.0)  # sec. 3.1 rule, written out
        assert abs(white - i_mid) < 0.035, (level, i, white, i_mid)


def test_hatching_coarse_lines_are_never_thinner_than_min_width():
    hs = S.hatching_set(64, layers=4, lines=16, min_width=2.0)
    for lay in hs.layers:
        if lay.shape[1] < 8:  # 4x4 texels and below cannot hold four stroke directions
            continue
        for layer in lay:
            # a solid texel exists in every layer: strokes at least ~min_width wide
            assert layer.max() > 0.99


# ---------------------------------------------------------------------------------------------
# bricks (Figure 7)
# ---------------------------------------------------------------------------------------------
def test_brick_normals_point_out_of_each_brick(bricks):
    nm = bricks.normals[0] * 2.0 - 1.0
    np.testing.assert_allclose(np.linalg.norm(nm, axis=-1), 1.0, atol=1e-5)
    s = 128
    mortar, outline = 0.025 * s / 2, max(0.02 * s, 1.0)
    band = int(mortar + outline / 2)  # texel inside the outline band, from the cell border
    # brick (row 0, col 0) spans u in [0, 1/2), v in [0, 1/4): rows 0..31, cols 0..63
    mid_row, mid_col = 16, 32
    left = nm[mid_row, band]
    right = nm[mid_row, 63 - band]
    low = nm[band, mid_col]  # low v
    high = nm[31 - band, mid_col]
    face = nm[mid_row, mid_col]
    assert left[0] < -0.5 and abs(left[1]) < 1e-6
    assert right[0] > 0.5 and abs(right[1]) < 1e-6
    assert low[1] < -0.5 and abs(low[0]) < 1e-6
    assert high[1] > 0.5 and abs(high[0]) < 1e-6
    np.testing.assert_allclose(face, [0.0, 0.0, 1.0], atol=1e-6)


def test_brick_stroke_lighting_keeps_the_shadowed_outlines(bricks):
    """Sec. 5.2 / Fig. 7 in texture space: lit from +u +v, the outlines facing -u and -v stay,
    the ones facing +u and +v vanish."""
    screen = S.stroke_map_pyramid(bricks).levels[0]
    nm = bricks.normals[0] * 2.0 - 1.0
    light = np.array([1.0, 1.0, 1.0]) / math.sqrt(3.0)
    lit = np.clip(nm @ light, 0.0, 1.0)  # DOT3, written out
    intensity = 0.1 + 0.85 * lit
    black = ~(screen + intensity > 1.0)
    s = 128
    band = int(0.025 * s / 2 + 0.02 * s / 2)
    rows = slice(8, 24)  # away from the corners
    cols = slice(16, 48)
    assert black[rows, band].all() and black[band, cols].all()  # facing -u, -v
    assert not black[rows, 63 - band].any() and not black[31 - band, cols].any()


def test_brick_set_options_are_validated():
    with pytest.raises(ValueError, match=r"rows: expected an even number of brick rows"):
        S.brick_set(64, rows=3)
    with pytest.raises(ValueError, match=r"tilt_deg: expected a finite number >= 0.0"):
        S.brick_set(64, tilt_deg=90.0)
    with pytest.raises(ValueError, match=r"size: expected a power of two in \[32, 2048\]"):
        S.brick_set(100)


# ---------------------------------------------------------------------------------------------
# hand-drawn layers (PNG)
# ---------------------------------------------------------------------------------------------
def test_png_layers_round_trip(tmp_path):
    import imageio.v3 as iio

    rng = np.random.default_rng(4)
    ink0 = (rng.random((32, 32)) > 0.8).astype(np.float64)
    ink1 = np.round(rng.random((32, 32)) * 255) / 255
    rgba = np.zeros((32, 32, 4), np.uint8)  # black ink on a transparent background
    rgba[..., 3] = (ink0 * 255).astype(np.uint8)
    gray = ((1.0 - ink1) * 255).round().astype(np.uint8)  # black ink on white
    p0, p1 = tmp_path / "dark.png", tmp_path / "light.png"
    iio.imwrite(p0, rgba)
    iio.imwrite(p1, gray)
    strokes = S.load_stroke_layers([p0, p1], levels=[0.0, 0.5])
    np.testing.assert_allclose(strokes.layers[0][0], ink0, atol=1e-6)
    np.testing.assert_allclose(strokes.layers[0][1], ink1, atol=1e-6)
    # coarser levels are the box-filtered coverages
    np.testing.assert_allclose(
        strokes.layers[1][0], ink0.reshape(16, 2, 16, 2).mean(axis=(1, 3)), atol=1e-6
    )
    screen = S.stroke_map_pyramid(strokes).levels[0]
    expected = np.ones((32, 32))
    for ink, g in ((ink1, 0.5), (ink0, 0.0)):  # lightest first, darkest on top (sec. 4.2)
        expected = (1 - ink) * expected + ink * g
    np.testing.assert_allclose(screen, expected, atol=1e-6)


def test_png_layer_errors(tmp_path):
    with pytest.raises(TypeError, match=r"paths: expected a list of layer files"):
        S.load_stroke_layers(str(tmp_path / "a.png"))
    with pytest.raises(ValueError, match=r"paths\[0\]: .* is not an existing image file"):
        S.load_stroke_layers([tmp_path / "missing.png"])
    with pytest.raises(ValueError, match=r"layers\[1\]: expected the shape of layers\[0\]"):
        S.stroke_set_from_layers([np.zeros((8, 8)), np.zeros((4, 4))])
    with pytest.raises(ValueError, match=r"levels: expected strictly increasing"):
        S.stroke_set_from_layers([np.zeros((8, 8)), np.zeros((8, 8))], levels=[0.5, 0.2])


# ---------------------------------------------------------------------------------------------
# engraving (sec. 4.1)
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("profile", ["ramp", "triangle"])
def test_engraving_pyramid_levels_are_the_profile_at_each_resolution(profile):
    pyr = S.engraving_pyramid(64, profile=profile)
    assert [lv.shape for lv in pyr.levels] == [(1, s) for s in S.level_sizes(64)]
    for lv in pyr.levels[:-1]:
        n = lv.shape[1]
        f = (np.arange(n) + 0.5) / n  # texel centres
        expected = f if profile == "ramp" else np.abs(2 * f - 1)
        np.testing.assert_allclose(lv[0], expected, atol=1e-7)
        # uniform as far as n texels allow: the white fraction of a threshold is exact at
        # the texel values' midpoints
        for intensity in (0.25, 0.5, 0.75):
            assert abs(np.mean(lv[0] + intensity > 1.0) - intensity) <= 1.0 / n + 1e-9
    assert pyr.levels[-1].shape == (1, 1) and float(pyr.levels[-1][0, 0]) == 0.5


def test_engraving_pyramid_errors():
    with pytest.raises(ValueError, match=r"size: expected a power of two"):
        S.engraving_pyramid(100)
    with pytest.raises(ValueError, match=r"profile: expected one of"):
        S.engraving_pyramid(64, profile="sine")


def test_line_coverage_errors():
    with pytest.raises(ValueError, match=r"a, b: got \(0, 0\)"):
        S.line_coverage(16, 0, 0, 1.0)
    with pytest.raises(ValueError, match=r"width: expected a finite number > 0.0"):
        S.line_coverage(16, 0, 2, 0.0)
    with pytest.raises(TypeError, match=r"size: expected an integer, got float"):
        S.line_coverage(16.0, 0, 2, 1.0)
