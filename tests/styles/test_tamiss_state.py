"""TAMISS state across frames and the parameters of the jitter remedies.

Oracles: the pipeline's pre-existing explicit API (``run_pipeline(table=..., history=...)`` with
objects kept by hand), naive per-point evaluation of cubics, and the default style's frame 0.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import textwrap

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.formulas.tamiss import StrokeFit, StrokeHashTable
from refnpr.raster import rasterize
from refnpr.render import composite_resolve
from refnpr.scenes import load_scene
from refnpr.sequence import is_stateful, render_sequence
from refnpr.styles import ShadeContext, get_style, style_from_spec
from refnpr.styles.tamiss import (
    AggregateHistory,
    TamissStyle,
    aggregate_exact,
    aggregate_hashed,
    run_pipeline,
)
from refnpr.styles.tamiss.gather import field_inputs, gather_fragments
from refnpr.styles.tamiss.motion import stroke_anchors
from refnpr.styles.tamiss.state import StrokeCoefficients, TamissState, reexpress, smooth_fit

W, H = 96, 72
PEN = dict(
    directions=["v"],
    period=4.0,
    density=1.0,
    extent="overdraw",
    wobble=0.5,
    end_jitter=0.25,
    taper=0.3,
    width=1.3,
    brush="pen",
)


@pytest.fixture(scope="module")
def anim():
    return load_scene("tamiss_knot_orbit")


def _gb(style, scene, spp=1):
    return rasterize(
        scene, None, W, H, sorted(style.requires(scene)), spp, **style.raster_options(scene)
    )


def _ctx(style, scene, spp=1):
    return ShadeContext(_gb(style, scene, spp), scene)


def _frames(style, anim, n=3, spp=1):
    """Inks of frames 0..n-1 driven by hand through run_frame."""
    state = style.initial_state()
    out = []
    for f in range(n):
        result, state = style.run_frame(_ctx(style, anim.at(f), spp), state)
        out.append(result)
    return out


# -- state threading ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "extra",
    [{}, {"aggregation": "hashed"}, {"smooth": 0.5}, {"average_frames": 3}, {"gather_scale": 2}],
)
def test_a_still_is_frame_0(anim, extra):
    style = TamissStyle(**PEN, **extra)
    ctx = _ctx(style, anim.at(0))
    still = style.shade(ctx)
    frame0, _ = style.shade_frame(ctx, style.initial_state())
    np.testing.assert_array_equal(still, frame0)


def test_only_remedies_carry_state():
    assert TamissStyle(average_frames=1).initial_state() is None
    assert isinstance(TamissStyle().initial_state(), TamissState)  # average_frames=4 default
    for extra in ({"aggregation": "hashed"}, {"smooth": 0.2}, {"average_frames": 2}):
        assert isinstance(TamissStyle(**extra).initial_state(), TamissState)
    assert is_stateful(TamissStyle(smooth=0.2))
    assert is_stateful(get_style("contoured", base=TamissStyle(aggregation="hashed")))


def test_smoothing_averaging_and_hashing_leave_frame_0_as_today(anim):
    scene = anim.at(0)
    plain = TamissStyle(**PEN)
    ctx = _ctx(plain, scene)
    want = plain.shade(ctx)
    np.testing.assert_array_equal(TamissStyle(**PEN, smooth=0.6).shade(ctx), want)
    np.testing.assert_array_equal(TamissStyle(**PEN, average_frames=4).shade(ctx), want)
    # hashed still: a fresh table warmed up inside the pipeline, exactly as run_pipeline does
    hashed = TamissStyle(**PEN, aggregation="hashed")
    ref = run_pipeline(ctx.gb, scene, hashed.pipeline_params)
    np.testing.assert_array_equal(hashed.run(ctx).ink, ref.ink)


def test_hashed_sequence_equals_a_table_kept_by_hand(anim):
    style = TamissStyle(
        **PEN, aggregation="hashed", table_size=4096, warmup_frames=2, average_frames=1
    )
    p = style.pipeline_params
    got = _frames(style, anim, 3)
    table = StrokeHashTable(p.table_size, max_probes=p.max_probes)
    for f in range(3):
        scene = anim.at(f)
        gb = _gb(style, scene)
        if f == 0:  # the warm-up run_pipeline makes for a fresh table, done by hand
            frags = gather_fragments(field_inputs(gb, scene), p.field, gather_width=p.gather_width)
            for _ in range(p.warmup_frames):
                aggregate_hashed(frags, table)
        ref = run_pipeline(gb, scene, p, table=table)
        np.testing.assert_array_equal(got[f].ink, ref.ink)
        np.testing.assert_array_equal(got[f].stroke_ids, ref.stroke_ids)
        assert got[f].aggregates.hash_stats.as_dict() == ref.aggregates.hash_stats.as_dict()


@pytest.mark.parametrize("motion", ["none", "exact"])
@pytest.mark.parametrize("aggregation", ["exact", "hashed"])
def test_average_frames_equals_a_history_kept_by_hand(anim, aggregation, motion):
    style = TamissStyle(
        **PEN, average_frames=3, average_motion=motion, aggregation=aggregation, table_size=4096
    )
    got = _frames(style, anim, 4)
    p = style.pipeline_params
    plain = TamissStyle(**PEN, aggregation=aggregation, table_size=4096).pipeline_params
    window, anchors = [], []
    table = None
    for f in range(4):
        scene = anim.at(f)
        gb = _gb(style, scene)
        if f == 0:  # frame 0 is the still (an average of one frame) and starts the history
            ref = run_pipeline(gb, scene, plain)
            np.testing.assert_array_equal(got[0].ink, ref.ink)
            table = ref.table
            if aggregation == "hashed":  # the same routing again, into a throwaway table
                again = StrokeHashTable(p.table_size, max_probes=p.max_probes)
                frags = ref.fragments
                for _ in range(p.warmup_frames + 1):
                    agg0 = aggregate_hashed(frags, again, dtype=np.float64)
            else:
                agg0 = aggregate_exact(ref.fragments, dtype=np.float64)
            window.append(agg0)
            anchors.append(stroke_anchors(agg0, gb, scene))
            continue
        moving = {"anchors": anchors, "scene": scene, "size": (W, H)} if motion == "exact" else {}
        history = AggregateHistory(3, window=window, **moving)
        ref = run_pipeline(gb, scene, p, history=history, table=table)
        np.testing.assert_array_equal(got[f].ink, ref.ink)
        window = list(history.window[-2:])
        anchors = (anchors + [stroke_anchors(history.window[-1], gb, scene)])[-2:]


@pytest.mark.parametrize(
    "extra", [{"aggregation": "hashed"}, {"smooth": 0.5}, {"average_frames": 2}]
)
def test_a_state_reused_twice_gives_the_same_frame_twice(anim, extra):
    style = TamissStyle(**PEN, **extra)
    _, s1 = style.shade_frame(_ctx(style, anim.at(0)), style.initial_state())
    read = s1.table.read_table if s1.table is not None else None
    window = [a.moments.copy() for a in s1.window]
    ctx1 = _ctx(style, anim.at(1))
    a, s2a = style.shade_frame(ctx1, s1)
    b, s2b = style.shade_frame(ctx1, s1)
    np.testing.assert_array_equal(a, b)
    assert s2a is not s1 and s2b is not s1 and s1.frame == 1 and s2a.frame == 2
    if read is not None:
        np.testing.assert_array_equal(s1.table.read_table, read)  # not routed behind our back
        assert s2a.table is not s1.table
    for before, after in zip(window, s1.window, strict=True):
        np.testing.assert_array_equal(before, after.moments)
    # and the third frame is the same from either copy of the second state
    ctx2 = _ctx(style, anim.at(2))
    np.testing.assert_array_equal(style.shade_frame(ctx2, s2a)[0], style.shade_frame(ctx2, s2b)[0])


def test_smoothing_changes_later_frames_only(anim):
    plain = _frames(TamissStyle(**PEN), anim, 3)
    smooth = _frames(TamissStyle(**PEN, smooth=0.5), anim, 3)
    np.testing.assert_array_equal(plain[0].ink, smooth[0].ink)
    assert not np.array_equal(plain[2].ink, smooth[2].ink)


def test_render_sequence_equals_shade_frame_by_hand(anim, tmp_path):
    spec = {"name": "tamiss", **PEN, "smooth": 0.5, "aggregation": "hashed", "table_size": 4096}
    res = render_sequence(anim, spec, W, H, 1, out_dir=tmp_path, frames="0:3")
    assert res.stateful and res.rendered == [0, 1, 2]
    style = style_from_spec(spec)
    state = style.initial_state()
    for f in range(3):
        scene = anim.at(f)
        gb = _gb(style, scene)
        rgba, state = style.shade_frame(ShadeContext(gb, scene), state)
        px = composite_resolve(np.asarray(rgba, np.float32), gb.n, scene.background)
        from refnpr.image import Image

        want = Image(px).to_srgb8()
        got = iio.imread(tmp_path / f"frame_{f:05d}.png")
        np.testing.assert_array_equal(got, want)


# -- coefficient smoothing against a naive oracle ----------------------------------------------


def _naive_eval(c, lo, hi, t):
    """sum_m c_m s^m with s = (t - centre) / half-width (0 for an empty range), point by point."""
    out = np.empty(t.shape)
    for i in range(t.shape[0]):
        half = 0.5 * (hi[i] - lo[i])
        for k in range(t.shape[1]):
            s = (t[i, k] - 0.5 * (lo[i] + hi[i])) / half if half > 0 else 0.0
            out[i, k] = sum(c[i, m] * s**m for m in range(4))
    return out


def _random_fit(rng, S, dtype=np.float64):
    lo = rng.uniform(0.0, 0.4, S)
    hi = lo + rng.uniform(0.1, 0.6, S)
    c = [rng.normal(size=(S, 4)) * [50.0, 10.0, 2.0, 1.0] for _ in range(3)]
    return StrokeFit(
        c[0].astype(dtype), c[1].astype(dtype), c[2].astype(dtype),
        lo.astype(dtype), hi.astype(dtype), np.full(S, 10.0, dtype),
    )  # fmt: skip


def test_reexpress_matches_naive_evaluation():
    rng = np.random.default_rng(3)
    S = 20
    c = rng.normal(size=(S, 4))
    lo, hi = rng.uniform(0, 0.5, S), rng.uniform(0.5, 1.0, S)
    lo2, hi2 = lo + rng.normal(0, 0.05, S), hi + rng.normal(0, 0.05, S)
    c2 = reexpress(c, lo, hi, lo2, hi2)
    t = lo2[:, None] + (hi2 - lo2)[:, None] * rng.uniform(-0.2, 1.2, (S, 7))
    np.testing.assert_allclose(
        _naive_eval(c2, lo2, hi2, t), _naive_eval(c, lo, hi, t), rtol=1e-10, atol=1e-10
    )
    # a degenerate old range is the constant c_0
    lo[0] = hi[0] = 0.3
    c2 = reexpress(c, lo, hi, lo2, hi2)
    np.testing.assert_allclose(c2[0], [c[0, 0], 0, 0, 0])


@pytest.mark.parametrize("w", [0.2, 0.5, 0.9])
def test_smooth_fit_is_the_blend_of_the_two_curves(w):
    rng = np.random.default_rng(7)
    S = 12
    cur, prev = _random_fit(rng, S), _random_fit(rng, S)
    ids = np.arange(100, 100 + S, dtype=np.int64)
    prev_ids = ids.copy()
    prev_ids[::3] += 1000  # every third stroke is new this frame
    order = np.argsort(prev_ids)
    memory = StrokeCoefficients.from_fit(
        prev_ids[order],
        StrokeFit(
            prev.c_x[order], prev.c_y[order], prev.c_v[order], prev.t_min[order],
            prev.t_max[order], prev.count[order],
        ),
    )  # fmt: skip
    out = smooth_fit(cur, ids, memory, w)
    t = cur.t_min[:, None] + (cur.t_max - cur.t_min)[:, None] * rng.uniform(0, 1, (S, 5))
    new = np.zeros(S, dtype=bool)
    new[::3] = True
    for name in ("c_x", "c_y", "c_v"):
        a = getattr(cur, name)
        b = getattr(prev, name)
        want = (1 - w) * _naive_eval(a, cur.t_min, cur.t_max, t) + w * _naive_eval(
            b, prev.t_min, prev.t_max, t
        )
        want[new] = _naive_eval(a, cur.t_min, cur.t_max, t)[new]  # new strokes start fresh
        got = _naive_eval(getattr(out, name), out.t_min, out.t_max, t)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(out.t_min, cur.t_min)


def test_smooth_fit_keeps_dtype_and_skips_non_finite():
    rng = np.random.default_rng(1)
    cur, prev = _random_fit(rng, 4, np.float32), _random_fit(rng, 4)
    cx = cur.c_x.copy()
    cx[1, 2] = np.nan
    from dataclasses import replace

    cur = replace(cur, c_x=cx)
    ids = np.arange(4, dtype=np.int64)
    out = smooth_fit(cur, ids, StrokeCoefficients.from_fit(ids, prev), 0.5)
    assert out.c_x.dtype == np.float32
    np.testing.assert_array_equal(out.c_x[1], cur.c_x[1])
    assert not np.array_equal(out.c_x[0], cur.c_x[0])
    assert smooth_fit(cur, ids, None, 0.5) is cur


# -- gather_scale ------------------------------------------------------------------------------


def test_gather_scale_gathers_what_that_many_spp_would(anim):
    scene = anim.at(0)
    fine = TamissStyle(**PEN, gather_scale=2).run(_ctx(TamissStyle(**PEN), scene, spp=1))
    ref = TamissStyle(**PEN).run(_ctx(TamissStyle(**PEN), scene, spp=4))
    for name in ("x", "y", "t", "id"):
        np.testing.assert_array_equal(getattr(fine.fragments, name), getattr(ref.fragments, name))
    np.testing.assert_array_equal(fine.aggregates.moments, ref.aggregates.moments)
    assert fine.ink.shape == (H, W) and fine.n == 1 and fine.inputs.n == 2
    # the same gather grid as the G-buffer: exactly the default
    same = TamissStyle(**PEN, gather_scale=2).run(_ctx(TamissStyle(**PEN), scene, spp=4))
    np.testing.assert_array_equal(same.ink, ref.ink)


@pytest.mark.parametrize("show", ["ids", "fits", "strokes", "levels"])
def test_gather_scale_views_are_on_the_output_grid(anim, show):
    style = TamissStyle(**PEN, gather_scale=3, show=show)
    out = style.shade(_ctx(style, anim.at(0)))
    assert out.shape == (H, W, 4) and np.any(out[..., 3] > 0)


# -- parameter errors --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, err, match",
    [
        ({"smooth": 1.0}, ValueError, r"smooth: .*\[0, 1\)"),
        ({"smooth": -0.1}, ValueError, "smooth"),
        ({"smooth": "a"}, TypeError, "smooth"),
        ({"gather_scale": 0}, ValueError, "gather_scale"),
        ({"gather_scale": 2.5}, (TypeError, ValueError), "gather_scale"),
        ({"gather_scale": 64}, ValueError, "gather_scale"),
        ({"average_frames": 0}, ValueError, "average_frames"),
        ({"average_frames": True}, (TypeError, ValueError), "average_frames"),
        ({"average_motion": "flow"}, ValueError, "average_motion"),
    ],
)
def test_remedy_parameter_errors(kwargs, err, match):
    with pytest.raises(err, match=match):
        TamissStyle(**kwargs)


def test_state_errors(anim):
    style = TamissStyle(aggregation="hashed", table_size=1024)
    ctx = _ctx(style, anim.at(0))
    with pytest.raises(TypeError, match="state: expected a TamissState"):
        style.shade_frame(ctx, {"table": None})
    other = TamissState(table=StrokeHashTable(2048))
    with pytest.raises(ValueError, match="table_size=1024"):
        style.shade_frame(ctx, other)


def test_remedies_round_trip_through_params():
    style = TamissStyle(gather_scale=3, average_frames=2, average_motion="none", smooth=0.25)
    again = get_style("tamiss", **{k: v for k, v in style.params().items() if k != "base"})
    assert again.pipeline_params == style.pipeline_params


# -- thread-count determinism of a sequence ----------------------------------------------------

_SCRIPT = textwrap.dedent(
    """
    import hashlib, numpy as np
    from refnpr.raster import rasterize
    from refnpr.scenes import load_scene
    from refnpr.styles import ShadeContext
    from refnpr.styles.tamiss import TamissStyle
    anim = load_scene("tamiss_knot_orbit")
    style = TamissStyle(directions=["v"], aggregation="hashed", table_size=4096, smooth=0.5,
                        average_frames=2, gather_scale=2)
    state = style.initial_state()
    h = hashlib.sha256()
    for f in range(3):
        scene = anim.at(f)
        gb = rasterize(scene, None, 96, 72, sorted(style.requires(scene)), 1,
                       **style.raster_options(scene))
        rgba, state = style.shade_frame(ShadeContext(gb, scene), state)
        h.update(np.ascontiguousarray(rgba).tobytes())
    print(h.hexdigest())
    """
)


def test_sequence_is_bit_identical_for_any_thread_count():
    digests = []
    for threads in ("1", "2"):
        env = dict(os.environ, NUMBA_NUM_THREADS=threads)
        out = subprocess.run(
            [sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True, check=True
        )
        digests.append(out.stdout.strip().splitlines()[-1])
    assert digests[0] == digests[1]
    assert len(digests[0]) == len(hashlib.sha256().hexdigest())
