"""Stroke metrics by stroke id: synthetic stroke ends on hand-projected surfaces, and TAMISS."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.coherence import (
    STROKE_CHANNELS,
    StrokeEnds,
    measure_strokes,
    stroke_ends,
    stroke_pair_metrics,
)
from refnpr.raster import rasterize
from refnpr.scenes import load_scene

from .fixtures import EYE, H, W, pixel_size, scene, wall


def gbuf(sc):
    return rasterize(sc, None, W, H, STROKE_CHANNELS, 1, dtype=np.float64)


def ends(ids, start, end):
    return StrokeEnds(np.asarray(ids), np.asarray(start, float), np.asarray(end, float))


START = [[10.3, 12.7], [40.1, 30.2], [61.9, 50.5]]
END = [[20.6, 12.9], [44.4, 38.0], [70.2, 51.1]]


def test_ends_that_move_with_the_surface_have_no_jitter():
    dx = 0.137
    prev_sc, now_sc = scene([wall(size=40.0)]), scene([wall(dx, size=40.0)])
    shift = dx / pixel_size(EYE[2])  # px, the wall is frontal at view distance 5
    prev = ends([3, 7, 9], START, END)
    now = ends([3, 7, 9], np.add(START, [shift, 0]), np.add(END, [shift, 0]))
    r = stroke_pair_metrics(now, prev, gbuf(prev_sc), now_sc, prev_sc)
    assert r.n_ends == 6 and r.appeared == 0 and r.vanished == 0 and r.n_strokes == 3
    assert r.jitter_max < 1e-9


def test_jitter_is_the_distance_from_the_true_motion_and_ids_are_matched():
    dx = 0.137
    prev_sc, now_sc = scene([wall(size=40.0)]), scene([wall(dx, size=40.0)])
    shift = dx / pixel_size(EYE[2])
    prev = ends([3, 7, 9], START, END)
    # stroke 3 is gone, stroke 11 is new; stroke 7 ends 0.3 px off in x and 0.4 px in y,
    # stroke 9 follows the surface exactly
    now = ends(
        [7, 9, 11],
        [
            [START[1][0] + shift + 0.3, START[1][1] + 0.4],
            [START[2][0] + shift, START[2][1]],
            [5, 5],
        ],
        [[END[1][0] + shift, END[1][1]], [END[2][0] + shift, END[2][1]], [6, 6]],
    )
    r = stroke_pair_metrics(now, prev, gbuf(prev_sc), now_sc, prev_sc, frame=4)
    assert (r.frame, r.appeared, r.vanished, r.n_ends, r.n_strokes) == (4, 1, 1, 4, 3)
    assert r.jitter_max == pytest.approx(0.5, abs=1e-9)
    assert r.jitter_mean == pytest.approx(0.5 / 4, abs=1e-9)


def test_ends_off_the_surface_are_not_measured():
    sc = scene([wall(size=2.0)])  # a small wall: most of the frame is background
    gb = gbuf(sc)
    assert (gb["mesh_id"] < 0).any()
    e = ends([1, 2], [[W / 2, H / 2], [1.0, 1.0]], [[W / 2 + 1, H / 2], [-5.0, 2.0]])
    r = stroke_pair_metrics(e, e, gb, sc, sc)
    assert r.n_ends == 2 and r.jitter_max < 1e-9  # the two on the wall, still


def test_no_common_strokes_gives_nan_jitter():
    sc = scene([wall()])
    r = stroke_pair_metrics(
        ends([1], [[5, 5]], [[6, 6]]), ends([2], [[5, 5]], [[6, 6]]), gbuf(sc), sc, sc
    )
    assert r.n_ends == 0 and math.isnan(r.jitter_mean) and r.as_dict()["jitter_mean"] is None


def test_stroke_ends_bad_input():
    with pytest.raises(ValueError, match=r"ids: expected a sorted 1-D array"):
        ends([3, 1], [[0, 0], [1, 1]], [[0, 0], [1, 1]])
    with pytest.raises(ValueError, match=r"start: expected shape \(2, 2\)"):
        ends([1, 3], [[0, 0]], [[0, 0], [1, 1]])
    with pytest.raises(TypeError, match=r"result: expected a TAMISS PipelineResult"):
        stroke_ends(object())
    sc = scene([wall()])
    with pytest.raises(ValueError, match=r"prev_gb: lacks channels"):
        e = ends([1], [[5, 5]], [[6, 6]])
        stroke_pair_metrics(e, e, rasterize(sc, None, W, H, ("depth",), 1), sc, sc)


@pytest.mark.parametrize("frames, tol", [(1, 1e-6), (4, 1e-4)])
def test_tamiss_still_frames_have_no_jitter_and_no_popping(frames, tol):
    """Per-frame fits: the same frame twice draws the same ends. Averaged (the default 4
    frames): the same sums carried by a zero motion, to the float32 fit's rounding."""
    sc = load_scene("tamiss_sphere")
    rows = measure_strokes([sc, sc], {"name": "tamiss", "average_frames": frames}, 96, 72)
    (r,) = rows
    assert r.n_strokes > 20 and r.n_ends > 20
    assert r.appeared == 0 and r.vanished == 0
    assert r.jitter_max < tol


def test_measure_with_strokes_reports_and_plots_them(tmp_path):
    from refnpr.coherence import measure

    sc = load_scene("tamiss_sphere")
    rep = measure([sc, sc, sc], "tamiss", 64, 48, strokes=True)
    assert [r.frame for r in rep.strokes] == [1, 2]
    # the default averages 4 frames: still frames carried by a zero motion, to float32 rounding
    assert all(r.jitter_max < 1e-4 and r.appeared == r.vanished == 0 for r in rep.strokes)
    assert rep.summary()["jitter_max"]["max"] < 1e-4
    assert len(rep.as_dict()["strokes"]) == 2
    assert rep.plot(tmp_path / "s.png").stat().st_size > 0


def test_stroke_metrics_follow_the_styles_state_across_frames():
    """measure_strokes / measure(strokes=True) thread TAMISS's run_frame state (here the
    aggregate history of average_frames=3): the same rows as threading it by hand, and not the
    rows of stateless runs."""
    from refnpr.coherence import measure
    from refnpr.coherence.strokes import frame_stroke_ends
    from refnpr.styles import get_style

    anim = load_scene("tamiss_knot_orbit")
    stills = [anim.at(f) for f in range(3)]
    w, h = 96, 72
    style = get_style("tamiss", average_frames=3, directions=["v"], period=4.0)
    rows = measure_strokes(stills, style, w, h)
    state, by_hand, prev = style.initial_state(), [], None
    for t, sc in enumerate(stills):
        e, gb, state = frame_stroke_ends(style, sc, w, h, state)
        if prev is not None:
            by_hand.append(stroke_pair_metrics(e, prev[0], prev[1], sc, prev[2], frame=t))
        prev = (e, gb, sc)
    assert [r.as_dict() for r in rows] == [r.as_dict() for r in by_hand]
    stateless = measure_strokes(
        stills, get_style("tamiss", directions=["v"], period=4.0, average_frames=1), w, h
    )
    assert [r.as_dict() for r in rows] != [r.as_dict() for r in stateless]
    report = measure(stills, style, w, h, strokes=True)
    assert [r.as_dict() for r in report.strokes] == [r.as_dict() for r in rows]
