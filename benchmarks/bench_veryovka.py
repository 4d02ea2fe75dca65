"""Veryovka 2002 threshold textures: run time against error, temporal coherence, tone fidelity.

Usage::

    python benchmarks/bench_veryovka.py                      # full run, writes results/veryovka.json
    python benchmarks/bench_veryovka.py --quick --json /tmp/v.json   # smoke run (seconds)

Sections:

``pareto``
    For a hatched view (the vase with cross-hatching, ``source="lines"``) and an image-threshold
    view (``veryovka_room``, CLAHE pyramids), the error of each anti-aliasing method against a
    16 x 16 supersampled binary render of the same view (spp = 256) and its run time (median of
    ``--runs`` calls of ``refnpr.render.render``, G-buffer included; the pyramids are built
    before timing). Methods: 1 spp binary, n x n supersampling (n = 2, 4, 8), filtered
    thresholding with K threshold samples (``filter="pcf"``; images: two mip levels each, the
    paper's sec. 4, and "pcf-tri": one trilinear threshold each, ``mip="trilinear"``) alone and with
    2 x 2 supersampling, analytic line filtering (lines only) alone and with 2 x 2.
    Error = mean absolute difference of the gray image (linear, [0, 1]); RMSE also reported. The
    Pareto front (no other method both faster and more accurate) is marked, and the method
    that reaches the error of 4 x 4 supersampling in the least time is named. A PNG plot (time
    vs error, log-log) is written next to the JSON.
``temporal``
    Pixels that flip between consecutive binary frames of a camera dolly, with and without the
    multi-scale transition (eqs. 7-8): a head-on plane whose dyadic scale crosses an integer
    mid-dolly, and the teapot with hatching over a 12-frame dolly.
``tone``
    Mean rendered tone minus target on a flat, evenly lit plane, per threshold source.

Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
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

from refnpr.raster import Camera  # noqa: E402
from refnpr.render import render  # noqa: E402
from refnpr.scenes import Light, Material, Scene, SceneObject, load_scene  # noqa: E402
from refnpr.scenes.room import plane  # noqa: E402
from refnpr.styles.threshold import ThresholdStyle  # noqa: E402

VIEWS = {
    "hatched": (
        "vase",
        dict(source="lines", period=6.0, uniform=True, directions=[45.0, -45.0], specular=False),
    ),
    "image": ("veryovka_room", dict(source="image", specular=False)),
}


def methods(view: str) -> list[tuple[str, dict, int]]:
    """(label, extra style params, spp) per anti-aliasing method."""
    out = [("binary 1spp", {}, 1)]
    out += [(f"SS {n}x{n}", {}, n * n) for n in (2, 4, 8)]
    ks = (1, 4, 16) if view == "image" else (4, 16)
    out += [(f"pcf K={k}", dict(filter="pcf", samples=k), 1) for k in ks]
    out += [(f"pcf K={k} + SS 2x2", dict(filter="pcf", samples=k), 4) for k in ks[:2]]
    if view == "image":  # one trilinear threshold per footprint sample (PCF of the binary image)
        out += [
            (f"pcf-tri K={k}", dict(filter="pcf", samples=k, mip="trilinear"), 1) for k in (4, 16)
        ]
        out += [("pcf-tri K=4 + SS 2x2", dict(filter="pcf", samples=4, mip="trilinear"), 4)]
    if view == "hatched":
        out += [
            ("analytic", dict(filter="analytic"), 1),
            ("analytic + SS 2x2", dict(filter="analytic"), 4),
        ]
    return out


def pareto_front(rows: list[dict]) -> list[str]:
    """Labels of rows no other row beats in both time and error."""
    return _time_error.pareto_front(rows, "time_s")


def section_pareto(w: int, h: int, runs: int, ref_n: int) -> dict:
    out = {}
    for view, (scene_name, params) in VIEWS.items():
        scene = load_scene(scene_name)
        render(scene, ThresholdStyle(**params), 16, 12, 1)  # warm numba, build nothing timed
        t0 = time.perf_counter()
        ref_style = ThresholdStyle(**params)
        ref = render(scene, ref_style, w, h, ref_n * ref_n).rgba[..., 0].astype(np.float64)
        ref_time = time.perf_counter() - t0
        styles = []
        for label, extra, spp in methods(view):
            style = ThresholdStyle(**params, **extra)
            render(scene, style, 16, 12, spp)  # builds and caches pyramids / tone tables
            styles.append((label, extra, spp, style, [], []))
        images = {}
        for _ in range(runs):  # round-robin, so that load changes hit every method alike
            for label, _extra, spp, style, times, shade in styles:
                t0 = time.perf_counter()
                img = render(scene, style, w, h, spp)
                times.append(time.perf_counter() - t0)
                shade.append(img.timings["shade"] + img.timings["resolve"])
                images[label] = img.rgba[..., 0].astype(np.float64)
        rows = []
        for label, extra, spp, _style, times, shade in styles:
            diff = images[label] - ref
            rows.append(
                {
                    "method": label,
                    "params": extra,
                    "spp": spp,
                    "runs_s": times,
                    "time_s": statistics.median(times),
                    "shade_s": statistics.median(shade),
                    "mae": float(np.mean(np.abs(diff))),
                    "rmse": float(np.sqrt(np.mean(diff**2))),
                }
            )
        front, target, best = _time_error.summarize(rows, "time_s", "SS 4x4")
        out[view] = {
            "scene": scene_name,
            "style": params,
            "reference": f"binary, {ref_n}x{ref_n} supersampling",
            "reference_time_s": ref_time,
            "rows": rows,
            "pareto_front": front,
            "ss4x4_mae": target,
            "fastest_at_ss4x4_error": best,
        }
    return out


# ------------------------------------------------------------------------------- temporal


def _flat_scene(x: float, distance: float) -> Scene:
    th = math.acos(x)
    obj = SceneObject(
        plane(width=40.0, depth=40.0, segments=2),
        material=Material(ambient=0.0, diffuse=1.0, specular=0.0),
    )
    cam = Camera.look_at((0.0, distance, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 40.0, 0.1, 50.0)
    light = Light(direction=(math.sin(th), math.cos(th), 0.0))
    return Scene(
        objects=(obj,),
        camera=cam,
        lights=(light,),
        ambient=(0.0, 0.0, 0.0),
        background=(1, 1, 1, 1),
    )


def _flips(frames: list[np.ndarray]) -> list[int]:
    return [int(np.count_nonzero(a != b)) for a, b in zip(frames[:-1], frames[1:], strict=True)]


def section_temporal(size: int, frames: int) -> dict:
    out = {}
    period = 6.0
    scales = 2.0025 + 0.005 * (np.arange(frames) - frames // 2)
    res = {}
    for multiscale in (True, False):
        style = ThresholdStyle(
            source="lines", period=period, specular=False, uniform=True, multiscale=multiscale
        )
        imgs = []
        for s in scales:
            d = size / (2 * math.tan(math.radians(20.0)) * period * 2.0**s)
            imgs.append(render(_flat_scene(0.3, d), style, size, size, 1).rgba[..., 0] > 0.5)
        res["multiscale" if multiscale else "floored"] = _flips(imgs)
    out["plane"] = {
        "size": size,
        "dyadic_scales": [float(s) for s in scales],
        "crossing_step": int(np.argmax(scales[1:] >= 2.0)),
        "flips": res,
    }
    scene = load_scene("teapot")
    cam = scene.camera
    eye, target = np.asarray(cam.eye), np.asarray(cam.target)
    res = {}
    for multiscale in (True, False):
        style = ThresholdStyle(
            source="lines", period=5.0, specular=False, uniform=True, multiscale=multiscale
        )
        imgs = []
        for i in range(frames):
            e = target + (eye - target) * (
                1.0 - 0.03 * i
            )  # dolly in by 3% of the distance per frame
            c = Camera.look_at(tuple(e), tuple(target), (0.0, 1.0, 0.0), 30.0, 0.5, 50.0)
            imgs.append(
                render(scene, style, size * 2, int(size * 1.5), 1, camera=c).rgba[..., 0] > 0.5
            )
        res["multiscale" if multiscale else "floored"] = _flips(imgs)
    out["teapot"] = {"size": [size * 2, int(size * 1.5)], "dolly_per_frame": 0.03, "flips": res}
    return out


# ----------------------------------------------------------------------------------- tone


TONE_SOURCES = {
    "lines (paper eq. 8)": dict(source="lines", period=4.0, uniform=False),
    "lines uniform": dict(source="lines", period=4.0, uniform=True),
    "lines uniform analytic": dict(source="lines", period=4.0, uniform=True, filter="analytic"),
    "cross-hatch uniform": dict(source="lines", period=4.0, uniform=True, directions=[30.0, -60.0]),
    "stipple (paper)": dict(source="stipple", period=6.0, uniform=False),
    "stipple tone table": dict(source="stipple", period=6.0, uniform=True),
    "image brick trilinear": dict(source="image", texture="brick"),
    "image brick 2-level": dict(source="image", texture="brick", filter="pcf", samples=1),
    "image brick 2-level corrected": dict(
        source="image", texture="brick", filter="pcf", samples=1, tone_correct=True
    ),
    "image brick CLAHE only": dict(
        source="image", texture="brick", rank_equalize=False, filter="pcf", samples=1
    ),
    "constant t=0.5 (toon)": dict(source="constant", t=0.5),
}


def section_tone(size: int) -> dict:
    levels = (0.1, 0.25, 0.5, 0.75, 0.9)
    ppu = size / (2 * 5.0 * math.tan(math.radians(20.0)))
    out = {}
    for label, params in TONE_SOURCES.items():
        p = dict(params, specular=False)
        if p["source"] == "lines":
            p["uv_scale"] = ppu / (p["period"] * 2.0**2.37)  # Frac(s) = 0.37
        elif p["source"] == "stipple":
            p["uv_scale"] = 1.7
        style = ThresholdStyle(**p)
        errs = [
            float(render(_flat_scene(x, 5.0), style, size, size, 1).rgba[..., 0].mean() - x)
            for x in levels
        ]
        out[label] = {
            "levels": list(levels),
            "error": errs,
            "max_abs_error": max(abs(e) for e in errs),
        }
    return out


# --------------------------------------------------------------------------------- output


def print_tables(report: dict) -> None:
    for view, r in report.get("pareto", {}).items():
        print(f"\n{view} view ({r['scene']}), error vs {r['reference']}, median of runs")
        print(f"{'method':<22}{'spp':>5}{'time s':>9}{'shade s':>9}{'MAE':>9}{'RMSE':>9}  pareto")
        for row in sorted(r["rows"], key=lambda x: x["time_s"]):
            mark = "*" if row["pareto"] else ""
            print(
                f"{row['method']:<22}{row['spp']:>5}{row['time_s']:>9.3f}{row['shade_s']:>9.3f}"
                f"{row['mae']:>9.4f}{row['rmse']:>9.4f}  {mark}"
            )
        print(
            f"reaches SS 4x4's error ({r['ss4x4_mae']:.4f}) fastest: {r['fastest_at_ss4x4_error']}"
        )
    if "temporal" in report:
        print("\nflipped pixels per frame (binary), dolly")
        for name, t in report["temporal"].items():
            for mode, flips in t["flips"].items():
                print(
                    f"{name:<8}{mode:<12} mean {np.mean(flips):8.1f}  max {max(flips):6d}  {flips}"
                )
    if "tone" in report:
        print("\ntone on a flat plane: mean - target at x = 0.1, 0.25, 0.5, 0.75, 0.9")
        for label, t in report["tone"].items():
            errs = " ".join(f"{e:+.4f}" for e in t["error"])
            print(f"{label:<32}{errs}   max |err| {t['max_abs_error']:.4f}")


def plot(report: dict, path: Path) -> None:
    panels = [
        {
            "title": f"{view}: {r['scene']}",
            "rows": r["rows"],
            "target": r["ss4x4_mae"],
            "target_label": "SS 4x4 error",
            "ylabel": "mean abs error vs 16x16 SS",
        }
        for view, r in report["pareto"].items()
    ]
    _time_error.plot_time_vs_error(
        path, panels, time_key="time_s", xlabel="render time (s, median)"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes, one run (smoke test)")
    ap.add_argument("--runs", type=int, default=None)
    ap.add_argument("--size", default=None, help="WxH of the pareto views (default 160x120)")
    ap.add_argument("--sections", default="pareto,temporal,tone")
    ap.add_argument("--json", default=str(HERE / "results" / "veryovka.json"))
    args = ap.parse_args(argv)
    w, h = (64, 48) if args.quick else (160, 120)
    if args.size:
        w, h = (int(v) for v in args.size.lower().split("x"))
    runs = args.runs or (1 if args.quick else 3)
    sections = args.sections.split(",")
    report: dict = {
        "meta": {
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "machine": platform.platform(),
            "python": platform.python_version(),
            "size": [w, h],
            "runs": runs,
            "quick": args.quick,
        }
    }
    if "pareto" in sections:
        report["pareto"] = section_pareto(w, h, runs, 8 if args.quick else 16)
    if "temporal" in sections:
        report["temporal"] = section_temporal(48 if args.quick else 96, 6 if args.quick else 12)
    if "tone" in sections:
        report["tone"] = section_tone(64 if args.quick else 160)
    print_tables(report)
    path = Path(args.json)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report, indent=1))
    print(f"\nwrote {path}")
    if "pareto" in report:
        try:
            png = path.with_suffix(".png")
            plot(report, png)
            print(f"wrote {png}")
        except ImportError as exc:  # matplotlib is optional
            print(f"plot skipped: {exc}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
