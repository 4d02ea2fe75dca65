"""Veryovka Fig. 4 fidelity: cross-hatching shows two crossing sets of dark lines; stipple dots
are round in screen space, jittered, and keep tone.

Measured properties, each with an independent oracle: the power spectrum of a rendered
cross-hatched plane, second moments and nearest-neighbour distances of the connected components
of a thresholded stipple texture under an anisotropic mapping, and a water-filling allocation
simulated by small increments.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import cKDTree

from refnpr.formulas.threshold import (
    combine_thresholds,
    dot_dyadic_scale,
    dot_threshold,
    layer_whites,
    stipple_scales,
    stipple_threshold,
    stipple_tone_table,
)
from refnpr.render import render
from refnpr.styles.threshold import ThresholdStyle

from .test_threshold_tone import flat_scene

# ----------------------------------------------------------------------------- cross-hatching


def _orientation_peaks(img: np.ndarray) -> tuple[float, float]:
    """Largest spectral power near the horizontal and near the vertical frequency axes.

    Lines along x (functions of y) put their power on the vertical frequency axis and lines
    along y on the horizontal one; a 20 degree wedge around each axis, DC excluded.
    """
    a = img - img.mean()
    p = np.abs(np.fft.fftshift(np.fft.fft2(a))) ** 2
    h, w = p.shape
    fy, fx = np.mgrid[-(h // 2) : h - h // 2, -(w // 2) : w - w // 2]
    ang = np.degrees(np.arctan2(np.abs(fy), np.abs(fx)))
    r = np.hypot(fx, fy)
    ring = r > 4
    return float(p[ring & (ang < 10)].max()), float(p[ring & (ang > 80)].max())


@pytest.mark.parametrize("x", [0.5, 0.6])
def test_cross_hatching_shows_both_line_sets(x):
    """Both orientations carry comparable line power where both layers are drawn.

    The earlier composition (one common level scaled per layer) gave the second set 1/3 of the
    first set's power at x = 0.5 and 1/7 at 0.6 with onsets [1, 0.75]: dashes, not lines.
    """
    style = ThresholdStyle(
        source="lines",
        period=8.0,
        uv_scale=3.0,
        uniform=True,
        specular=False,
        directions=[0.0, 90.0],
        onsets=[1.0, 0.75],
    )
    img = render(flat_scene(x), style, 192, 192, 1).rgba[..., 0].astype(np.float64)
    p_h, p_v = _orientation_peaks(img)
    assert min(p_h, p_v) / max(p_h, p_v) > 0.5, (p_h, p_v)
    assert abs(img.mean() - x) < 0.02  # tone kept


def _whites_by_increments(x: float, onsets: list[float], steps: int = 20000) -> np.ndarray:
    """Oracle: give darkness -ln x to the active layers of least darkness in small steps."""
    lam_total = -math.log(x)
    act = -np.log(np.asarray(onsets))
    lev = np.zeros(len(onsets))
    d = lam_total / steps
    for k in range(steps):
        lam = k * d
        active = act <= lam + 1e-12
        low = lev[active].min()
        rising = active & (lev <= low + d)
        lev[rising] += d / rising.sum()
    return np.exp(-lev)


@pytest.mark.parametrize("onsets", [[1.0, 0.75], [1.0, 0.5, 0.8], [0.4, 1.0, 0.9]])
def test_layer_allocation_matches_water_filling_oracle(onsets):
    for x in (0.9, 0.7, 0.5, 0.3, 0.1):
        want = _whites_by_increments(x, onsets)
        got = layer_whites(np.array(x), onsets)
        np.testing.assert_allclose(got, want, atol=2e-3)
        assert got.prod() == pytest.approx(x, rel=1e-9)  # tone: product of white fractions


def test_composite_is_union_of_layer_lines_and_uniform():
    rng = np.random.default_rng(3)
    onsets = [1.0, 0.75]
    f = rng.uniform(0, 1, (2, 100_000))
    t = combine_thresholds(list(f), onsets=onsets)
    for x in (0.2, 0.45, 0.6, 0.8):
        w = layer_whites(np.array(x), onsets)
        white = (f[0] <= w[0]) & (f[1] <= w[1])  # white in every layer
        assert np.mean(white == (x >= t)) > 0.9999
        assert abs(np.mean(x >= t) - x) < 0.006
    # at x = 0.6 the first set is frozen at its onset width, the second catches up
    w = layer_whites(np.array(0.6), onsets)
    assert 1 - w[0] == pytest.approx(0.25) and 1 - w[1] == pytest.approx(0.2)


# ---------------------------------------------------------------------------------- stipple

ANISO = 4.0  # the mapping stretches u four times less than v on screen
TABLE = stipple_tone_table()


def _aniso_plane(size: int = 256, w: float = 12.0):
    """uv of a plane whose texture runs 4x faster along v than along u per pixel."""
    y, x = np.mgrid[0:size, 0:size] + 0.5
    du = 1.0 / 40.0
    uv = np.stack([x * du, y * du * ANISO], -1)
    gx = np.broadcast_to([du, 0.0], uv.shape)
    gy = np.broadcast_to([0.0, du * ANISO], uv.shape)
    return uv, gx, gy, w


def _dots(black: np.ndarray):
    lab, n = ndimage.label(black)
    out = []
    for i, sl in enumerate(ndimage.find_objects(lab), start=1):
        if sl[0].start == 0 or sl[1].start == 0:
            continue
        if sl[0].stop == black.shape[0] or sl[1].stop == black.shape[1]:
            continue
        yy, xx = np.nonzero(lab[sl] == i)
        if yy.size < 12:
            continue
        cov = np.cov(np.stack([xx, yy]))
        ev = np.linalg.eigvalsh(cov)
        out.append((math.sqrt(ev[1] / ev[0]), xx.mean() + sl[1].start, yy.mean() + sl[0].start))
    return np.array(out)


@pytest.mark.parametrize("frac_s", [0.0, 0.5])
def test_stipple_dots_are_round_under_an_anisotropic_mapping(frac_s):
    uv, gx, gy, w = _aniso_plane()
    s_u, s_v = stipple_scales(gx, gy, w)
    s_u = np.floor(s_u) + frac_s
    s_v = np.floor(s_v) + frac_s
    f = stipple_threshold(uv, s_u, s_v, tone_table=TABLE)
    dots = _dots(0.88 < f)
    assert len(dots) > 100
    assert np.median(dots[:, 0]) < 1.25  # principal axes ratio of the dots
    # the isotropic lattice dots of dot_threshold are stretched by the mapping (the oracle fails)
    old = dot_threshold(uv, np.floor(dot_dyadic_scale(gx, gy, w)) + frac_s)
    assert np.median(_dots(0.88 < old)[:, 0]) > 2.0


def test_stipple_dots_are_jittered_not_on_a_lattice():
    uv, gx, gy, w = _aniso_plane()
    s_u, s_v = (np.floor(s) for s in stipple_scales(gx, gy, w))

    def nn_spread(jitter):
        d = _dots(0.85 < stipple_threshold(uv, s_u, s_v, jitter=jitter))
        pts = d[:, 1:]
        dist, _ = cKDTree(pts).query(pts, k=2)
        nn = dist[:, 1]
        return float(nn.std() / nn.mean())

    assert nn_spread(0.0) < 0.05  # a rigid lattice: every dot has the same nearest distance
    assert nn_spread(0.2) > 0.1


def test_stipple_keeps_tone_at_intermediate_scales():
    uv, gx, gy, w = _aniso_plane(320)
    s_u, s_v = stipple_scales(gx, gy, w)
    table = TABLE
    for fu, fv in ((0.3, 0.7), (0.5, 0.5), (0.9, 0.1)):
        f = stipple_threshold(uv, np.floor(s_u) + fu, np.floor(s_v) + fv, tone_table=table)
        for x in (0.2, 0.5, 0.8, 0.9):
            assert abs(np.mean(x >= f) - x) < 0.03, (fu, fv, x)


def test_stipple_is_exactly_uniform_at_integer_scales_and_continuous_across_them():
    rng = np.random.default_rng(7)
    uv = rng.uniform(0, 6, (200_000, 2))
    f = stipple_threshold(uv, np.full(len(uv), 2.0), np.full(len(uv), 1.0))
    hist, _ = np.histogram(f, bins=10, range=(0, 1))
    assert np.all(np.abs(hist - 20_000) < 5 * math.sqrt(20_000))
    a = stipple_threshold(uv[:500], np.full(500, 3.0 - 1e-9), np.full(500, 1.5))
    b = stipple_threshold(uv[:500], np.full(500, 3.0), np.full(500, 1.5))
    np.testing.assert_allclose(a, b, atol=1e-6)


def test_stipple_errors_name_the_parameter():
    with pytest.raises(TypeError, match="tone_table"):
        stipple_threshold(np.zeros(2), 0.0, 0.0, tone_table=np.eye(3))
    with pytest.raises(ValueError, match="jitter"):
        stipple_threshold(np.zeros(2), 0.0, 0.0, jitter=0.0, tone_table=TABLE)
    with pytest.raises(TypeError, match="jitter"):
        stipple_threshold(np.zeros(2), 0.0, 0.0, jitter=True)
    with pytest.raises(ValueError, match=r"jitter: expected a dot offset in \[0, 0.4\]"):
        stipple_threshold(np.zeros(2), 0.0, 0.0, jitter=0.5)
    with pytest.raises(ValueError, match="w"):
        stipple_scales(np.ones(2), np.ones(2), 0.0)
    with pytest.raises(TypeError, match="jitter"):
        ThresholdStyle(source="stipple", jitter="yes")
    with pytest.raises(ValueError, match="jitter"):
        ThresholdStyle(source="stipple", jitter=0.9)
