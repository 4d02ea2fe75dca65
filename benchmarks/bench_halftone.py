"""Freudenberg et al. 2002 real-time halftoning: run time against error, temporal coherence, tone.

Usage::

    python benchmarks/bench_halftone.py                       # full run, writes results/halftone.json
    python benchmarks/bench_halftone.py --quick --json /tmp/h.json   # smoke run (seconds)

Sections:

``pareto``
    For halftoned views (the teapot engraving of Fig. 5, ``halftone_teapot``; the hatched sphere
    of Fig. 4, ``halftone_sphere``), the error of each anti-aliasing method against a 16 x 16
    supersampled *binary* render of the same view (spp = 256) and its run time (median of ``--runs`` calls of ``refnpr.render.render``, G-buffer
    included; screens are built before timing). Methods: 1 spp binary (sec. 3.1), n x n
    supersampled binary (n = 2, 4, 8), the smooth threshold at 1 spp (sec. 3.2: the paper's
    one-sided ramp with c = 4, and the centred ramp with c = 2, 4, 8), the centred smooth
    threshold with 2 x 2 supersampling. Error = mean absolute difference of the gray image
    (linear, [0, 1]) over the pixels the object covers; RMSE and the mean signed difference
    (tone bias) are also reported. The Pareto front (no other method both faster and at least
    as accurate) is marked, and the method that reaches the error of 4 x 4 supersampling in
    the least time is named. A PNG plot (time vs error, log-log) is written next to the JSON.
``temporal``
    Pixels that flip (change by more than 1/2) between consecutive frames of a camera dolly
    (the eye moves 1.5 % of the distance towards the target per frame), binary vs smooth,
    on both views; also the mean absolute change per pixel.
``tone``
    Mean output minus target intensity on a flat, evenly lit plane, per screen and threshold
    (max over I in [0.05, 0.95]).

Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import _time_error  # noqa: E402

from refnpr.raster import Camera, rasterize  # noqa: E402
from refnpr.render import render  # noqa: E402
from refnpr.scenes import (  # noqa: E402
    Light,
    Material,
    Scene,
    SceneObject,
    load_scene,
    plane,
    transform_matrix,
)
from refnpr.styles import ShadeContext, get_style  # noqa: E402

VIEWS = {
    "teapot-engraving": (
        "halftone_teapot",
        dict(screen={"kind": "engraving", "profile": "triangle", "angle": 90.0}, uv_scale=[1, 6]),
    ),
    "sphere-hatching": (
        "halftone_sphere",
        dict(screen="hatching", uv_scale=[4, 2], specular=False),
    ),
}


def methods() -> list[tuple[str, dict, int]]:
    """(label, style overrides, spp)."""
    out = [("binary 1spp", dict(threshold="binary"), 1)]
    out += [(f"binary {n}x{n}", dict(threshold="binary"), n * n) for n in (2, 4, 8)]
    out.append(("smooth c=4 (paper)", dict(threshold="smooth", c=4.0), 1))
    out += [
        (f"smooth centred c={c:g}", dict(threshold="smooth", c=c, centred=True), 1)
        for c in (2.0, 4.0, 8.0)
    ]
    out.append(("smooth centred c=4 2x2", dict(threshold="smooth", c=4.0, centred=True), 4))
    out.append(("smooth c=auto (fwidth)", dict(threshold="smooth", c="auto"), 1))
    out += [(f"smooth c=auto {n}x{n}", dict(threshold="smooth", c="auto"), n * n) for n in (2, 3)]
    out.insert(2, ("binary 3x3", dict(threshold="binary"), 9))
    return out


SAMPLE_LOD = False


def _style(view: str, **over):
    _, params = VIEWS[view]
    return get_style("halftone", **{**params, "sample_lod": SAMPLE_LOD, **over})


def _gray(img) -> np.ndarray:
    return img.rgba[..., :3].astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])


def _timed(scene, style, w, h, spp, runs):
    render(scene, style, w, h, spp)  # warm: screens built, numba loaded
    times, img = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        img = render(scene, style, w, h, spp)
        times.append(time.perf_counter() - t0)
    return img, times


def section_pareto(w: int, h: int, runs: int, ref_n: int) -> dict:
    out = {}
    for view, (scene_name, _) in VIEWS.items():
        scene = load_scene(scene_name)
        t0 = time.perf_counter()
        ref_img, gb = render(
            scene, _style(view, threshold="binary"), w, h, ref_n * ref_n, return_gbuffer=True
        )
        ref_s = time.perf_counter() - t0
        ref = _gray(ref_img)
        covered = gb.resolve((gb["mesh_id"] >= 0).astype(np.float64)) > 0
        del gb
        rows = []
        for label, over, spp in methods():
            img, times = _timed(scene, _style(view, **over), w, h, spp, runs)
            diff = _gray(img)[covered] - ref[covered]
            rows.append(
                {
                    "method": label,
                    "spp": spp,
                    "runs_s": times,
                    "median_s": statistics.median(times),
                    "mae": float(np.mean(np.abs(diff))),
                    "rmse": float(np.sqrt(np.mean(diff**2))),
                    "bias": float(np.mean(diff)),
                }
            )
        front, target, best = _time_error.summarize(rows, "median_s", "binary 4x4")
        out[view] = {
            "scene": scene_name,
            "size": [w, h],
            "reference": f"binary {ref_n}x{ref_n} (spp {ref_n * ref_n})",
            "reference_s": ref_s,
            "covered_pixels": int(covered.sum()),
            "rows": rows,
            "pareto_front": front,
            "error_of_4x4": target,
            "fastest_reaching_4x4_error": best,
        }
    return out


def _dolly_cameras(scene, frames: int, step: float) -> list[Camera]:
    cam = scene.camera
    eye, target = np.asarray(cam.eye, float), np.asarray(cam.target, float)
    out = []
    for k in range(frames):
        e = eye + (target - eye) * step * k
        out.append(
            Camera.look_at(tuple(e), tuple(target), tuple(cam.up), cam.fov_y, cam.near, cam.far)
        )
    return out


def section_temporal(w: int, h: int, frames: int) -> dict:
    variants = [
        ("binary 1spp", dict(threshold="binary"), 1),
        ("smooth c=4 (paper)", dict(threshold="smooth", c=4.0), 1),
        ("smooth centred c=4", dict(threshold="smooth", c=4.0, centred=True), 1),
        ("smooth c=auto", dict(threshold="smooth", c="auto"), 1),
        ("binary 4x4", dict(threshold="binary"), 16),
    ]
    out = {}
    for view, (scene_name, _) in VIEWS.items():
        scene = load_scene(scene_name)
        cams = _dolly_cameras(scene, frames, 0.015)
        rows = []
        for label, over, spp in variants:
            style = _style(view, **over)
            imgs, covered = [], []
            for cam in cams:
                img, gb = render(scene, style, w, h, spp, camera=cam, return_gbuffer=True)
                imgs.append(_gray(img))
                covered.append(int((gb.resolve((gb["mesh_id"] >= 0) * 1.0) > 0).sum()))
            flips = [
                int(np.sum(np.abs(b - a) > 0.5)) for a, b in zip(imgs[:-1], imgs[1:], strict=True)
            ]
            change = [
                float(np.mean(np.abs(b - a))) for a, b in zip(imgs[:-1], imgs[1:], strict=True)
            ]
            rows.append(
                {
                    "method": label,
                    "flips_per_frame": flips,
                    "mean_flips": float(np.mean(flips)),
                    "mean_flips_fraction": float(np.mean(flips) / np.mean(covered)),
                    "mean_abs_change": float(np.mean(change)),
                }
            )
        out[view] = {"scene": scene_name, "frames": frames, "step": 0.015, "rows": rows}
    return out


def _flat_scene(intensity: float) -> Scene:
    obj = SceneObject(
        plane(2.0, 2.0, tile=2.0),
        transform_matrix(rotate_deg=(90.0, 0.0, 0.0)),
        Material(ambient=0.0, diffuse=intensity, specular=0.0),
        name="plane",
    )
    cam = Camera.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 30.0, 0.1, 50.0)
    return Scene((obj,), cam, (Light(direction=(0.0, 0.0, 1.0)),))


def section_tone(size: int, quick: bool = False) -> dict:
    screens = {
        "engraving triangle": {"kind": "engraving", "profile": "triangle", "angle": 30.0},
        "engraving ramp": {"kind": "engraving", "profile": "ramp", "angle": 30.0},
        "dither brick": "brick",
        "dither grass": "grass",
        "hatching": "hatching",
        "bricks": "bricks",
    }
    variants = [
        ("binary", dict(threshold="binary")),
        ("binary per_level", dict(threshold="binary", mip="per_level")),
        ("binary tone_correct", dict(threshold="binary", tone_correct=True)),
        ("smooth c=4 (paper)", dict(threshold="smooth", c=4.0)),
        ("smooth centred c=4", dict(threshold="smooth", c=4.0, centred=True)),
    ]
    intensities = np.linspace(0.05, 0.95, 5 if quick else 19)
    if quick:
        screens = {k: screens[k] for k in ("engraving triangle", "dither brick", "hatching")}
    rows = []
    base = _flat_scene(0.5)
    for sname, screen in screens.items():
        st0 = get_style("halftone", screen=screen, uv_scale=2.0, specular=False)
        gb = rasterize(base, base.camera, size, size, sorted(st0.requires(base)))
        covered = gb["mesh_id"] >= 0
        for vname, over in variants:
            st = get_style("halftone", screen=screen, uv_scale=2.0, specular=False, **over)
            errs = []
            for i in intensities:
                img = st.shade(ShadeContext(gb, _flat_scene(float(i))))
                errs.append(float(img[..., 0][covered].mean()) - i)
            errs = np.array(errs)
            rows.append(
                {
                    "screen": sname,
                    "variant": vname,
                    "mean_error": float(errs.mean()),
                    "max_abs_error": float(np.abs(errs).max()),
                    "worst_intensity": float(intensities[np.argmax(np.abs(errs))]),
                }
            )
    return {"size": size, "uv_scale": 2.0, "intensities": intensities.tolist(), "rows": rows}


def print_tables(report: dict) -> None:
    for view, sec in report.get("pareto", {}).items():
        print(f"\n{view}: {sec['size'][0]}x{sec['size'][1]}, error vs {sec['reference']}")
        print(
            f"  {'method':26s} {'spp':>4s} {'median s':>9s} {'MAE':>8s} {'RMSE':>8s} {'bias':>8s}"
        )
        for r in sec["rows"]:
            mark = " *" if r["pareto"] else ""
            print(
                f"  {r['method']:26s} {r['spp']:4d} {r['median_s']:9.3f} {r['mae']:8.4f} "
                f"{r['rmse']:8.4f} {r['bias']:+8.4f}{mark}"
            )
        print(
            f"  * Pareto front. Error of 4x4: {sec['error_of_4x4']:.4f}; fastest method reaching "
            f"it: {sec['fastest_reaching_4x4_error']}"
        )
    for view, sec in report.get("temporal", {}).items():
        print(f"\n{view}: dolly of {sec['frames']} frames, pixels flipping (|change| > 1/2)")
        for r in sec["rows"]:
            print(
                f"  {r['method']:26s} flips/frame {r['mean_flips']:8.1f} "
                f"({100 * r['mean_flips_fraction']:5.2f} % of covered)  mean |change| "
                f"{r['mean_abs_change']:.4f}"
            )
    if "tone" in report:
        print("\nflat plane tone: max |mean - I| over I in [0.05, 0.95] (mean error)")
        for r in report["tone"]["rows"]:
            print(
                f"  {r['screen']:20s} {r['variant']:20s} {r['max_abs_error']:.4f} "
                f"({r['mean_error']:+.4f}) worst at I={r['worst_intensity']:.2f}"
            )


def plot(report: dict, path: Path) -> None:
    panels = [
        {
            "title": f"{view} ({sec['size'][0]}x{sec['size'][1]})",
            "rows": sec["rows"],
            "target": sec["error_of_4x4"],
            "target_label": "error of 4x4",
            "ylabel": f"MAE vs {sec['reference']}",
        }
        for view, sec in report["pareto"].items()
    ]
    _time_error.plot_time_vs_error(
        path, panels, time_key="median_s", xlabel="median render time (s)"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes, one run (smoke test)")
    ap.add_argument("--runs", type=int, default=None)
    ap.add_argument("--size", default=None, help="WxH of the pareto/temporal views (160x120)")
    ap.add_argument("--ref", type=int, default=None, help="reference n (n x n spp; default 16)")
    ap.add_argument("--frames", type=int, default=None, help="dolly frames (default 10)")
    ap.add_argument("--sections", default="pareto,temporal,tone")
    ap.add_argument("--json", default=str(HERE / "results" / "halftone.json"))
    ap.add_argument("--plot", default=None, help="PNG of the Pareto plot (default: next to json)")
    ap.add_argument("--sample-lod", action="store_true", help="per-sample LODs in every render")
    args = ap.parse_args(argv)
    global SAMPLE_LOD
    SAMPLE_LOD = bool(args.sample_lod)
    w, h = (48, 36) if args.quick else (160, 120)
    if args.size:
        w, h = (int(x) for x in args.size.lower().split("x"))
    runs = args.runs or (1 if args.quick else 3)
    ref_n = args.ref or (4 if args.quick else 16)
    frames = args.frames or (3 if args.quick else 10)
    sections = [s.strip() for s in args.sections.split(",") if s.strip()]
    report: dict = {
        "meta": {
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "python": platform.python_version(),
            "machine": platform.machine(),
            "quick": args.quick,
            "runs": runs,
            "sample_lod": SAMPLE_LOD,
        }
    }
    if "pareto" in sections:
        report["pareto"] = section_pareto(w, h, runs, ref_n)
    if "temporal" in sections:
        report["temporal"] = section_temporal(w, h, frames)
    if "tone" in sections:
        report["tone"] = section_tone(32 if args.quick else 96, args.quick)
    print_tables(report)
    out = Path(args.json)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2))
    print(f"\nwrote {out}")
    if "pareto" in report:
        png = Path(args.plot) if args.plot else out.with_suffix(".png")
        try:
            plot(report, png)
            print(f"wrote {png}")
        except ImportError as exc:  # matplotlib is optional
            print(f"plot skipped: {exc}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
