"""X-Toon benchmark: frame time of refnpr's X-Toon style against its own toon style (Barla et al.
2006, Table 1 reports X-Toon at ~1.2x the frame time of toon shading), and the difference between
the per-vertex (the paper's GPU implementation) and per-pixel (exact) detail.

Usage::

    python benchmarks/bench_xtoon.py --runs 7 --json benchmarks/results/xtoon.json
    python benchmarks/bench_xtoon.py --quick --json /tmp/xtoon.json     # smoke run, seconds

Sections (``--sections``, comma separated; default both):

``speed``
    ``refnpr.render.render(scene, style, W, H)`` wall time (rasterize + shade + resolve, everything
    the renderer does for a frame) for the toon style (``toon``: the default two-tone step with its
    specular term; ``toon-diffuse``: ``specular=False``) and four X-Toon configurations, on the
    scenes ``xtoon_teapot`` (the teapot, ~6k triangles), ``xtoon_row`` (five teapots, ~32k) and
    ``xtoon_terrain`` (~74k) at 640x480 and 1280x960. Each run renders every style once in turn
    (so drift hits all alike); the first frame of each (scene, size, style) is a warm-up and is not
    timed. Medians are quoted, with the shade phase alone, and the ratio X-Toon / toon (frame time:
    the paper's fps ratio toon / X-Toon).
``accuracy``
    per-vertex vs per-pixel detail at 640x480: |D_vertex - D_pixel| over covered samples (max,
    mean, 99th percentile) and the 8-bit sRGB image difference (max, fraction of pixels that differ
    by more than 2/255), for the depth map on each scene and the near-silhouette and flow maps.

Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SCENES = ("xtoon_teapot", "xtoon_row", "xtoon_terrain")
SIZES = ((640, 480), (1280, 960))
#: depth range (z_min, r) per scene for the depth map
DEPTH = {"xtoon_teapot": (11.0, 1.6), "xtoon_row": (18.0, 3.0), "xtoon_terrain": (16.0, 6.0)}
PREV_EYE = {"xtoon_teapot": 1.5, "xtoon_row": 2.0, "xtoon_terrain": 1.0}  # orbit degrees


def styles_for(scene_name: str) -> dict[str, dict]:
    z_min, r = DEPTH[scene_name]
    depth = {"name": "xtoon", "texture": "loa_receding", "detail": "depth", "z_min": z_min, "r": r}
    return {
        "toon": {"name": "toon"},
        "toon-diffuse": {"name": "toon", "specular": False},
        "xtoon-depth": depth,
        "xtoon-depth-vertex": {**depth, "detail_mode": "vertex"},
        "xtoon-orientation": {
            "name": "xtoon",
            "texture": "silhouette_fade",
            "detail": "orientation",
        },
        "xtoon-depth+sphere": {**depth, "shape": "sphere", "shape_weight": 0.5},
    }


def _median(xs: list[float]) -> float:
    return float(statistics.median(xs))


def speed(scenes, sizes, runs: int, log) -> list[dict]:
    from refnpr.render import render, required_channels
    from refnpr.scenes import load_scene
    from refnpr.styles import style_from_spec

    rows = []
    for scene_name in scenes:
        scene = load_scene(scene_name)
        tris = sum(m.n_faces for m in scene.world_meshes())
        styles = {k: style_from_spec(v) for k, v in styles_for(scene_name).items()}
        for w, h in sizes:
            times = {k: [] for k in styles}
            shade = {k: [] for k in styles}
            for style in styles.values():
                render(scene, style, w, h)  # warm-up (numba cache load, first allocation)
            for _ in range(runs):
                for key, style in styles.items():
                    img = render(scene, style, w, h)
                    times[key].append(img.timings["total"])
                    shade[key].append(img.timings["shade"])
            base = _median(times["toon"])
            base_d = _median(times["toon-diffuse"])
            for key, style in styles.items():
                row = {
                    "scene": scene_name,
                    "triangles": tris,
                    "size": f"{w}x{h}",
                    "style": key,
                    "params": styles_for(scene_name)[key],
                    "channels": sorted(required_channels(scene, style)),
                    "median_s": _median(times[key]),
                    "shade_median_s": _median(shade[key]),
                    "runs_s": times[key],
                    "ratio_vs_toon": _median(times[key]) / base,
                    "ratio_vs_toon_diffuse": _median(times[key]) / base_d,
                }
                rows.append(row)
                log(
                    f"{scene_name:14s} {w}x{h:<5d} {key:20s} {row['median_s'] * 1e3:8.1f} ms "
                    f"(shade {row['shade_median_s'] * 1e3:7.1f})  x{row['ratio_vs_toon']:.2f} toon  "
                    f"x{row['ratio_vs_toon_diffuse']:.2f} toon-diffuse"
                )
    return rows


def _d_and_image(scene, spec, w, h):
    from refnpr.raster import rasterize
    from refnpr.render import render
    from refnpr.styles import style_from_spec
    from refnpr.styles.base import ShadeContext

    style = style_from_spec(spec)
    gb = rasterize(scene, scene.camera, w, h, sorted(style.requires(scene)))
    d = style.fields(ShadeContext(gb, scene))["detail"]
    return d, render(scene, style, w, h).to_srgb8()


def accuracy(scenes, size, log) -> list[dict]:
    from refnpr.scenes import load_scene

    w, h = size
    rows = []
    cases = []
    for scene_name in scenes:
        cases.append((scene_name, "depth", styles_for(scene_name)["xtoon-depth"]))
    cases.append(
        (
            "xtoon_teapot",
            "orientation",
            {"name": "xtoon", "detail": "orientation", "r": 1.0, "texture": "silhouette_blur"},
        )
    )
    for scene_name in ("xtoon_row",):
        scene = load_scene(scene_name)
        prev = scene.camera.orbit(azimuth_deg=-PREV_EYE[scene_name])
        cases.append(
            (
                scene_name,
                "flow",
                {
                    "name": "xtoon",
                    "detail": "flow",
                    "texture": "loa_receding",
                    "flow_min": 1.0,
                    "flow_max": 10.0,
                    "prev_camera": prev,
                },
            )
        )
    for scene_name, kind, spec in cases:
        if scene_name not in scenes:
            continue
        scene = load_scene(scene_name)
        d_p, img_p = _d_and_image(scene, {**spec, "detail_mode": "pixel"}, w, h)
        d_v, img_v = _d_and_image(scene, {**spec, "detail_mode": "vertex"}, w, h)
        ok = np.isfinite(d_p)
        diff = np.abs(d_p[ok].astype(np.float64) - d_v[ok])
        img = np.abs(img_p[..., :3].astype(int) - img_v[..., :3].astype(int)).max(axis=-1)
        row = {
            "scene": scene_name,
            "detail": kind,
            "size": f"{w}x{h}",
            "samples": int(ok.sum()),
            "d_max_abs_diff": float(diff.max()),
            "d_mean_abs_diff": float(diff.mean()),
            "d_p99_abs_diff": float(np.quantile(diff, 0.99)),
            "image_max_diff_8bit": int(img.max()),
            "image_frac_pixels_over_2": float(np.mean(img > 2)),
        }
        rows.append(row)
        log(
            f"{scene_name:14s} {kind:12s} |dD| max {row['d_max_abs_diff']:.4f} mean "
            f"{row['d_mean_abs_diff']:.5f} p99 {row['d_p99_abs_diff']:.4f}; image max "
            f"{row['image_max_diff_8bit']}/255, {row['image_frac_pixels_over_2']:.2%} of pixels > 2/255"
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--quick", action="store_true", help="160x120 and 320x240, 2 runs, teapot only")
    ap.add_argument("--sections", default="speed,accuracy")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--json", type=Path, default=HERE / "results" / "xtoon.json")
    args = ap.parse_args(argv)
    sections = set(args.sections.split(","))
    scenes = tuple(args.scenes.split(","))
    sizes, runs, acc_size = SIZES, args.runs, (640, 480)
    if args.quick:
        sizes, runs, acc_size, scenes = ((160, 120), (320, 240)), 2, (160, 120), ("xtoon_teapot",)
    lines: list[str] = []

    def log(text: str) -> None:
        print(text, flush=True)
        lines.append(text)

    report = {
        "meta": {
            "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "python": sys.version.split()[0],
            "machine": platform.machine(),
            "cpus": os.cpu_count(),
            "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
            "runs": runs,
            "command": " ".join(
                [Path(sys.argv[0]).name, *(argv if argv is not None else sys.argv[1:])]
            ),
        },
        "speed": [],
        "accuracy": [],
    }
    if "speed" in sections:
        log(f"render() frame time, median of {runs} runs (ratio = style / toon)")
        report["speed"] = speed(scenes, sizes, runs, log)
    if "accuracy" in sections:
        log(f"per-vertex vs per-pixel detail at {acc_size[0]}x{acc_size[1]}")
        report["accuracy"] = accuracy(scenes, acc_size, log)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=1, default=str))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
