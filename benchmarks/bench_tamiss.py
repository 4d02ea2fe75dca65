"""TAMISS benchmark: per-phase times at the paper's Table 1 settings, and stroke jitter.

Usage::

    python benchmarks/bench_tamiss.py                       # full run, writes results/tamiss.json
    python benchmarks/bench_tamiss.py --quick --json /tmp/t.json   # smoke run, seconds

Sections (``--sections``, comma separated; default phases,hash,jitter; ``options`` on request)::

    python benchmarks/bench_tamiss.py --sections options          # the jitter remedies
    python benchmarks/bench_tamiss.py --sections options --quick  # smoke run

``phases``
    The ``tamiss_torus_knot`` scene at 1920 x 1200 (the paper's Table 1 resolution), one G-buffer
    (float64, spp 1), hatching along v with the row period chosen so that about 1k, 4k and 16k
    strokes are aggregated (the paper's stroke counts; the period is found by a secant search on
    log(count) vs log(period) and reported). For each: median over ``--runs`` of the wall time of
    each phase of ``run_pipeline`` -- gather (G-buffer channels to per-sample inputs, including
    the diffuse tone, plus the two-pass numba fragment kernel), aggregate (exact, float32), fit
    (four CG iterations, float32, drop rule), extrude (segments and strips) and raster
    (anti-aliased strips, 4 x 4 sub-samples) -- and the fit's share of the total. Then the same
    rows beside the paper's Table 1 (``PAPER_TABLE1``, GPU milliseconds: OLS against gather +
    aggregate, CGM against fit, E&R against extrude + raster), and at 1920 x 1200 a MET / NOT MET
    line for the target: the whole frame (all five phases) <= ``TARGET_16K_S`` at 16k strokes.
``hash``
    The paper's double-hashed aggregation on the same G-buffer with about 4k strokes: for table
    sizes from a quarter of the stroke count to 8 times it, three frames of a still view routed from an
    empty table; per frame the strokes delayed (lost the write race for an empty slot), contested
    (their slot received another stroke's fragments, so not drawn this frame) and lost (no slot
    within 32 probes).
``jitter``
    The ``tamiss_sphere`` scene, the camera orbiting slowly (``--orbit-step`` degrees per frame
    about the vertical axis through the sphere, ``--frames`` frames, ``--jitter-size``), extent
    ``range``. For every stroke present in two consecutive frames, with t_e one of its ends
    (t_min, t_max) in the first frame, its true screen motion is the projection of its texture
    point at t_e in the two frames (texture -> mesh -> world by point location in the uv chart,
    then the frames' camera matrices). Reported (pixels, mean and 95th percentile over stroke
    ends and frame pairs):

    * curve jitter: |(r'(t_e) - r(t_e)) - (P'(t_e) - P(t_e))|, the fitted curve at a fixed t;
    * endpoint jitter: |(r'(t_e') - r(t_e)) - (P'(t_e) - P(t_e))|, the drawn end (t_e' its
      new t_min / t_max), which also moves when the gathered t range changes;

    without averaging and with :class:`AggregateHistory` over ``--average`` frames (the paper's
    proposal, sec. 4.1). Averaging lags true motion by (frames - 1) / 2 frames, constant for a
    steady orbit, so it cancels in these frame-to-frame differences.

``options``
    The jitter remedies as style parameters, each beside the texture-space TAM baseline of the
    same field (golden case ``tamiss-knot-tam``) on two sequences: the built-in
    ``tamiss_knot_orbit`` (0.625 degrees a frame) and ``knot_1deg``, the ``tamiss_torus_knot``
    scene in the ``tamiss-knot-pen`` style with its camera orbiting 1 degree a frame about the
    vertical axis through the knot. Variants (``OPTION_VARIANTS``): the default; the paper's
    hashed aggregation; ``gather_scale`` (gathering on a g x g grid per pixel, independent of
    spp); ``average_frames`` (the paper's sec. 4.1 averaging of aggregates over k frames);
    ``smooth`` (refnpr's exponential smoothing of the fitted curves by stroke id); a combination.
    Per variant, frames rendered through the sequence protocol (``shade_frame`` and its state):
    E (warping error) and E/D (its ratio to the plain difference), medians over the pairs
    (``refnpr.coherence.pair_metrics`` with the exact motion field), the frame time (median of
    rasterize + shade + composite, from a second pass rendering each frame with every variant in
    turn, so that the ratio to the default tamiss is measured side by side);
    and the stroke-end jitter (px after removing the true motion; median over pairs of the
    per-pair mean and 95th percentile) and strokes appeared / vanished per pair, from the style's
    pipeline on a spp-1 G-buffer with its own state threaded through the frames (as
    ``refnpr.coherence.measure(strokes=True)`` does, but stateful: that one runs each frame's
    pipeline without the state). ``drawn``: the same jitter with the ends on the drawn centreline
    (past [t_min, t_max] the tangent extension of extent ``overdraw``), where
    ``coherence.stroke_ends`` evaluates the cubic's extrapolation there.

All times are wall-clock ``time.perf_counter`` seconds; nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from refnpr.formulas.tamiss import StrokeHashTable  # noqa: E402
from refnpr.raster import Camera, rasterize  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402
from refnpr.styles.tamiss import (  # noqa: E402
    AggregateHistory,
    TamissParams,
    run_pipeline,
    stroke_geometry,
)

#: The ``options`` section's variants: label -> parameters over the scene's tamiss style. The
#: default averages 4 frames carried along the motion; each other remedy is measured on the
#: paper's per-frame fits (``average_frames=1``), alone.
OPTION_VARIANTS: dict[str, dict] = {
    "per-frame fits (paper)": {"average_frames": 1},
    "default": {},
    "hashed": {"aggregation": "hashed", "average_frames": 1},
    "gather_scale=3": {"gather_scale": 3, "average_frames": 1},
    "gather_scale=4": {"gather_scale": 4, "average_frames": 1},
    "average_frames=2": {"average_frames": 2},
    "average_frames=4 plain": {"average_frames": 4, "average_motion": "none"},
    "average_frames=8": {"average_frames": 8},
    "smooth=0.3": {"smooth": 0.3, "average_frames": 1},
    "smooth=0.5": {"smooth": 0.5, "average_frames": 1},
    "smooth=0.7": {"smooth": 0.7, "average_frames": 1},
    "smooth=0.5+gather_scale=3": {"smooth": 0.5, "gather_scale": 3, "average_frames": 1},
    "default+extent=visible": {"extent": "visible"},
}
#: The variant frame times are divided by (the paper's TAMISS, no remedy).
TIME_REFERENCE = "per-frame fits (paper)"
#: The TAM baseline of the options section (golden case tamiss-knot-tam).
TAM_KNOT = {
    "name": "tam",
    "directions": ["v"],
    "period": 4.0,
    "density": 1.0,
    "contours": {"width": 1.2},
}

#: what the tamiss style reads (``derivatives="smooth"`` needs bary, position and its derivatives)
CHANNELS = [
    "uv",
    "duv_dx",
    "duv_dy",
    "tri_id",
    "mesh_id",
    "normal",
    "bary",
    "position",
    "dposition_dx",
    "dposition_dy",
]
PHASES = ("gather", "aggregate", "fit", "extrude", "raster")
#: Szécsi et al., Table 1 (GTX 780, 1920 x 1200): (triangles, strokes, OLS, CGM, E&R) in ms.
#: OLS (fragment streaming and regressor aggregation) compares with refnpr's gather + aggregate,
#: CGM with fit, E&R (extrusion and rendering) with extrude + raster.
PAPER_TABLE1 = (
    (27_000, 1000, 3.06, 0.04, 0.11),
    (27_000, 4000, 2.96, 0.19, 0.32),
    (90_000, 4000, 2.86, 0.31, 2.01),
    (193_000, 4000, 2.78, 0.23, 0.51),
    (193_000, 16000, 2.88, 0.91, 2.04),
)
#: Target: the whole TAMISS frame (all phases, G-buffer excluded), 16k strokes at 1920x1200, s.
TARGET_16K_S = 0.25


def gbuffer(sc, w, h, camera=None):
    return rasterize(sc, camera, w, h, CHANNELS, 1, dtype=np.float64)


def count_strokes(gb, sc, period):
    p = TamissParams.from_params(directions=["v"], period=period)
    return len(run_pipeline(gb, sc, p).aggregates)


def find_period(gb, sc, target, lo=1.0, hi=64.0):
    """Period (px) giving about ``target`` aggregated strokes: secant on log count vs log period."""
    p0, n0 = 8.0, count_strokes(gb, sc, 8.0)
    p1 = float(np.clip(p0 * np.sqrt(n0 / target), lo, hi))
    n1 = count_strokes(gb, sc, p1)
    for _ in range(4):
        if abs(np.log(n1 / target)) < 0.03 or n1 == n0:
            break
        slope = (np.log(n1) - np.log(n0)) / (np.log(p1) - np.log(p0))
        p2 = float(np.clip(np.exp(np.log(p1) + (np.log(target) - np.log(n1)) / slope), lo, hi))
        p0, n0, p1 = p1, n1, p2
        n1 = count_strokes(gb, sc, p1)
    return p1, n1


def bench_phases(args) -> list[dict]:
    sc = load_scene("tamiss_torus_knot")
    w, h = args.size
    t0 = time.perf_counter()
    gb = gbuffer(sc, w, h)
    raster_s = time.perf_counter() - t0
    rows = []
    scale = (w * h) / (1920 * 1200)
    for target in args.targets:
        goal = max(20, int(round(target * scale)))
        period, _ = find_period(gb, sc, goal)
        params = TamissParams.from_params(directions=["v"], period=period)
        run_pipeline(gb, sc, params)  # warm caches
        runs = []
        for _ in range(args.runs):
            r = run_pipeline(gb, sc, params)
            runs.append(dict(r.timings))
        med = {k: statistics.median(t[k] for t in runs) for k in (*PHASES, "total")}
        st = r.stats()
        rows.append(
            {
                "target_strokes": goal,
                "period_px": period,
                "strokes": st["strokes"],
                "drawn": st["drawn"],
                "fragments": st["fragments"],
                "median_s": med,
                "runs_s": runs,
                "fit_share": med["fit"] / med["total"],
                "extrude_raster_s": med["extrude"] + med["raster"],
            }
        )
    print(f"\nTAMISS phases, tamiss_torus_knot {w}x{h} (G-buffer {raster_s:.2f} s, not included), "
          f"median of {args.runs} runs, seconds")  # fmt: skip
    print(f"{'strokes':>8} {'period':>7} {'frags':>8} " + " ".join(f"{p:>9}" for p in PHASES)
          + f" {'total':>8} {'fit %':>6}")  # fmt: skip
    for r in rows:
        m = r["median_s"]
        print(f"{r['strokes']:>8} {r['period_px']:>7.2f} {r['fragments']:>8} "
              + " ".join(f"{m[p]:>9.4f}" for p in PHASES)
              + f" {m['total']:>8.3f} {100 * r['fit_share']:>6.2f}")  # fmt: skip
    print("\nBeside the paper's Table 1 (GPU, GTX 780), ms: OLS vs gather + aggregate, CGM vs fit, "
          "E&R vs extrude + raster")  # fmt: skip
    print(f"{'strokes':>8} {'tris':>6} {'OLS':>6} {'CGM':>6} {'E&R':>6}   refnpr: "
          f"{'gath+agg':>9} {'fit':>8} {'ext+ras':>8} {'total':>8}")  # fmt: skip
    for r in rows:
        m = {k: 1000 * v for k, v in r["median_s"].items()}
        paper = [p for p in PAPER_TABLE1 if p[1] == r["target_strokes"]] or [None]
        r["paper_table1_ms"] = [
            {"triangles": p[0], "strokes": p[1], "ols": p[2], "cgm": p[3], "er": p[4]}
            for p in paper
            if p is not None
        ]
        for p in paper:
            cells = "    -      -      -      -" if p is None else (
                f"{p[0] // 1000:>5}k {p[2]:>6.2f} {p[3]:>6.2f} {p[4]:>6.2f}")  # fmt: skip
            print(f"{r['strokes']:>8} {cells}   refnpr: {m['gather'] + m['aggregate']:>9.1f} "
                  f"{m['fit']:>8.1f} {m['extrude'] + m['raster']:>8.1f} {m['total']:>8.1f}")  # fmt: skip
    big = [r for r in rows if r["target_strokes"] == 16000 and (w, h) == (1920, 1200)]
    if big:
        total = big[0]["median_s"]["total"]
        verdict = "MET" if total <= TARGET_16K_S else "NOT MET"
        big[0]["target_16k"] = {
            "limit_s": TARGET_16K_S,
            "total_s": total,
            "met": total <= TARGET_16K_S,
        }
        print(f"\nwhole frame <= {TARGET_16K_S} s at 16k strokes (1920x1200): {verdict} "
              f"(median total {total:.3f} s, {big[0]['strokes']} strokes)")  # fmt: skip
    return rows


def bench_hash(args) -> list[dict]:
    """Double-hashed aggregation: delayed / contested / lost strokes per table size."""
    sc = load_scene("tamiss_torus_knot")
    w, h = args.size
    gb = gbuffer(sc, w, h)
    goal = max(20, int(round(4000 * (w * h) / (1920 * 1200))))
    period, n = find_period(gb, sc, goal)
    params = TamissParams.from_params(directions=["v"], period=period, aggregation="hashed")
    rows = []
    for log2 in range(max(4, int(np.log2(n)) - 1), int(np.log2(n)) + 5):
        table = StrokeHashTable(1 << log2)
        frames = [run_pipeline(gb, sc, params, table=table).aggregates.hash_stats for _ in range(3)]
        rows.append({"table_size": 1 << log2, "strokes": n,
                     "frames": [f.as_dict() for f in frames]})  # fmt: skip
    print(f"\nDouble hashing, tamiss_torus_knot {w}x{h}, {n} strokes, a still view; frames 1, 2, 3 "
          "from an empty table: delayed / contested (not drawn this frame) / lost")  # fmt: skip
    for r in rows:
        cells = "   ".join(
            f"{f['n_delayed']:>5} /{f['n_contested']:>5} /{f['n_lost']:>5}" for f in r["frames"]
        )
        print(f"table {r['table_size']:>7} (load {n / r['table_size']:5.2f}):   {cells}")
    return rows


def _uv_locator(mesh, chart_uv_scale):
    """texture (u', v') -> world point on the mesh (piecewise linear), by bucketed point location."""
    uv = mesh.uv * np.asarray(chart_uv_scale)
    tri_uv = uv[mesh.faces]  # (F, 3, 2)
    lo, hi = tri_uv.min(1), tri_uv.max(1)
    g = 64
    u0, u1 = uv[:, 0].min(), uv[:, 0].max()
    v0, v1 = uv[:, 1].min(), uv[:, 1].max()
    cell = lambda x, a, b: np.clip(((x - a) / (b - a) * g).astype(int), 0, g - 1)  # noqa: E731
    buckets: dict = {}
    for f in range(tri_uv.shape[0]):
        for i in range(cell(lo[f, 0], u0, u1), cell(hi[f, 0], u0, u1) + 1):
            for j in range(cell(lo[f, 1], v0, v1), cell(hi[f, 1], v0, v1) + 1):
                buckets.setdefault((i, j), []).append(f)

    def locate(pts):
        out = np.full((pts.shape[0], 3), np.nan)
        for k, (u, v) in enumerate(pts):
            cand = buckets.get((int(cell(np.array(u), u0, u1)), int(cell(np.array(v), v0, v1))))
            if not cand:
                continue
            t = tri_uv[cand]
            a, b, c = t[:, 0], t[:, 1], t[:, 2]
            den = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (
                a[:, 1] - c[:, 1]
            )
            w0 = ((b[:, 1] - c[:, 1]) * (u - c[:, 0]) + (c[:, 0] - b[:, 0]) * (v - c[:, 1])) / den
            w1 = ((c[:, 1] - a[:, 1]) * (u - c[:, 0]) + (a[:, 0] - c[:, 0]) * (v - c[:, 1])) / den
            w2 = 1 - w0 - w1
            inside = (w0 >= -1e-9) & (w1 >= -1e-9) & (w2 >= -1e-9)
            if np.any(inside):
                i = np.flatnonzero(inside)[0]
                P = mesh.positions[mesh.faces[cand[i]]]
                out[k] = w0[i] * P[0] + w1[i] * P[1] + w2[i] * P[2]
        return out

    return locate


def _project(gb, world):
    P = np.concatenate([world, np.ones((world.shape[0], 1))], 1) @ gb.view_projection.T
    ndc = P[:, :2] / P[:, 3:]
    return np.stack([(ndc[:, 0] + 1) / 2 * gb.width, (1 - ndc[:, 1]) / 2 * gb.height], 1)


def bench_jitter(args) -> dict:
    sc = load_scene("tamiss_sphere")
    w, h = args.jitter_size
    obj = sc.objects[0]
    locate = _uv_locator(obj.world_mesh(), obj.material.uv_scale)
    params = TamissParams.from_params(directions=["u"], period=4.0, extent="range")
    cam0 = sc.camera
    eye0 = np.asarray(cam0.eye)
    target = np.asarray(cam0.target)
    out = {}
    for label, hist_frames in (("none", None), (f"average{args.average}", args.average)):
        history = AggregateHistory(hist_frames) if hist_frames else None
        frames = []
        for k in range(args.frames):
            a = np.radians(args.orbit_step * k)
            rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
            eye = target + rot @ (eye0 - target)
            cam = Camera.look_at(eye, target, cam0.up, cam0.fov_y, cam0.near, cam0.far)
            frame_sc = sc.with_camera(cam)
            gb = gbuffer(frame_sc, w, h)
            r = run_pipeline(gb, frame_sc, params, history=history)
            frames.append((gb, r))
        curve, endpoint = [], []
        for (gb0, r0), (gb1, r1) in zip(frames[:-1], frames[1:], strict=True):
            ids = np.intersect1d(r0.stroke_ids[r0.keep], r1.stroke_ids[r1.keep])
            if ids.size == 0:
                continue
            i0 = np.searchsorted(r0.stroke_ids, ids)
            i1 = np.searchsorted(r1.stroke_ids, ids)
            f0, f1 = r0.fit.take(i0), r1.fit.take(i1)
            g = stroke_geometry(ids, params.field)
            for end in ("t_min", "t_max"):
                te = np.asarray(getattr(f0, end), dtype=np.float64)
                te1 = np.asarray(getattr(f1, end), dtype=np.float64)
                uvp = np.stack([g.p_start + te * g.length, g.q], 1)  # layer "u": (p, q) = uv'
                world = locate(uvp)
                ok = np.all(np.isfinite(world), 1)
                true = _project(gb1, world) - _project(gb0, world)
                x0, y0 = (
                    np.asarray(v, np.float64) for v in f0.evaluate(te[:, None].astype(f0.c_x.dtype))
                )
                tc = np.clip(te, f1.t_min, f1.t_max)[:, None].astype(f1.c_x.dtype)
                x1, y1 = (np.asarray(v, np.float64) for v in f1.evaluate(tc))
                e1x, e1y = (
                    np.asarray(v, np.float64)
                    for v in f1.evaluate(te1[:, None].astype(f1.c_x.dtype))
                )
                d_curve = np.stack([x1 - x0, y1 - y0], -1)[:, 0] - true
                d_end = np.stack([e1x - x0, e1y - y0], -1)[:, 0] - true
                curve.append(np.hypot(*d_curve[ok].T))
                endpoint.append(np.hypot(*d_end[ok].T))
        c, e = np.concatenate(curve), np.concatenate(endpoint)
        out[label] = {
            "curve_mean_px": float(c.mean()),
            "curve_p95_px": float(np.percentile(c, 95)),
            "endpoint_mean_px": float(e.mean()),
            "endpoint_p95_px": float(np.percentile(e, 95)),
            "samples": int(c.size),
        }
    print(f"\nStroke jitter, tamiss_sphere {w}x{h}, orbit {args.orbit_step} deg/frame, "
          f"{args.frames} frames, extent range; pixels after removing true motion")  # fmt: skip
    print(f"{'aggregates':>12} {'curve mean':>11} {'curve p95':>10} {'end mean':>9} "
          f"{'end p95':>8} {'n':>7}")  # fmt: skip
    for k, v in out.items():
        print(f"{k:>12} {v['curve_mean_px']:>11.4f} {v['curve_p95_px']:>10.4f} "
              f"{v['endpoint_mean_px']:>9.4f} {v['endpoint_p95_px']:>8.4f} {v['samples']:>7}")  # fmt: skip
    return {"scene": "tamiss_sphere", "size": [w, h], "orbit_step_deg": args.orbit_step,
            "frames": args.frames, "average_frames": args.average, "results": out}  # fmt: skip


def _orbit_scenes(name: str, step_deg: float, frames: int) -> list:
    """``frames`` stills of scene ``name`` with its camera orbiting ``step_deg`` a frame about
    the vertical axis through its target."""
    sc = load_scene(name)
    cam0 = sc.camera
    eye0, target = np.asarray(cam0.eye, np.float64), np.asarray(cam0.target, np.float64)
    out = []
    for k in range(frames):
        a = np.radians(step_deg * k)
        rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        cam = Camera.look_at(
            target + rot @ (eye0 - target), target, cam0.up, cam0.fov_y, cam0.near, cam0.far
        )
        out.append(sc.with_camera(cam))
    return out


def _drawn_ends(result):
    """``refnpr.coherence.stroke_ends`` with the ends on the *drawn* centreline: past [t_min,
    t_max] (extent overdraw) the tangent extension the strips follow, where ``stroke_ends``
    evaluates the cubic's extrapolation."""
    from refnpr.coherence import StrokeEnds
    from refnpr.styles.tamiss.strokes import centreline

    seg = np.asarray(result.segments, dtype=np.float64)
    drawn = np.asarray(result.n_segments) > 0
    with np.errstate(invalid="ignore"):
        t0 = np.where(drawn, np.nanmin(np.where(drawn[:, None], seg[..., 0], 0.0), axis=1), 0.0)
        t1 = np.where(drawn, np.nanmax(np.where(drawn[:, None], seg[..., 1], 0.0), axis=1), 0.0)
    with np.errstate(invalid="ignore", over="ignore"):
        x0, y0, _, _ = centreline(result.fit, t0[:, None])
        x1, y1, _, _ = centreline(result.fit, t1[:, None])
    ids = np.asarray(result.stroke_ids, dtype=np.int64)
    pick = np.flatnonzero(drawn)[np.argsort(ids[drawn], kind="stable")]
    return StrokeEnds(
        ids[pick],
        np.stack([x0[pick, 0], y0[pick, 0]], -1),
        np.stack([x1[pick, 0], y1[pick, 0]], -1),
    )


def _lag_px(result, field) -> float:
    """Median lag, in pixels along each stroke's motion, of the fitted (averaged) sums'
    centroids behind the frame's own fragments (positive: behind; 0 without averaging)."""
    from refnpr.styles.tamiss import aggregate_exact

    def centroids(agg):
        m = np.asarray(agg.moments, np.float64)
        return np.asarray(agg.origin, np.float64) + m[:, [7, 11]] / np.maximum(m[:, :1], 1)

    raw = aggregate_exact(result.fragments, dtype=np.float64)
    raw = raw.take(np.isin(raw.stroke_ids, result.stroke_ids))
    c_raw = centroids(raw)
    h, w = field.shape
    col = np.clip(c_raw[:, 0].astype(int), 0, w - 1)
    row = np.clip(c_raw[:, 1].astype(int), 0, h - 1)
    v = np.stack([col + 0.5, row + 0.5], -1) - field.xy[row, col]
    speed = np.hypot(*v.T)
    ok = field.valid[row, col] & (speed > 0.05)
    if not ok.any():
        return float("nan")
    u = v[ok] / speed[ok, None]
    return float(np.median(-np.einsum("ki,ki->k", centroids(result.aggregates)[ok] - c_raw[ok], u)))


def _measure_variant(style, scenes, w, h, spp, strokes: bool) -> dict:
    """E, E/D, frame time and (stroke styles) stroke jitter, the ink's E/D against its floor
    (``refnpr.coherence.ink_floor``) and the averaging lag of one style on ``scenes``."""
    from refnpr.coherence import (
        MOTION_CHANNELS,
        STROKE_CHANNELS,
        ink_floor,
        motion_field,
        pair_metrics,
        render_frame,
        stroke_ends,
        stroke_pair_metrics,
    )
    from refnpr.coherence.strokes import stroke_style
    from refnpr.styles import ShadeContext

    state = style.initial_state()
    times, rows, fields = [], [], []
    prev = None
    for t, scene in enumerate(scenes):
        t0 = time.perf_counter()
        rgba, state = render_frame(style, scene, w, h, spp, state)
        times.append(time.perf_counter() - t0)
        gb = rasterize(scene, None, w, h, MOTION_CHANNELS, 1, dtype=np.float64)
        if prev is not None:
            motion = motion_field(gb, prev[1], scene, prev[2])
            rows.append(pair_metrics(rgba, prev[0], motion, frame=t))
            fields.append(motion)
        prev = (rgba, gb, scene)
    out = {
        "E": statistics.median(r.warp_error for r in rows),
        "E_over_D": statistics.median(r.ratio for r in rows),
        "flip": statistics.median(r.flip for r in rows),
        "frame_s": statistics.median(times),
        "frame_s_spread": [min(times), max(times)],
    }
    if not strokes:
        return out
    tam = stroke_style(style)
    sstate = tam.initial_state()
    srows, drows = [], []
    prev_e = None
    for t, scene in enumerate(scenes):
        chans = sorted(set(tam.requires(scene)) | set(STROKE_CHANNELS))
        sgb = rasterize(
            scene, None, w, h, chans, 1, **{"dtype": np.float64, **tam.raster_options(scene)}
        )
        result, sstate = tam.run_frame(ShadeContext(sgb, scene), sstate)
        ends, dends = stroke_ends(result), _drawn_ends(result)
        if prev_e is not None:
            srows.append(stroke_pair_metrics(ends, prev_e[0], prev_e[1], scene, prev_e[2], frame=t))
            drows.append(stroke_pair_metrics(dends, prev_e[3], prev_e[1], scene, prev_e[2]))
        prev_e = (ends, sgb, scene, dends)
    # the ink at the render's spp against its floor, and the averaging lag
    fstate = tam.initial_state()
    floors, lags = [], []
    prev_f = None
    for t, scene in enumerate(scenes):
        gb = rasterize(scene, None, w, h, sorted(tam.requires(scene)), spp,
                       **tam.raster_options(scene))  # fmt: skip
        result, fstate = tam.run_frame(ShadeContext(gb, scene), fstate)
        sgb = rasterize(scene, None, w, h, STROKE_CHANNELS, 1, dtype=np.float64)
        if prev_f is not None:
            field = fields[t - 1]
            floors.append(ink_floor(prev_f[0], result, prev_f[1], scene, prev_f[2], field))
            lags.append(_lag_px(result, field))
        prev_f = (result, sgb, scene)
    ok = [r for r in srows if r.n_ends]
    dok = [r for r in drows if r.n_ends]
    out.update(
        {
            "jitter_mean_px": statistics.median(r.jitter_mean for r in ok) if ok else None,
            "jitter_p95_px": statistics.median(r.jitter_p95 for r in ok) if ok else None,
            "drawn_end_mean_px": statistics.median(r.jitter_mean for r in dok) if dok else None,
            "drawn_end_p95_px": statistics.median(r.jitter_p95 for r in dok) if dok else None,
            "appeared": statistics.mean(r.appeared for r in srows),
            "vanished": statistics.mean(r.vanished for r in srows),
            "n_strokes": statistics.mean(r.n_strokes for r in srows),
            "ink_E_over_D": statistics.median(f.actual.ratio for f in floors),
            "floor_E_over_D": statistics.median(f.floor.ratio for f in floors),
            "excess_E_over_D": statistics.median(f.excess for f in floors),
            "lag_px": statistics.median(lags),
            "motion_px": statistics.median(f.actual.motion_px for f in floors),
        }
    )
    return out


def _interleaved_times(styles: dict, scenes, w, h, spp) -> dict:
    """Median frame time (rasterize + shade + composite) of each style, frames rendered in turn
    across the styles (each with its own state), so that the machine's load is shared."""
    from refnpr.coherence import render_frame

    states = {k: s.initial_state() for k, s in styles.items()}
    times: dict = {k: [] for k in styles}
    for scene in scenes:
        for k, style in styles.items():
            t0 = time.perf_counter()
            _, states[k] = render_frame(style, scene, w, h, spp, states[k])
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def bench_options(args) -> dict:
    from refnpr.styles import style_from_spec

    if args.quick:
        w, h, spp, n = 160, 120, 1, 4
    else:
        w, h, spp, n = 480, 360, 4, 12
    anim = load_scene("tamiss_knot_orbit")
    sequences = {
        "tamiss_knot_orbit": [anim.at(f) for f in range(n)],
        "knot_1deg": _orbit_scenes("tamiss_torus_knot", 1.0, n),
        "knot_4deg": _orbit_scenes("tamiss_torus_knot", 4.0, n),
    }
    pen = dict(anim.at(0).style)  # the tamiss-knot-pen style, contours included
    variants = [("tam", TAM_KNOT, False)] + [
        (label, {**pen, **extra}, True) for label, extra in OPTION_VARIANTS.items()
    ]
    if args.quick:
        keep = ("tam", TIME_REFERENCE, "default", "gather_scale=3", "average_frames=4 plain")
        variants = [v for v in variants if v[0] in keep]
        sequences = {k: sequences[k] for k in ("tamiss_knot_orbit", "knot_4deg")}
    out: dict = {"size": [w, h], "spp": spp, "frames": n, "sequences": {}}
    for seq, scenes in sequences.items():
        res = {}
        for label, spec, strokes in variants:
            res[label] = _measure_variant(style_from_spec(spec), scenes, w, h, spp, strokes)
        side = _interleaved_times(
            {label: style_from_spec(spec) for label, spec, _ in variants}, scenes, w, h, spp
        )
        for label, v in res.items():
            v["frame_s_interleaved"] = side[label]
            v["time_ratio"] = side[label] / side[TIME_REFERENCE]
        out["sequences"][seq] = res
        print(f"\nTAMISS jitter options, {seq} {w}x{h} spp {spp}, {n} frames (medians over pairs; "
              f"x time against {TIME_REFERENCE!r})")  # fmt: skip
        print(f"{'variant':>26} {'end mean':>9} {'end p95':>8} {'drawn':>6} {'d p95':>6} "
              f"{'appear':>7} {'vanish':>7} {'E':>8} {'E/D':>6} {'ink E/D':>8} {'floor':>6} "
              f"{'excess':>7} {'lag px':>7} {'frame s':>8} {'x time':>7}")  # fmt: skip

        def cell(v, key, width, fmt):
            x = v.get(key)
            return f"{x:{width}{fmt}}" if x is not None else f"{'-':>{width}}"

        for label, v in res.items():
            print(f"{label:>26} {cell(v, 'jitter_mean_px', 9, '.3f')} "
                  f"{cell(v, 'jitter_p95_px', 8, '.3f')} {cell(v, 'drawn_end_mean_px', 6, '.3f')} "
                  f"{cell(v, 'drawn_end_p95_px', 6, '.3f')} {cell(v, 'appeared', 7, '.1f')} "
                  f"{cell(v, 'vanished', 7, '.1f')} {v['E']:8.5f} {v['E_over_D']:6.3f} "
                  f"{cell(v, 'ink_E_over_D', 8, '.3f')} {cell(v, 'floor_E_over_D', 6, '.3f')} "
                  f"{cell(v, 'excess_E_over_D', 7, '.3f')} {cell(v, 'lag_px', 7, '.3f')} "
                  f"{v['frame_s_interleaved']:8.3f} {v['time_ratio']:7.2f}")  # fmt: skip
        if "motion_px" in res.get("default", {}):
            print(f"{'':>26} surface motion {res['default']['motion_px']:.2f} px a frame")
    return out


def _size(s: str) -> tuple[int, int]:
    w, h = s.lower().split("x")
    return int(w), int(h)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, one run (smoke test)")
    ap.add_argument("--sections", default="phases,hash,jitter")
    ap.add_argument("--size", type=_size, default=None, help="phases image size (1920x1200)")
    ap.add_argument("--targets", default="1000,4000,16000", help="stroke counts at 1920x1200")
    ap.add_argument("--runs", type=int, default=None)
    ap.add_argument("--jitter-size", type=_size, default=None, help="jitter image size (640x480)")
    ap.add_argument("--frames", type=int, default=None)
    ap.add_argument("--orbit-step", type=float, default=0.25)
    ap.add_argument("--average", type=int, default=4)
    ap.add_argument("--json", default=str(HERE / "results" / "tamiss.json"))
    args = ap.parse_args(argv)
    args.size = args.size or ((480, 300) if args.quick else (1920, 1200))
    args.jitter_size = args.jitter_size or ((240, 180) if args.quick else (640, 480))
    args.runs = args.runs or (1 if args.quick else 5)
    args.frames = args.frames or (4 if args.quick else 16)
    args.targets = [int(x) for x in args.targets.split(",")]
    sections = {s.strip() for s in args.sections.split(",") if s.strip()}
    report = {
        "meta": {
            "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "python": platform.python_version(),
            "machine": platform.machine(),
            "cpus": os.cpu_count(),
            "numba_threads": int(__import__("numba").get_num_threads()),
            "quick": bool(args.quick),
        },
        "phases": bench_phases(args) if "phases" in sections else [],
        "hash": bench_hash(args) if "hash" in sections else [],
        "jitter": bench_jitter(args) if "jitter" in sections else {},
        "options": bench_options(args) if "options" in sections else {},
    }
    path = Path(args.json)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report, indent=2))
    print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
