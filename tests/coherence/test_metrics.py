"""warp, the per-pair numbers and the measure driver, against naive loops and the formulas."""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import pytest

from refnpr.coherence import (
    MOTION_CHANNELS,
    CoherenceReport,
    PairMetrics,
    luminance,
    measure,
    motion_field,
    pair_metrics,
    warp,
)
from refnpr.raster import rasterize
from refnpr.render import render
from refnpr.scenes import SceneObject, icosphere, transform_matrix
from refnpr.styles import Style, get_style

from .fixtures import AMP, EYE, H, SineStyle, W, camera, pixel_size, scene, wall


def gbuf(sc):
    return rasterize(sc, None, W, H, MOTION_CHANNELS, 1, dtype=np.float64)


def moved_wall_pair(dx=0.137, dy=-0.05):
    before = scene([wall(size=40.0)])
    after = scene([wall(dx, dy, size=40.0)])
    return after, before


def naive_bilinear(img, x, y):
    """img (H, W) at continuous pixel coordinates (centre of pixel i at i + 0.5), clamped."""
    h, w = img.shape
    fx, fy = x - 0.5, y - 0.5
    i0, j0 = math.floor(fx), math.floor(fy)
    ax, ay = fx - i0, fy - j0
    total = 0.0
    for dj, wy in ((0, 1 - ay), (1, ay)):
        for di, wx in ((0, 1 - ax), (1, ax)):
            jj = min(max(j0 + dj, 0), h - 1)
            ii = min(max(i0 + di, 0), w - 1)
            total += wx * wy * img[jj, ii]
    return total


@pytest.mark.parametrize("shift_px", [(1.98, -0.72), (0.3, 0.2)])
def test_warp_equals_a_naive_bilinear_loop(shift_px):
    s = pixel_size(EYE[2])
    after, before = moved_wall_pair(shift_px[0] * s, -shift_px[1] * s)
    mf = motion_field(gbuf(after), gbuf(before), after, before)
    if shift_px == (0.3, 0.2):  # the first column and row land in the clamped edge band
        assert mf.valid[:, 0].all() and mf.valid[0, :].all()
        assert 0 <= mf.xy[0, 0, 0] < 0.5 and 0 <= mf.xy[0, 0, 1] < 0.5
    rng = np.random.default_rng(3)
    prev = rng.random((H, W))
    got = warp(prev, mf)
    assert mf.valid.sum() > 0.9 * W * H
    for j, i in np.argwhere(mf.valid):
        assert got[j, i] == pytest.approx(naive_bilinear(prev, *mf.xy[j, i]), abs=1e-12)
    assert np.all(got[~mf.valid] == 0.0)
    rgb = np.stack([prev, 1 - prev, prev**2], -1)
    np.testing.assert_allclose(warp(rgb, mf)[..., 1][mf.valid], 1 - got[mf.valid], atol=1e-12)


def test_pair_metrics_follow_their_definitions():
    after, before = moved_wall_pair()
    mf = motion_field(gbuf(after), gbuf(before), after, before)
    rng = np.random.default_rng(7)
    img = rng.random((H, W, 4)).astype(np.float32)
    prev = rng.random((H, W, 4)).astype(np.float32)
    got = pair_metrics(img, prev, mf, frame=5)
    # the formulas written out: Rec. 709 luminance, masked means, ink = Y < 0.5
    y = 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]
    yp = 0.2126 * prev[..., 0] + 0.7152 * prev[..., 1] + 0.0722 * prev[..., 2]
    m = mf.valid
    y_hat = np.zeros((H, W))
    for j, i in np.argwhere(m):
        y_hat[j, i] = naive_bilinear(yp.astype(np.float64), *mf.xy[j, i])
    e = np.abs(y - y_hat)[m].mean()
    d = np.abs(y - yp)[m].mean()
    assert got.frame == 5
    assert got.n_valid == m.sum() and got.n_covered == W * H
    assert got.warp_error == pytest.approx(e, rel=1e-6)
    assert got.plain_diff == pytest.approx(d, rel=1e-6)
    assert got.ratio == pytest.approx(e / d, rel=1e-6)
    assert got.flip == pytest.approx(((y < 0.5) != (y_hat < 0.5))[m].mean(), abs=1e-12)
    assert got.flip_plain == pytest.approx(((y < 0.5) != (yp < 0.5))[m].mean(), abs=1e-12)
    # the wall is frontal at view distance 5: a uniform shift of (dx, dy) / pixel size
    assert got.motion_px == pytest.approx(math.hypot(0.137, 0.05) / pixel_size(EYE[2]), rel=1e-9)


def test_ratio_is_nan_when_nothing_changed_and_json_says_null():
    sc = scene([wall()])
    mf = motion_field(gbuf(sc), gbuf(sc), sc, sc)
    img = np.full((H, W, 4), 0.25, np.float32)
    got = pair_metrics(img, img, mf)
    assert got.warp_error == 0.0 and got.plain_diff == 0.0 and got.flip == 0.0
    assert math.isnan(got.ratio)
    assert got.as_dict()["ratio"] is None


def test_empty_mask_gives_nan_numbers():
    sc = scene([wall()])
    far = scene([wall()], camera(180.0))  # the previous camera looks away: nothing lands
    mf = motion_field(gbuf(sc), gbuf(far), sc, far)
    assert mf.covered.any() and not mf.valid.any()
    got = pair_metrics(np.ones((H, W, 4)), np.ones((H, W, 4)), mf)
    assert got.n_valid == 0 and math.isnan(got.warp_error) and math.isnan(got.flip)


def test_luminance_weights():
    px = np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]])
    np.testing.assert_allclose(luminance(px)[0], [0.2126, 0.7152, 0.0722])
    with pytest.raises(ValueError, match=r"rgb: expected an \(H, W, 3\)"):
        luminance(np.zeros((4, 4)))


def test_luminance_ignores_alpha_even_where_it_is_not_finite():
    rgba = np.ones((2, 3, 4))
    rgba[1, 2, 3] = np.nan
    np.testing.assert_array_equal(luminance(rgba), luminance(rgba[..., :3]))


@pytest.mark.parametrize("which", ["image", "prev_image"])
def test_a_frame_with_a_nan_pixel_is_refused_by_its_name(which):
    sc = scene([wall()])
    mf = motion_field(gbuf(sc), gbuf(sc), sc, sc)
    images = {"image": np.ones((H, W, 4)), "prev_image": np.ones((H, W, 4))}
    images[which][2, 3, 1] = np.nan
    message = rf"^{which}: expected finite colours, got NaN or inf in 1 of its pixels, the first "
    with pytest.raises(ValueError, match=message + r"at \(y, x\) = \(2, 3\)"):
        pair_metrics(images["image"], images["prev_image"], mf)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, bool])
def test_a_frame_that_is_not_float_linear_rgb_is_refused(dtype):
    """A PNG frame as read is uint8 0..255: measured as it is, the metrics came out 255 times
    too large, without a word."""
    sc = scene([wall()])
    mf = motion_field(gbuf(sc), gbuf(sc), sc, sc)
    frame = np.ones((H, W, 4), dtype=dtype)
    with pytest.raises(TypeError, match=r"^image: expected float linear RGB.*got dtype"):
        pair_metrics(frame, np.ones((H, W, 4)), mf)


# -- measure ------------------------------------------------------------------------------
def test_static_scene_measures_zero():
    sc = scene([wall(tz=-1.0), SceneObject(icosphere(2, 1.0), transform_matrix((0.3, 0, 0.5)))])
    rep = measure([sc, sc, sc], "toon", W, H, spp=4)
    assert len(rep.rows) == 2
    for r in rep.rows:
        assert r.warp_error == 0.0 and r.plain_diff == 0.0
        assert r.flip == 0.0 and r.flip_plain == 0.0
        assert r.n_valid == r.n_covered == W * H
        assert math.isnan(r.ratio) and r.motion_px == 0.0


def test_translated_texture_small_warp_error_large_plain_difference():
    dx = 2.5 * pixel_size(EYE[2])  # 2.5 px per frame: the warp samples between pixel centres
    frames = [scene([wall(k * dx, size=40.0)]) for k in range(3)]
    rep = measure(frames, SineStyle(), W, H)
    period_px = 0.5 / pixel_size(EYE[2])  # tile 0.5 world units per texture repeat
    k = 2 * math.pi / period_px
    # bilinear interpolation error bound, (|f_xx| + |f_yy|) / 8 per unit spacing
    bound = (AMP * k**2 + AMP * k**2) / 8
    for r in rep.rows:
        assert 0.0 < r.warp_error < bound / 2  # a mean, inside the pointwise bound
        assert r.motion_px == pytest.approx(2.5, abs=1e-9)
        assert r.plain_diff > 10 * r.warp_error
        assert r.ratio < 0.1
        assert r.n_valid > 0.9 * W * H
    s = rep.summary()
    assert s["warp_error"]["max"] == max(r.warp_error for r in rep.rows)
    assert s["warp_error"]["median"] == pytest.approx(np.median([r.warp_error for r in rep.rows]))


def test_screen_fixed_texture_has_warp_error_above_the_plain_difference():
    # the shower-door effect: a pattern fixed in screen space while the surface moves is flat
    # but does not move with the surface: D = 0, E > 0 (the ratio is then undefined)
    class Screen(Style):
        name = "test_coherence_screen"

        def requires(self, scene):
            return frozenset({"mesh_id"})

        def shade(self, ctx):
            hh, ww = ctx.gb.sample_shape
            xs = np.arange(ww)[None, :] + 0.5
            v = 0.5 + 0.4 * np.sin(2 * np.pi * xs / 7.0) * np.ones((hh, 1))
            out = np.ones((hh, ww, 4), np.float32)
            out[..., :3] = v[..., None]
            return out

    frames = [scene([wall(k * 0.137, size=40.0)]) for k in range(2)]
    r = measure(frames, Screen(), W, H).rows[0]
    assert r.plain_diff == 0.0 and r.warp_error > 0.05


def test_measure_shades_in_order_through_the_sequence_protocol():
    calls = []

    class Spy(Style):
        name = "test_coherence_spy"

        def requires(self, scene):
            return frozenset({"mesh_id"})

        def for_frame(self, scene, prev_scene):
            calls.append(("for_frame", scene, prev_scene))
            return self

        def initial_state(self):
            return 0

        def shade_frame(self, ctx, state):
            calls.append(("shade_frame", ctx.scene, state))
            out = np.ones(ctx.gb.sample_shape + (4,), np.float32)
            out[..., :3] = 0.1 * state
            return out, state + 1

    frames = [scene([wall(k * 0.1)]) for k in range(3)]
    rep = measure(frames, Spy(), 16, 12, keep_images=True)
    assert [c[0] for c in calls] == ["for_frame", "shade_frame"] * 3
    assert calls[0][1:] == (frames[0], None)
    assert calls[2][1:] == (frames[1], frames[0]) and calls[4][1:] == (frames[2], frames[1])
    assert [c[2] for c in calls if c[0] == "shade_frame"] == [0, 1, 2]
    assert [float(im[0, 0, 0]) for im in rep.images] == pytest.approx([0.0, 0.1, 0.2])


def test_measure_frames_equal_render_for_a_stateless_style():
    frames = [scene([wall(k * 0.1), SceneObject(icosphere(2, 0.8))]) for k in range(2)]
    style = get_style("toon", n=3)
    rep = measure(frames, style, W, H, spp=4, keep_images=True)
    for sc, img in zip(frames, rep.images, strict=True):
        assert np.array_equal(img, render(sc, style, W, H, 4).rgba)


def test_measure_bad_input():
    sc = scene([wall()])
    with pytest.raises(ValueError, match=r"scenes: need at least two frames"):
        measure([sc], "toon", W, H)
    with pytest.raises(TypeError, match=r"scenes: expected a sequence of still Scenes"):
        measure(sc, "toon", W, H)
    with pytest.raises(TypeError, match=r"scenes\[1\]: expected a refnpr.scenes.Scene"):
        measure([sc, "x"], "toon", W, H)
    with pytest.raises(ValueError, match=r"frames: got 3 frame numbers for 2 scenes"):
        measure([sc, sc], "toon", W, H, frames=[0, 1, 2])
    other = scene([wall(), SceneObject(icosphere(1, 0.5))])
    with pytest.raises(ValueError, match=r"prev_scene: has 1 objects, scene has 2"):
        measure([sc, other], "toon", W, H)


# -- report -------------------------------------------------------------------------------
def _report():
    rows = (
        PairMetrics(1, 0.1, 0.2, 0.5, 0.01, 0.02, 1.0, 100, 120),
        PairMetrics(2, 0.3, 0.0, float("nan"), 0.03, 0.0, 0.0, 90, 120),
        PairMetrics(3, 0.2, 0.4, 0.5, 0.02, 0.05, 2.0, 80, 120),
    )
    return CoherenceReport(rows, {"style": "toon"})


def test_report_summary_and_json(tmp_path):
    rep = _report()
    s = rep.summary()
    assert s["warp_error"] == {"median": 0.2, "max": 0.3, "defined": 3}
    assert s["ratio"] == {"median": 0.5, "max": 0.5, "defined": 2}
    data = json.loads(rep.to_json())
    assert data["pairs"][1]["ratio"] is None
    assert data["summary"]["n_valid"]["median"] == 90
    path = rep.save(tmp_path / "sub" / "c.json")
    assert json.loads(path.read_text()) == data


def test_report_plot_writes_a_png(tmp_path):
    path = _report().plot(tmp_path / "c.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_plot_without_matplotlib_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(ImportError, match=r"plot: needs matplotlib"):
        _report().plot(tmp_path / "c.png")
