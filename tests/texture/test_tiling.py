"""Textures that tile: a seam measure, Moisan's periodic component against its defining
equation and a dense solve, CLAHE on the torus, the ``tiling`` option on a user's image."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.data
from hypothesis import given
from hypothesis import strategies as st

from refnpr.styles.threshold.images import PyramidCache
from refnpr.styles.threshold.params import PARAMS
from refnpr.texture import (
    BUILTIN_TEXTURES,
    TILINGS,
    brick_texture,
    build_pyramid,
    builtin_image,
    clahe_pyramid,
    load_texture,
    periodic_clahe,
    periodic_component,
    smooth_component,
)

#: The seam may be at most this much stronger than the strongest of the interior neighbouring
#: lines (the maximum, not the mean: on the checkerboard a square's edge lies on the border,
#: as every 25 texels inside it).
SEAM_SLACK = 1.2
#: For the photographs, whose differences are spread evenly, the seam may be at most this much
#: stronger than the mean interior line: it must look like any other pair of lines.
SEAM_SLACK_MEAN = 1.5


def seam_ratio(image: np.ndarray, axis: int, stat=np.max) -> float:
    """Mean |difference| across the wrap-around border (last line next to the first), over
    ``stat`` (max or mean) of the same statistic between the interior neighbouring lines along
    ``axis`` (0: rows, the v seam; 1: columns, the u seam). At most about 1 where the texture
    tiles; a seam makes the border pair an outlier."""
    a = np.moveaxis(np.asarray(image, dtype=np.float64), axis, 0)
    interior = np.abs(np.diff(a, axis=0)).reshape(a.shape[0] - 1, -1).mean(axis=1)
    border = np.abs(a[0] - a[-1]).mean()
    return float(border / stat(interior))


def worst_seam(image: np.ndarray, stat=np.max) -> float:
    return max(seam_ratio(image, 0, stat), seam_ratio(image, 1, stat))


# --- the seam measure itself ------------------------------------------------------------------


def test_seam_measure_fails_on_the_old_brick_and_gravel_photographs():
    # scikit-image's photographs, as the built-ins used to be
    for name in ("brick", "gravel"):
        assert worst_seam(getattr(skimage.data, name)() / 255.0) > 2.0 * SEAM_SLACK, name


def test_seam_measure_sees_a_cut_and_passes_a_periodic_image():
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:96, 0:128] + 0.5
    wave = 0.5 + 0.2 * np.sin(2 * np.pi * 3 * x / 128) * np.cos(2 * np.pi * 2 * y / 96)
    wave = wave + 0.02 * rng.standard_normal(wave.shape)
    assert worst_seam(wave) < 1.0 and worst_seam(wave, np.mean) < SEAM_SLACK_MEAN
    ramp = wave + 0.3 * x / 128  # a gradient does not repeat: a jump of 0.3 at the u border
    assert seam_ratio(ramp, 1) > 3.0 and seam_ratio(ramp, 0) < 1.0


# --- every built-in texture and every CLAHE level tiles ---------------------------------------


@pytest.mark.parametrize("name", BUILTIN_TEXTURES)
def test_builtin_texture_tiles(name):
    tex = load_texture(name)
    assert tex.dtype == np.float32 and 0.0 <= tex.min() and tex.max() <= 1.0
    assert worst_seam(tex) <= 1.0
    if name != "checkerboard":
        assert worst_seam(tex, np.mean) <= SEAM_SLACK_MEAN


def test_every_old_builtin_photograph_fails_the_seam_measure():
    for name in BUILTIN_TEXTURES:
        old = getattr(skimage.data, name)() / 255.0
        assert worst_seam(old) > 1.5 or worst_seam(old, np.mean) > 2.0, name


@pytest.mark.parametrize("name", BUILTIN_TEXTURES)
def test_builtin_clahe_levels_tile(name):
    pyr = clahe_pyramid(load_texture(name), window=16)
    for k, lv in enumerate(pyr.levels):
        if min(lv.shape) >= 16:  # smaller levels have too few interior lines for statistics
            assert worst_seam(lv) <= SEAM_SLACK, (name, k, lv.shape)


@pytest.mark.parametrize("name", ["brick", "gravel"])
def test_old_photographs_clahe_levels_show_the_seam(name):
    # the measure on the CLAHE levels can fail: the photograph's seam survives CLAHE
    pyr = clahe_pyramid(getattr(skimage.data, name)(), window=16)
    assert worst_seam(pyr.levels[0]) > 2.0 * SEAM_SLACK


def test_builtin_images_are_8bit_and_deterministic():
    for name in BUILTIN_TEXTURES:
        a, b = builtin_image(name), builtin_image(name)
        assert a.dtype == np.uint8 and a.ndim == 2
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match=r"name: expected one of \['brick'"):
        builtin_image("bricks")


def test_builtin_photographs_keep_their_content():
    # the periodic component changes the photograph only by a smooth, zero-mean field
    for name in ("gravel", "grass", "camera", "moon"):
        photo = getattr(skimage.data, name)().astype(np.float64)
        new = builtin_image(name).astype(np.float64)
        assert abs(new.mean() - photo.mean()) < 1.0  # 8-bit levels
        lap = np.abs(np.diff(new - photo, 2, axis=0)).mean()  # the change is smooth:
        assert lap < 0.05 * np.abs(np.diff(photo, 2, axis=0)).mean()  # no new detail


# --- the procedural brick ---------------------------------------------------------------------


def _runs(mask: np.ndarray) -> int:
    """Number of False -> True transitions along a cyclic 1-D mask."""
    return int(np.sum(mask & ~np.roll(mask, 1)))


def test_brick_is_a_running_bond_with_mortar_that_repeats():
    img = brick_texture().astype(np.float64) / 255.0
    mortar = img > 0.6  # joints are light, brick faces dark
    assert 0.1 < mortar.mean() < 0.3
    # bricks run along v (rows): a column through brick faces crosses 5 joints per repeat,
    # a row crosses the 16 courses' joints
    assert _runs(mortar[:, 40]) == 5  # inside course 1 (texels 32 to 64)
    assert _runs(mortar[75]) == 16  # between the brick ends of both kinds of course
    # running bond: the joints of neighbouring courses are half a brick apart
    c0, c1 = 16, 48  # centres of the first two courses (32 texels each)
    j0 = np.flatnonzero(mortar[:, c0] & ~np.roll(mortar[:, c0], 1))
    j1 = np.flatnonzero(mortar[:, c1] & ~np.roll(mortar[:, c1], 1))
    offset = (j1[0] - j0[0]) % (512 / 5)
    assert abs(offset - 512 / 10) < 2.0
    # per-brick variation: brick face tones differ
    faces = [img[r, c0] for r in range(60, 512, 103)]
    assert np.ptp(faces) > 0.03
    assert worst_seam(img) <= SEAM_SLACK


def test_brick_parameters_are_checked():
    with pytest.raises(ValueError, match="courses: expected an even number"):
        brick_texture(64, courses=5)
    with pytest.raises(ValueError, match=r"size: expected an integer >= 16, got 8"):
        brick_texture(8)
    with pytest.raises(ValueError, match="mortar: expected a joint width > 0"):
        brick_texture(64, mortar=0.0)


# --- Moisan's periodic component against independent oracles ---------------------------------


def lap_periodic(a: np.ndarray) -> np.ndarray:
    """Discrete Laplacian on the torus, by rolling."""
    return sum(np.roll(a, s, ax) for s in (1, -1) for ax in (0, 1)) - 4.0 * a


def lap_interior_loop(a: np.ndarray) -> np.ndarray:
    """Discrete Laplacian with free borders (only neighbours inside the image), by loops."""
    m, n = a.shape
    out = np.zeros_like(a)
    for j in range(m):
        for i in range(n):
            for dj, di in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                if 0 <= j + dj < m and 0 <= i + di < n:
                    out[j, i] += a[j + dj, i + di] - a[j, i]
    return out


def dense_periodic_solve(u: np.ndarray) -> np.ndarray:
    """p from Lap_per p = Lap_int u and mean(p) = mean(u), a dense least-squares solve."""
    m, n = u.shape
    size = m * n
    lap = np.zeros((size, size))
    for j in range(m):
        for i in range(n):
            k = j * n + i
            for dj, di in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                lap[k, ((j + dj) % m) * n + (i + di) % n] += 1.0
                lap[k, k] -= 1.0
    rhs = lap_interior_loop(u).ravel()
    system = np.vstack([lap, np.full((1, size), 1.0 / size)])
    p, *_ = np.linalg.lstsq(system, np.append(rhs, u.mean()), rcond=None)
    return p.reshape(m, n)


@given(st.integers(1, 9), st.integers(1, 9), st.integers(0, 2**31 - 1))
def test_periodic_component_solves_its_defining_equation(m, n, seed):
    u = np.random.default_rng(seed).random((m, n))
    p = periodic_component(u)
    np.testing.assert_allclose(lap_periodic(p), lap_interior_loop(u), atol=1e-10)
    assert p.mean() == pytest.approx(u.mean(), abs=1e-12)


@pytest.mark.parametrize("shape", [(5, 7), (6, 6), (2, 9), (1, 4)])
def test_periodic_component_matches_a_dense_solve(shape):
    u = np.random.default_rng(11).random(shape)
    np.testing.assert_allclose(periodic_component(u), dense_periodic_solve(u), atol=1e-9)


def test_periodic_component_removes_a_seam_and_keeps_the_interior_differences():
    y, x = np.mgrid[0:64, 0:80] + 0.5
    grain = 0.05 * np.random.default_rng(9).random(x.shape)
    u = 0.3 + 0.4 * x / 80 + 0.2 * y / 64 + grain  # ramps: seams along u and v
    p = periodic_component(u)
    assert worst_seam(u) > 5.0 and worst_seam(p) <= SEAM_SLACK
    s = smooth_component(u)
    np.testing.assert_allclose(u, p + s, atol=1e-12)
    assert abs(s.mean()) < 1e-12
    # channels are independent: an (M, N, C) image decomposes per channel
    rgb = np.stack([u, 1.0 - u, u**2], axis=-1)
    got = periodic_component(rgb)
    for c in range(3):
        np.testing.assert_allclose(got[..., c], periodic_component(rgb[..., c]), atol=1e-12)


def test_periodic_component_bad_input():
    with pytest.raises(ValueError, match=r"image: expected a \(rows, cols\)"):
        periodic_component(np.zeros(5))
    with pytest.raises(ValueError, match="image: contains NaN or inf"):
        periodic_component(np.full((3, 3), np.nan))
    with pytest.raises(TypeError, match="image: expected a numeric image array"):
        periodic_component(np.array([["a", "b"]]))


# --- CLAHE on the torus -----------------------------------------------------------------------


def naive_periodic_clahe(a: np.ndarray, window: int, clip_limit: float, nbins: int) -> np.ndarray:
    """The same definition texel by texel: cyclic regions, clipped histograms, and for each
    texel the two nearest region centres per axis found by cyclic distance."""
    m, n = a.shape
    lo, hi = a.min(), a.max()
    bins = np.minimum(((a - lo) / (hi - lo) * nbins).astype(int), nbins - 1)

    def regions(size):
        k = max(1, round(size / min(window, size)))
        edges = [int(np.floor(i * size / k)) for i in range(k + 1)]
        return edges, [(edges[i] + edges[i + 1]) / 2 for i in range(k)]

    er, cr = regions(m)
    ec, cc = regions(n)
    maps = {}
    for i in range(len(cr)):
        for j in range(len(cc)):
            block = bins[er[i] : er[i + 1], ec[j] : ec[j + 1]].ravel()
            h = np.bincount(block, minlength=nbins).astype(float)
            limit = max(clip_limit * block.size, 1.0)
            for _ in range(8):
                excess = np.maximum(h - limit, 0).sum()
                if excess <= 0:
                    break
                h = np.minimum(h, limit) + excess / nbins
            maps[i, j] = np.cumsum(h) / block.size

    def neighbours(x, centres, size):
        # the centre at or before x and the next one, cyclically, with the weight of the next
        before = max(range(len(centres)), key=lambda i: -((x - centres[i]) % size))
        after = (before + 1) % len(centres)
        gap = (centres[after] - centres[before]) % size or size
        return before, after, ((x - centres[before]) % size) / gap

    out = np.zeros((m, n))
    for y in range(m):
        r0, r1, wy = neighbours(y + 0.5, cr, m)
        for x in range(n):
            c0, c1, wx = neighbours(x + 0.5, cc, n)
            b = bins[y, x]
            out[y, x] = (
                (1 - wy) * (1 - wx) * maps[r0, c0][b]
                + (1 - wy) * wx * maps[r0, c1][b]
                + wy * (1 - wx) * maps[r1, c0][b]
                + wy * wx * maps[r1, c1][b]
            )
    return (out - out.min()) / (out.max() - out.min())


def lit_noise(shape: tuple[int, int], seed: int) -> np.ndarray:
    """Noise under a periodic illumination: each contextual region has its own histogram, so
    CLAHE maps differ from region to region (plain noise is equalized already)."""
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]]
    light = 0.5 + 0.4 * np.sin(2 * np.pi * x / shape[1]) * np.cos(2 * np.pi * y / shape[0])
    return light * np.random.default_rng(seed).random(shape) ** 0.7


@pytest.mark.parametrize(("shape", "window"), [((12, 10), 4), ((13, 9), 5), ((7, 16), 3)])
def test_periodic_clahe_matches_a_naive_loop(shape, window):
    a = lit_noise(shape, 5)
    got = periodic_clahe(a, window=window, clip_limit=0.3, nbins=16)
    want = naive_periodic_clahe(a, window, 0.3, 16)
    np.testing.assert_allclose(got, want, atol=1e-6)
    assert np.abs(want - (a - a.min()) / np.ptp(a)).max() > 0.2  # not a global map


def test_periodic_clahe_commutes_with_tiling():
    # 42 x 34 texels: window 8 divides neither, which scikit-image's CLAHE (even on periodic
    # padding) needs to be periodic; regions on the torus tile for any size
    a = lit_noise((42, 34), 6)
    one = periodic_clahe(a, window=8, clip_limit=0.3, nbins=64)
    four = periodic_clahe(np.tile(a, (2, 2)), window=8, clip_limit=0.3, nbins=64)
    np.testing.assert_allclose(four, np.tile(one, (2, 2)), atol=1e-6)
    assert worst_seam(one) <= SEAM_SLACK


def test_periodic_clahe_treats_the_border_like_any_region_border():
    # shifting by whole regions (window 8 divides 48 x 40) shifts the result
    a = lit_noise((48, 40), 7)
    one = periodic_clahe(a, window=8, clip_limit=0.3, nbins=64)
    shifted = periodic_clahe(np.roll(a, (16, -24), (0, 1)), window=8, clip_limit=0.3, nbins=64)
    np.testing.assert_allclose(shifted, np.roll(one, (16, -24), (0, 1)), atol=1e-6)


def test_periodic_clahe_with_one_region_and_no_clip_is_histogram_equalization():
    a = np.random.default_rng(8).random((20, 30))
    got = periodic_clahe(a, window=64, clip_limit=1.0, nbins=8)
    bins = np.minimum(((a - a.min()) / np.ptp(a) * 8).astype(int), 7)
    cdf = np.cumsum(np.bincount(bins.ravel(), minlength=8)) / a.size
    want = cdf[bins]
    np.testing.assert_allclose(got, (want - want.min()) / np.ptp(want), atol=1e-6)


def test_periodic_clahe_constant_level_is_the_median():
    np.testing.assert_array_equal(
        periodic_clahe(np.full((8, 8), 0.3), window=4, clip_limit=0.01, nbins=16), 0.5
    )


# --- the papers' CLAHE properties still hold --------------------------------------------------


@pytest.mark.parametrize("name", ["brick", "grass", "gravel"])
def test_clahe_thresholds_are_uniform_and_homogeneous(name):
    pyr = clahe_pyramid(load_texture(name), window=16)
    for lv in pyr.levels:
        if lv.size >= 64:
            hist, _ = np.histogram(lv, bins=8, range=(0, 1))
            assert hist.min() >= 0.95 * hist.max()  # uniform (rank equalized) at every level
    lv = pyr.levels[0]
    blocks = lv.reshape(8, 64, 8, 64).mean(axis=(1, 3))  # 64-texel blocks: about 4 windows
    assert np.abs(blocks - 0.5).max() < 0.12  # homogeneous: no region is much darker
    # the paper's CLAHE alone approximates uniformity only
    paper = clahe_pyramid(load_texture(name), window=16, uniform=False).levels[0]
    hist, _ = np.histogram(paper, bins=8, range=(0, 1))
    assert hist.min() < 0.6 * hist.max()


def test_clahe_of_the_procedural_brick_shows_bricks_and_mortar():
    brick = load_texture("brick")
    lv = clahe_pyramid(brick, window=16).levels[0]
    mortar = brick > 0.6
    # joints stay the brightest thresholds, so thresholding draws the brick outlines last
    assert lv[mortar].mean() > 0.8 > 0.45 > lv[~mortar].mean()


# --- the tiling option on a user's image ------------------------------------------------------


def _ramp_png(tmp_path, rgb: bool = False):
    from refnpr.image import write_png_atomic

    y, x = np.mgrid[0:40, 0:56] + 0.5
    grain = 0.1 * np.random.default_rng(10).random(x.shape)
    gray = 0.15 + 0.5 * x / 56 + 0.2 * y / 40 + grain  # ramps: it does not tile
    pixels = np.stack([gray, gray * 0.9, gray * 0.8], axis=-1) if rgb else gray
    path = tmp_path / ("ramp_rgb.png" if rgb else "ramp.png")
    write_png_atomic(path, np.round(pixels * 255).astype(np.uint8))
    return path


def test_load_texture_tiling_option_on_a_user_image(tmp_path):
    path = _ramp_png(tmp_path)
    as_given = load_texture(path)
    np.testing.assert_array_equal(load_texture(path, tiling="none"), as_given)
    np.testing.assert_array_equal(load_texture(path, tiling=None), as_given)
    tiled = load_texture(path, tiling="periodic")
    assert worst_seam(as_given) > 5.0
    assert worst_seam(tiled) <= SEAM_SLACK
    assert tiled.dtype == np.float32 and tiled.shape == as_given.shape
    assert 0.0 <= tiled.min() and tiled.max() <= 1.0
    np.testing.assert_allclose(tiled, np.clip(periodic_component(as_given), 0.0, 1.0), atol=1e-6)
    # colour: per channel, gray conversion first when gray=True
    rgb = _ramp_png(tmp_path, rgb=True)
    colour = load_texture(rgb, gray=False, tiling="periodic")
    assert colour.shape == (40, 56, 3) and worst_seam(colour[..., 1]) <= SEAM_SLACK
    assert worst_seam(load_texture(rgb, tiling="periodic")) <= SEAM_SLACK
    # CLAHE levels of the made-periodic image tile too
    for lv in clahe_pyramid(tiled, window=8).levels[:2]:
        assert worst_seam(lv) <= SEAM_SLACK


def test_tiling_leaves_builtin_textures_as_they_are():
    for name in ("brick", "gravel"):
        np.testing.assert_array_equal(load_texture(name, tiling="periodic"), load_texture(name))


@pytest.mark.parametrize(
    ("tiling", "exc", "match"),
    [
        ("wrap", ValueError, r"screen.tiling: expected one of \['none', 'periodic'\]"),
        (True, TypeError, r"screen.tiling: expected one of \['none', 'periodic'\] \(or None\)"),
    ],
)
def test_tiling_bad_values(tiling, exc, match):
    assert TILINGS == ("none", "periodic")
    with pytest.raises(exc, match=match):
        load_texture("brick", param="screen", tiling=tiling)


def test_threshold_pyramid_cache_plumbs_the_tiling_option(tmp_path):
    path = str(_ramp_png(tmp_path))
    cache = PyramidCache()
    p = PARAMS.validate({"source": "image"})
    plain = cache.get(path, p)
    tiled = cache.get(path, p, tiling="periodic")
    assert len(cache) == 2 and cache.get(path, p, tiling="periodic") is tiled
    assert cache.get(path, p, tiling="none") is plain
    assert worst_seam(plain.levels[0]) > 2.0 * SEAM_SLACK
    assert worst_seam(tiled.levels[0]) <= SEAM_SLACK
    want = clahe_pyramid(load_texture(path, tiling="periodic"))
    for a, b in zip(tiled.levels, want.levels, strict=True):
        np.testing.assert_array_equal(a, b)
    raw = cache.get(
        path, PARAMS.validate({"source": "image", "clahe_levels": "none"}), tiling="periodic"
    )
    np.testing.assert_array_equal(
        raw.levels[0], build_pyramid(load_texture(path, tiling="periodic")).levels[0]
    )
