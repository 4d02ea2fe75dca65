"""The coherence floor of stroke images: strips carried exactly by the surface motion.

Oracles: a frontal wall moved by a whole number of pixels (the hand projection of the fixtures:
every vertex moves by exactly that, the ink by exactly that many columns), the backward motion
field of ``motion_field`` (a different route through frame t's own G-buffer), and a still pair.
"""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.coherence import (
    MOTION_CHANNELS,
    STROKE_CHANNELS,
    carry_strips,
    ink_floor,
    ink_image,
    motion_field,
)
from refnpr.formulas.tamiss import StrokeStrip
from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext
from refnpr.styles.tamiss import TamissStyle
from refnpr.styles.tamiss.raster import rasterize_strips
from refnpr.styles.tamiss.strokes import Strips

from .fixtures import EYE, H, W, pixel_size, scene, wall


def _strips(centres, half_length=6.0, half_width=0.8, k=9):
    """Horizontal strips of ``k`` vertex pairs around each centre (pixels)."""
    c = np.asarray(centres, np.float64)
    xs = np.linspace(-half_length, half_length, k)
    mid = np.stack([c[:, None, 0] + xs, np.broadcast_to(c[:, None, 1], (len(c), k))], -1)
    left = mid - [0.0, half_width]
    right = mid + [0.0, half_width]
    t = np.broadcast_to(np.linspace(0, 1, k), (len(c), k)).copy()
    p = len(c)
    return Strips(
        StrokeStrip(left, right, t), np.arange(p), np.arange(p) + 100, np.full(p, 2 * half_width)
    )


def test_strips_on_a_wall_moved_by_whole_pixels_move_by_exactly_that():
    shift = 3
    dx = shift * pixel_size(EYE[2])  # world units of 3 px on the frontal wall at distance 5
    before, after = scene([wall(size=40.0)]), scene([wall(dx, size=40.0)])
    prev_gb = rasterize(before, None, W, H, STROKE_CHANNELS, 1, dtype=np.float64)
    strips = _strips([[20.137, 15.29], [41.61, 33.77], [55.05, 48.4]])
    moved = carry_strips(strips, prev_gb, after, before)
    for a, b in ((strips.strip.left, moved.strip.left), (strips.strip.right, moved.strip.right)):
        np.testing.assert_allclose(b - a, np.broadcast_to([shift, 0.0], a.shape), atol=1e-9)
    np.testing.assert_array_equal(moved.ids, strips.ids)
    ink, _ = rasterize_strips(strips, (H, W), 1)
    ink2, _ = rasterize_strips(moved, (H, W), 1)
    assert ink.sum() > 50
    np.testing.assert_allclose(ink2[:, shift:], ink[:, :-shift], atol=1e-12)


def test_vertices_off_the_surface_move_with_their_strip():
    shift = 2
    dx = shift * pixel_size(EYE[2])
    small = 40 * pixel_size(EYE[2])  # a wall 40 px wide, centred: x in [20, 60]
    before, after = scene([wall(size=small)]), scene([wall(dx, size=small)])
    prev_gb = rasterize(before, None, W, H, STROKE_CHANNELS, 1, dtype=np.float64)
    strips = _strips([[58.3, 30.4], [10.2, 30.4]])  # runs past the right edge; wholly off
    moved = carry_strips(strips, prev_gb, after, before)
    d = moved.strip.left - strips.strip.left
    np.testing.assert_allclose(d[0], np.broadcast_to([shift, 0.0], d[0].shape), atol=1e-9)
    np.testing.assert_array_equal(d[1], 0.0)  # no vertex on the surface: stays


@pytest.fixture(scope="module")
def knot_pair():
    anim = load_scene("tamiss_knot_orbit")
    style = TamissStyle(directions=["v"])
    w, h = 160, 120
    out = []
    for f in (0, 1):
        sc = anim.at(f)
        gb = rasterize(sc, None, w, h, sorted(style.requires(sc)), 4, **style.raster_options(sc))
        result, _ = style.run_frame(ShadeContext(gb, sc), None)
        sgb = rasterize(sc, None, w, h, STROKE_CHANNELS, 1, dtype=np.float64)
        mgb = rasterize(sc, None, w, h, MOTION_CHANNELS, 1, dtype=np.float64)
        out.append((sc, result, sgb, mgb))
    return out


def test_carried_vertices_agree_with_the_backward_motion_field(knot_pair):
    (sc0, r0, sgb0, mgb0), (sc1, _, _, mgb1) = knot_pair
    field = motion_field(mgb1, mgb0, sc1, sc0)
    moved = carry_strips(r0.strips, sgb0, sc1, sc0)
    q = np.asarray(moved.strip.left).reshape(-1, 2)
    p = np.asarray(r0.strips.strip.left).reshape(-1, 2)
    col, row = np.floor(q[:, 0]).astype(int), np.floor(q[:, 1]).astype(int)
    inside = (col >= 1) & (col < 159) & (row >= 1) & (row < 119)
    col, row = np.clip(col, 0, 159), np.clip(row, 0, 119)
    # interior of the surface: the 3 x 3 pixels around are valid in the motion field
    ok = inside.copy()
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            ok &= field.valid[np.clip(row + dr, 0, 119), np.clip(col + dc, 0, 159)]
    centre = np.stack([col + 0.5, row + 0.5], -1)
    predicted = field.xy[row, col] + (q - centre)  # the motion is a translation over a pixel
    err = np.hypot(*(predicted - p)[ok].T)
    motion = np.hypot(*(q - p)[ok].T)
    assert ok.sum() > 1000 and np.median(motion) > 0.1
    assert np.median(err) < 0.01 and np.percentile(err, 90) < 0.03, np.percentile(err, [50, 90])


def test_ink_floor_lies_between_zero_and_the_actual_ratio(knot_pair):
    (sc0, r0, sgb0, mgb0), (sc1, r1, _, mgb1) = knot_pair
    field = motion_field(mgb1, mgb0, sc1, sc0)
    got = ink_floor(r0, r1, sgb0, sc1, sc0, field, frame=1)
    assert got.frame == 1
    assert 0.2 < got.floor.ratio < got.actual.ratio < 1.0
    assert got.excess == pytest.approx(got.actual.ratio - got.floor.ratio)
    assert set(got.as_dict()) == {"frame", "actual", "floor", "excess"}


def test_a_still_pair_has_a_zero_floor(knot_pair):
    (sc0, r0, sgb0, mgb0), _ = knot_pair
    field = motion_field(mgb0, mgb0, sc0, sc0)
    got = ink_floor(r0, r0, sgb0, sc0, sc0, field)
    assert got.actual.warp_error == 0.0
    assert got.floor.warp_error < 1e-12  # the carried vertices: to rounding


def test_floor_errors(knot_pair):
    (sc0, r0, sgb0, mgb0), _ = knot_pair
    field = motion_field(mgb0, mgb0, sc0, sc0)
    with pytest.raises(TypeError, match="prev_result: expected a TAMISS PipelineResult"):
        ink_floor(object(), r0, sgb0, sc0, sc0, field)
    with pytest.raises(ValueError, match=r"ink: expected an \(nH, nW\) coverage grid"):
        ink_image(np.zeros((5, 6)), 2)
    bad = rasterize(sc0, None, 160, 120, ["mesh_id"], 1)
    with pytest.raises(ValueError, match="position"):
        carry_strips(r0.strips, bad, sc0, sc0)
