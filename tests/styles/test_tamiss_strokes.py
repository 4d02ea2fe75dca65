"""Drawn extents, extrusion with per-stroke randomisation, and the anti-aliased strip rasterizer."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.formulas.tamiss import StrokeStrip, extrude_stroke, fit_fragments, pack_id
from refnpr.styles.tamiss.field import StrokeField
from refnpr.styles.tamiss.raster import BRUSHES, brush_texture, rasterize_strips
from refnpr.styles.tamiss.strokes import (
    Strips,
    centreline,
    drawn_segments,
    extrude,
    mean_speed,
)

IDS = pack_id(0, 0, 2, np.arange(3), 1, 3)


def fits(ts=((0.2, 0.8), (0.0, 1.0), (0.3, 0.7)), curved=True):
    """Three float64 strokes fitted to dense fragments of known curves."""
    ids, t, x, y = [], [], [], []
    for k, (a, b) in enumerate(ts):
        tk = np.linspace(a, b, 200)
        ids.append(np.full(tk.size, IDS[k]))
        t.append(tk)
        x.append(10 + 80 * tk + 7 * k)
        y.append(20 + 30 * tk + (25 * tk**2 - 10 * tk**3 if curved else 0.0) + 9 * k)
    uid, fit = fit_fragments(np.concatenate(ids), *(np.concatenate(v) for v in (t, x, y)))
    assert np.array_equal(uid, IDS)
    return fit


def test_extrusion_matches_the_formula_layer_inside_the_fitted_range():
    fit = fits()
    seg = np.full((3, 2, 2), np.nan)
    seg[:, 0] = [[0.25, 0.75], [0.1, 0.9], [0.3, 0.7]]
    field = StrokeField.from_params(width_jitter=0.0)
    strips = extrude(fit, IDS, seg, field, width=2.5, taper=0.2, samples=12)
    ref = extrude_stroke(fit, seg[:, 0, 0], seg[:, 0, 1], width=2.5, samples=12, taper=0.2)
    np.testing.assert_allclose(strips.strip.left, ref.left, atol=1e-9)
    np.testing.assert_allclose(strips.strip.right, ref.right, atol=1e-9)
    np.testing.assert_allclose(strips.strip.t, ref.t, atol=1e-12)
    np.testing.assert_array_equal(strips.ids, IDS)


def test_centreline_continues_along_the_tangent_outside_the_data():
    fit = fits(curved=False)  # straight lines: the continuation is exact
    t = np.array([[0.0, 0.5, 1.0]] * 3)
    x, y, tx, ty = centreline(fit, t)
    k = np.arange(3)[:, None]
    np.testing.assert_allclose(x, 10 + 80 * t + 7 * k, atol=1e-6)
    np.testing.assert_allclose(y, 20 + 30 * t + 9 * k, atol=1e-6)
    np.testing.assert_allclose(np.hypot(tx, ty), 1.0)
    np.testing.assert_allclose(mean_speed(fit), np.hypot(80, 30), rtol=1e-9)


def test_extents():
    fit = fits()
    rng, n = drawn_segments(fit, "range")
    np.testing.assert_allclose(rng[:, 0], np.stack([fit.t_min, fit.t_max], -1))
    assert np.all(np.isnan(rng[:, 1])) and np.all(n == 1)
    whole, _ = drawn_segments(fit, "stroke")
    np.testing.assert_array_equal(whole[:, 0], [[0, 1]] * 3)
    vis, nv = drawn_segments(fit, "visible")
    assert np.all(nv == 1)  # evenly covered strokes are visible over their whole range
    np.testing.assert_allclose(vis[:, 0], rng[:, 0], atol=0.02)
    od, _ = drawn_segments(fit, "overdraw", overdraw=6.0)
    np.testing.assert_allclose(od[1, 0], [0.0, 1.0])  # already the whole stroke: clamped
    x0, y0, _, _ = centreline(fit, vis[:, 0, :1])
    x1, y1, _, _ = centreline(fit, od[:, 0, :1])
    run_on = np.hypot(x1 - x0, y1 - y0)[[0, 2], 0]
    np.testing.assert_allclose(run_on, 6.0, rtol=0.05)  # 6 px at the mean speed


def test_randomisation_is_seeded_by_the_stroke_id():
    fit = fits(curved=False)
    seg = np.full((3, 2, 2), np.nan)
    seg[:, 0] = [[0.2, 0.8], [0.0, 1.0], [0.3, 0.7]]
    field = StrokeField.from_params(width_jitter=0.4)
    kw = {"width": 2.0, "taper": 0.0, "wobble": 1.5, "end_jitter": 0.3, "samples": 40}
    a = extrude(fit, IDS, seg, field, **kw)
    b = extrude(fit.take([2, 0]), IDS[[2, 0]], seg[[2, 0]], field, **kw)  # other order
    np.testing.assert_array_equal(a.strip.left[[2, 0]], b.strip.left)
    plain = extrude(fit, IDS, seg, field, **{**kw, "wobble": 0.0, "end_jitter": 0.0})
    # width within the jitter, wobble within 1.5 x its amplitude, end moves within end_jitter / 2
    w = np.hypot(*(a.strip.left - a.strip.right).transpose(2, 0, 1))
    assert np.all((w >= 2.0 * 0.6 - 1e-9) & (w <= 2.0 * 1.4 + 1e-9))
    assert len(np.unique(np.round(w[:, 5], 9))) == 3  # per-stroke widths differ
    centre = 0.5 * (a.strip.left + a.strip.right)
    x, y, _, _ = centreline(fit, a.strip.t)
    off = np.hypot(centre[..., 0] - x, centre[..., 1] - y)
    assert 0.3 < off.max() <= 1.5 * 1.5 + 1e-9
    span = seg[:, 0, 1] - seg[:, 0, 0]
    moved = np.abs(a.strip.t[:, 0] - plain.strip.t[:, 0])
    assert np.all(moved <= 0.15 * span + 1e-12) and moved.max() > 0


def rect_strip(x0, x1, y0, y1):
    left = np.array([[[x0, y0], [x1, y0]]], dtype=float)
    right = np.array([[[x0, y1], [x1, y1]]], dtype=float)
    return StrokeStrip(left=left, right=right, t=np.array([[0.0, 1.0]]))


def strips_of(*strips):
    s = StrokeStrip(
        left=np.concatenate([a.left for a in strips]),
        right=np.concatenate([a.right for a in strips]),
        t=np.concatenate([a.t for a in strips]),
    )
    n = s.left.shape[0]
    return Strips(s, np.arange(n), np.arange(n), np.ones(n))


def test_rectangle_coverage_is_its_area_per_pixel():
    # edges on the 1/4 sub-sample lattice's midlines: coverage is exact
    alpha, pieces = rasterize_strips(strips_of(rect_strip(2.0, 9.5, 3.25, 5.5)), (10, 12), aa=4)
    ys, xs = np.mgrid[0:10, 0:12]
    ov_x = np.clip(np.minimum(xs + 1, 9.5) - np.maximum(xs, 2.0), 0, 1)
    ov_y = np.clip(np.minimum(ys + 1, 5.5) - np.maximum(ys, 3.25), 0, 1)
    np.testing.assert_allclose(alpha, ov_x * ov_y, atol=1e-12)
    assert alpha.sum() == pytest.approx(7.5 * 2.25)
    assert pieces.max() == 1 and pieces[alpha == 0].max() <= 1


def test_pieces_composite_over_each_other_and_samples_scale():
    a, _ = rasterize_strips(
        strips_of(rect_strip(1, 6, 1, 6), rect_strip(3, 8, 3, 8)), (10, 10), opacity=0.5
    )
    assert a[2, 2] == 0.5 and a[7, 7] == 0.5 and a[4, 4] == pytest.approx(0.75)
    # 2 x 2 samples per pixel: pixel coordinates scale by n
    b, _ = rasterize_strips(strips_of(rect_strip(1, 3, 1, 2)), (8, 8), n=2)
    assert b[2:4, 2:6].min() == 1.0 and b.sum() == 8.0


@pytest.mark.parametrize("aa", [1, 3, 4, 8])  # a kernel per aa (raster_strips_for)
def test_a_folded_strip_is_inked_once(aa):
    # a strip that doubles back over itself (hairpin); coverage is that of the union
    left = np.array([[[2.0, 2.0], [12.0, 2.0], [4.0, 2.5]]])
    right = np.array([[[2.0, 5.0], [12.0, 5.0], [4.0, 4.5]]])
    strip = StrokeStrip(left=left, right=right, t=np.array([[0.0, 0.5, 1.0]]))
    alpha, _ = rasterize_strips(strips_of(strip), (8, 16), aa=aa)
    # oracle: union of the four triangles at the same sub-sample points
    tris = []
    for i in range(2):
        tris += [
            (left[0, i], right[0, i], left[0, i + 1]),
            (right[0, i], right[0, i + 1], left[0, i + 1]),
        ]
    ys, xs = np.mgrid[0:8, 0:16]
    off = (np.arange(aa) + 0.5) / aa
    px = (xs[..., None, None] + off[None, None, None, :]).reshape(8, 16, -1)
    py = (ys[..., None, None] + off[None, None, :, None]).reshape(8, 16, -1)
    px, py = np.broadcast_arrays(px, py)
    inside = np.zeros(px.shape, bool)
    for a, b, c in tris:
        d = [(q[0] - p[0]) * (py - p[1]) - (q[1] - p[1]) * (px - p[0])
             for p, q in ((a, b), (b, c), (c, a))]  # fmt: skip
        inside |= (np.all([v >= 0 for v in d], 0)) | (np.all([v <= 0 for v in d], 0))
    np.testing.assert_allclose(alpha, inside.mean(-1), atol=1e-12)
    assert alpha.max() == 1.0


@pytest.mark.parametrize(
    ("aa", "err", "match"),
    [(0, ValueError, r"aa: expected an integer in \[1, 8\], got 0"),
     (9, ValueError, r"aa: expected an integer in \[1, 8\], got 9"),
     (4.0, TypeError, "aa: expected an integer, got float 4.0")],
)  # fmt: skip
def test_sub_samples_outside_one_to_eight_are_refused(aa, err, match):
    with pytest.raises(err, match=match):
        rasterize_strips(strips_of(rect_strip(1, 3, 1, 2)), (8, 8), aa=aa)


def test_brushes():
    for name in BRUSHES:
        tex, wrap = brush_texture(name)
        assert tex.ndim == 2 and tex.min() >= 0 and tex.max() <= 1 and tex.max() > 0.5
    assert brush_texture(None)[0].shape == (1, 1)
    tex, _ = brush_texture("checkerboard")  # any built-in texture: dark = ink
    assert tex.min() == pytest.approx(0.0, abs=0.01) and tex.max() == pytest.approx(1.0, abs=0.01)
    with pytest.raises(ValueError, match="brush: 'no-such-brush' is neither a built-in"):
        brush_texture("no-such-brush")
    # the brush modulates coverage along t and across
    s = strips_of(rect_strip(0, 40, 2, 6))
    solid, _ = rasterize_strips(s, (8, 40))
    dry, _ = rasterize_strips(s, (8, 40), brush="dry")
    assert np.all(dry <= solid + 1e-12) and dry[:, 35:].sum() < dry[:, :5].sum()
