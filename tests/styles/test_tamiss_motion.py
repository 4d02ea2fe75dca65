"""Motion-compensated averaging of TAMISS aggregates (``average_motion="exact"``).

Oracles: each fragment's own world position (from the G-buffer) carried by the objects'
transforms and projected through the new camera, summed again (for the per-stroke affine
transport); the frame's own un-averaged sums (for the absence of lag); plain averaging on a
still sequence (where there is no motion to compensate).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from refnpr.coherence import MOTION_CHANNELS as FLOW
from refnpr.coherence import motion_field
from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext
from refnpr.styles.tamiss import TamissStyle, aggregate_exact
from refnpr.styles.tamiss.aggregate import recentre
from refnpr.styles.tamiss.gather import Fragments
from refnpr.styles.tamiss.motion import MOTION_CHANNELS, stroke_anchors, transport

W, H = 160, 120


@pytest.fixture(scope="module")
def anim():
    return load_scene("tamiss_knot_orbit")


def _gb(scene, spp=1, channels=()):
    chans = sorted(MOTION_CHANNELS | {"tri_id"} | set(channels))
    return rasterize(scene, None, W, H, chans, spp, dtype=np.float64)


def _project(scene, p):
    vp = scene.camera.view_projection(W, H)
    clip = p @ vp[:, :3].T + vp[:, 3]
    return np.stack(
        [(clip[:, 0] / clip[:, 3] + 1) * 0.5 * W, (1 - clip[:, 1] / clip[:, 3]) * 0.5 * H], -1
    )


def _patch_fragments(gb, centres, radius=2):
    """Fragments on the samples within ``radius`` px of each centre (one stroke id per centre,
    t along x) on the same sheet of surface as the centre (not a fold of the knot behind or in
    front of it), with their world positions."""
    mesh = np.asarray(gb["mesh_id"])
    pos = np.asarray(gb["position"])
    step = np.linalg.norm(np.asarray(gb["dposition_dx"]), axis=-1)
    xs, ys, ts, ids, world = [], [], [], [], []
    for k, (cx, cy) in enumerate(centres):
        obj = mesh[int(cy), int(cx)]
        for r in range(int(cy) - radius, int(cy) + radius + 1):
            for c in range(int(cx) - radius, int(cx) + radius + 1):
                far = np.linalg.norm(pos[r, c] - pos[int(cy), int(cx)])
                if mesh[r, c] != obj or far > 2.0 * radius * step[int(cy), int(cx)]:
                    continue
                xs.append(c + 0.5)
                ys.append(r + 0.5)
                ts.append(0.3 + 0.05 * (c - cx))
                ids.append(k)
                world.append(pos[r, c])
    n = len(xs)
    frags = Fragments(
        sample=np.zeros(n, np.int64),
        x=np.array(xs),
        y=np.array(ys),
        t=np.array(ts),
        id=np.array(ids, np.int64),
        layer=np.zeros(n, np.int8),
        level=np.zeros(n, np.int8),
        shape=(H, W),
        n_axis=1,
    )
    return frags, np.array(world)


def test_transport_matches_each_fragment_carried_exactly(anim):
    """The affine transport of a stroke's sums equals the sums of its fragments each carried
    by the exact motion (world point -> new camera), to second order in the stroke's size."""
    a, b = anim.at(0), anim.at(8)  # 5 degrees of orbit: a few pixels of motion
    gb = _gb(a)
    mesh = np.asarray(gb["mesh_id"])
    rows, cols = np.nonzero(mesh[4:-4, 4:-4] >= 0)
    pick = np.linspace(0, rows.size - 1, 40).astype(int)
    centres = np.stack([cols[pick] + 4.5, rows[pick] + 4.5], -1)
    frags, world = _patch_fragments(gb, centres)
    agg = aggregate_exact(frags, dtype=np.float64)
    anchors = stroke_anchors(agg, gb, a)
    moved, ok = transport(agg, anchors, b, W, H)
    assert ok.mean() > 0.9
    # the oracle: the same fragments at their exactly re-projected positions (the camera moves,
    # the object does not, so world points stay)
    xy = _project(b, world)
    exact = aggregate_exact(replace(frags, x=xy[:, 0], y=xy[:, 1]), dtype=np.float64)
    np.testing.assert_array_equal(exact.stroke_ids, moved.stroke_ids)
    back = recentre(
        moved.moments, moved.t_min, moved.t_max, moved.origin,
        exact.t_min, exact.t_max, exact.origin,
    )  # fmt: skip
    motion = np.abs(moved.origin - agg.origin).max()
    assert motion > 1.0  # the test moves strokes by more than a pixel
    m = np.asarray(exact.moments)
    count = m[:, :1]
    err = np.abs(back[ok, 7:] - m[ok, 7:]).max(1) / count[ok, 0]  # mean error per fragment, px
    # second order in the patch's size (+-2 px on a curved tube, seen in perspective): a few
    # hundredths of a pixel where the strokes moved 1-4 px; not moving them errs by the motion
    assert err.max() < 0.1 and np.median(err) < 0.03, err
    still = recentre(
        agg.moments, agg.t_min, agg.t_max, agg.origin, exact.t_min, exact.t_max, exact.origin
    )
    assert np.median(np.abs(still[:, 7:] - m[:, 7:]).max(1) / count[:, 0]) > 20 * np.median(err)
    np.testing.assert_array_equal(back[:, :7], m[:, :7])  # powers of s do not move


def test_transport_follows_moving_objects(anim):
    """An object's own transform moves its strokes (not only the camera)."""
    a = anim.at(0)
    obj = a.objects[0]
    shift = np.eye(4)
    shift[:3, 3] = 0.05 * a.camera.view_matrix()[0, :3]  # along the camera's right
    b = replace(a, objects=(replace(obj, transform=shift @ np.asarray(obj.transform)),))
    gb = _gb(a)
    mesh = np.asarray(gb["mesh_id"])
    rows, cols = np.nonzero(mesh[4:-4, 4:-4] >= 0)
    pick = np.linspace(0, rows.size - 1, 20).astype(int)
    frags, world = _patch_fragments(gb, np.stack([cols[pick] + 4.5, rows[pick] + 4.5], -1))
    agg = aggregate_exact(frags, dtype=np.float64)
    moved, ok = transport(agg, stroke_anchors(agg, gb, a), b, W, H)
    xy = _project(b, world + shift[:3, 3])
    exact = aggregate_exact(replace(frags, x=xy[:, 0], y=xy[:, 1]), dtype=np.float64)
    c_exact = exact.origin + exact.moments[:, [7, 11]] / exact.moments[:, :1]
    c_moved = moved.origin + moved.moments[:, [7, 11]] / moved.moments[:, :1]
    assert ok.all()
    assert np.abs(c_moved - c_exact).max() < 0.01
    c_then = agg.origin + agg.moments[:, [7, 11]] / agg.moments[:, :1]
    assert np.hypot(*(c_exact - c_then).T).min() > 0.3  # every stroke moved


def _centroids(agg):
    m = np.asarray(agg.moments)
    return np.asarray(agg.origin) + m[:, [7, 11]] / np.maximum(m[:, :1], 1)


def _lag(anim, motion, step=8, frames=5):
    """Median lag, in pixels along each stroke's motion, of the averaged sums' centroids behind
    the frame's own (positive: behind), and the median motion per frame."""
    style = TamissStyle(directions=["v"], average_frames=4, average_motion=motion)
    state = style.initial_state()
    prev = None
    for f in range(frames):
        scene = anim.at(step * f)
        gb = rasterize(
            scene, None, W, H, sorted(style.requires(scene)), 1, **style.raster_options(scene)
        )
        result, state = style.run_frame(ShadeContext(gb, scene), state)
        flow_gb = rasterize(scene, None, W, H, FLOW, 1, dtype=np.float64)
        if prev is not None:
            field = motion_field(flow_gb, prev[0], scene, prev[1])
        prev = (flow_gb, scene)
    raw = aggregate_exact(result.fragments, dtype=np.float64)
    raw = raw.take(np.isin(raw.stroke_ids, result.stroke_ids))
    c_raw = _centroids(raw)
    col = np.clip(c_raw[:, 0].astype(int), 0, W - 1)
    row = np.clip(c_raw[:, 1].astype(int), 0, H - 1)
    ok = field.valid[row, col]
    v = np.stack([col + 0.5, row + 0.5], -1) - field.xy[row, col]  # this frame's motion, px
    speed = np.hypot(*v.T)
    ok &= speed > 0.1
    u = v[ok] / speed[ok, None]
    behind = -np.einsum("ki,ki->k", _centroids(result.aggregates)[ok] - c_raw[ok], u)
    return float(np.median(behind)), float(np.median(speed[ok]))


def test_exact_averaging_does_not_lag(anim):
    """Averaged over 4 frames, the plain average sits about 1.5 frames of motion behind the
    frame's own strokes; the motion-compensated one does not lag."""
    plain, speed = _lag(anim, "none")
    moved, _ = _lag(anim, "exact")
    assert speed > 0.7  # px a frame
    assert plain > 1.0 * speed, (plain, speed)
    assert abs(moved) < 0.1 * plain, (moved, plain)


def test_a_still_sequence_averages_the_same_either_way(anim):
    scene = anim.at(0)
    out = {}
    for motion in ("none", "exact"):
        style = TamissStyle(directions=["v"], average_frames=3, average_motion=motion)
        state = style.initial_state()
        gb = rasterize(
            scene, None, W, H, sorted(style.requires(scene)), 1, **style.raster_options(scene)
        )
        for _ in range(3):
            result, state = style.run_frame(ShadeContext(gb, scene), state)
        out[motion] = result.aggregates
    np.testing.assert_array_equal(out["none"].stroke_ids, out["exact"].stroke_ids)
    np.testing.assert_allclose(out["exact"].moments, out["none"].moments, rtol=0, atol=1e-6)
    np.testing.assert_allclose(out["exact"].origin, out["none"].origin, rtol=0, atol=1e-9)


def test_motion_channels_are_required_only_when_used(anim):
    scene = anim.at(0)
    assert MOTION_CHANNELS <= TamissStyle(average_frames=2).requires(scene)
    flat = TamissStyle(derivatives="flat", constant_tone=0.5, average_frames=1)
    assert not (MOTION_CHANNELS - {"mesh_id"}) & flat.requires(scene)
    assert MOTION_CHANNELS <= TamissStyle(
        derivatives="flat", constant_tone=0.5, average_frames=2
    ).requires(scene)
    assert not (MOTION_CHANNELS - {"mesh_id"}) & TamissStyle(
        derivatives="flat", constant_tone=0.5, average_frames=2, average_motion="none"
    ).requires(scene)


def test_anchor_errors(anim):
    scene = anim.at(0)
    gb = rasterize(scene, None, W, H, ["uv", "tri_id", "mesh_id"], 1)
    agg = aggregate_exact(_patch_fragments(_gb(scene), [(80.5, 60.5)])[0])
    with pytest.raises(ValueError, match=r"dposition_dx.*lacks"):
        stroke_anchors(agg, gb, scene)
    anchors = stroke_anchors(agg.astype(np.float64), _gb(scene), scene)
    other = replace(agg.astype(np.float64), stroke_ids=agg.stroke_ids + 1)
    with pytest.raises(ValueError, match="stroke ids differ"):
        transport(other, anchors, scene, W, H)


def test_history_keeps_the_last_frames_and_their_anchors_aligned(anim):
    """A window longer than ``frames`` (average_frames lowered mid-sequence) keeps the last
    entries with their anchors; a mismatched count is refused."""
    from refnpr.styles.tamiss import AggregateHistory

    scene, now = anim.at(0), anim.at(4)
    gb = _gb(scene)
    entries = []
    for c in [(60.5, 50.5), (70.5, 55.5), (80.5, 60.5)]:
        agg = aggregate_exact(_patch_fragments(gb, [c])[0], dtype=np.float64)
        entries.append((agg, stroke_anchors(agg, gb, scene)))
    window = [a for a, _ in entries]
    anchors = [b for _, b in entries]
    current = aggregate_exact(_patch_fragments(_gb(now), [(75.5, 58.5)])[0], dtype=np.float64)
    long = AggregateHistory(2, window=window, anchors=anchors, scene=now, size=(W, H))
    short = AggregateHistory(2, window=window[-1:], anchors=anchors[-1:], scene=now, size=(W, H))
    assert len(long.window) == 2
    a, b = long.push(current), short.push(current)
    np.testing.assert_array_equal(a.moments, b.moments)
    np.testing.assert_array_equal(a.origin, b.origin)
    with pytest.raises(ValueError, match="anchors: expected one per window entry"):
        AggregateHistory(2, window=window, anchors=anchors[:2], scene=now, size=(W, H))
    with pytest.raises(ValueError, match="give the current frame's scene and size"):
        AggregateHistory(2, window=window, anchors=anchors)
    with pytest.raises(ValueError, match="make a new AggregateHistory for each frame"):
        long.push(current)  # its window was moved to `now` once; a second frame needs its own
