"""Whole-frame benchmark (issue 11, target 1): ``render()`` at 1920x1080 per scene/style, spp 1
and spp 4, with the phase breakdown from ``img.timings`` and the ratio total / rasterize.

Usage::

    python benchmarks/bench_frame.py --runs 5 --json benchmarks/results/frame.json
    python benchmarks/bench_frame.py --quick --json /tmp/frame.json      # 480x270, 3 runs
    python benchmarks/bench_frame.py --context                           # also a RenderContext

Each (scene, style, spp) is rendered once as a warm-up (numba cache load, texture pyramids,
memoized meshes), then ``--runs`` times; medians are quoted with min-max. Every row of one spp
is timed in turn before the next run, so drift on a shared machine hits all rows alike. With
``--context`` each row is also timed through ``refnpr.render.RenderContext`` (buffers reused
between frames), beside ``render()``. Targets (issue 11) are printed as MET / NOT MET against
total / rasterize: 2x toon, smooth, xtoon; 3x threshold, halftone; 4x tam; tamiss <= 1.5x the
tam frame (same scene, same spp). Nothing here asserts a time.
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

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

#: (scene, style) rows of the issue's table; "teapot" is the old default scene.
ROWS = (
    ("teapot", "toon"),
    ("teapot", "smooth"),
    ("xtoon_teapot", "xtoon"),
    ("veryovka_plane", "threshold"),
    ("halftone_teapot", "halftone"),
    ("tamiss_teapot", "tam"),
    ("tamiss_teapot", "tamiss"),
)
#: Target on total / rasterize per style (tamiss: on total / tam's total).
TARGET = {"toon": 2.0, "smooth": 2.0, "xtoon": 2.0, "threshold": 3.0, "halftone": 3.0, "tam": 4.0}
TAMISS_OVER_TAM = 1.5
PHASES = ("rasterize", "shade", "resolve", "total")


def _stats(values: list[float]) -> dict:
    return {
        "median_s": statistics.median(values),
        "min_s": min(values),
        "max_s": max(values),
        "runs_s": list(values),
    }


def run(args) -> dict:
    from refnpr.render import render

    width, height = args.size
    load_start = os.getloadavg()[0]
    ctx_cls = None
    if args.context:
        from refnpr.render import RenderContext as ctx_cls
    rows = ROWS
    if args.styles:
        wanted = set(args.styles)
        if "tamiss" in wanted:
            wanted.add("tam")  # tamiss's target is relative to tam's frame
        rows = tuple(r for r in ROWS if r[1] in wanted)
    results = []
    for spp in args.spp:
        contexts = {}
        # warm-up: one untimed frame per row (and per context)
        for scene, style in rows:
            render(scene, style, width, height, spp)
            if ctx_cls is not None:
                c = ctx_cls(scene, style, width, height, spp)
                c.render()
                contexts[(scene, style)] = c
        runs = {(s, st, k): [] for s, st in rows for k in ("render", "context")}
        for _ in range(args.runs):
            for scene, style in rows:
                img = render(scene, style, width, height, spp)
                runs[(scene, style, "render")].append(dict(img.timings))
                if ctx_cls is not None:
                    img = contexts[(scene, style)].render()
                    runs[(scene, style, "context")].append(dict(img.timings))
        for (scene, style, kind), timings in runs.items():
            if not timings:
                continue
            row = {"scene": scene, "style": style, "spp": spp, "engine": kind}
            for ph in PHASES:
                row[ph] = _stats([t[ph] for t in timings])
            row["ratio"] = row["total"]["median_s"] / row["rasterize"]["median_s"]
            results.append(row)
    # targets
    for row in results:
        if row["style"] == "tamiss":
            tam = next(
                r
                for r in results
                if r["style"] == "tam" and r["spp"] == row["spp"] and r["engine"] == row["engine"]
            )
            row["vs_tam"] = row["total"]["median_s"] / tam["total"]["median_s"]
            row["target"] = f"<= {TAMISS_OVER_TAM}x tam"
            row["met"] = row["vs_tam"] <= TAMISS_OVER_TAM
        else:
            row["target"] = f"<= {TARGET[row['style']]}x rasterize"
            row["met"] = row["ratio"] <= TARGET[row["style"]]
    return {
        "meta": {
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "machine": platform.platform(),
            "cpus": os.cpu_count(),
            "numba_threads": _threads(),
            "size": [width, height],
            "runs": args.runs,
            "label": args.label,
            "load_avg_1min": [load_start, os.getloadavg()[0]],
        },
        "rows": results,
    }


def numpy_composite_resolve(rgba, n, background):
    """What render() ran before the fused kernel (issue 11), verbatim: the side-by-side peer."""
    import numpy as np

    from refnpr.raster.gbuffer import box_resolve

    bg = np.asarray(background, dtype=np.float64)
    a = rgba[..., 3:4].astype(np.float64)
    premult = np.concatenate([rgba[..., :3] * a, a], axis=-1)
    bg_premult = np.concatenate([bg[:3] * bg[3], bg[3:4]])
    over = premult + bg_premult * (1.0 - a)
    res = box_resolve(over, n)
    alpha = res[..., 3:4]
    rgb = np.divide(res[..., :3], alpha, out=np.zeros_like(res[..., :3]), where=alpha > 0)
    return np.concatenate([rgb, alpha], axis=-1).astype(np.float32)


def run_resolve(args) -> list[dict]:
    """Composite + resolve alone: the numpy code it replaced vs the fused kernel (fresh output
    and ``out=``), alternating in one process on random samples, per spp."""
    import numpy as np

    from refnpr.render import composite_resolve

    width, height = args.size
    bg = (0.2, 0.3, 0.4, 1.0)
    rng = np.random.default_rng(0)
    rows = []
    for spp in args.spp:
        n = int(round(spp**0.5))
        rgba = rng.random((height * n, width * n, 4), dtype=np.float32)
        rgba[..., 3][rng.random((height * n, width * n)) < 0.3] = 0.0
        out = np.empty((height, width, 4), np.float32)
        want = numpy_composite_resolve(rgba, n, bg)
        same = bool(
            np.array_equal(composite_resolve(rgba, n, bg).view(np.uint32), want.view(np.uint32))
        )
        fns = {
            "numpy": lambda x=rgba, n=n: numpy_composite_resolve(x, n, bg),
            "fused": lambda x=rgba, n=n: composite_resolve(x, n, bg),
            "fused_out": lambda x=rgba, n=n, o=out: composite_resolve(x, n, bg, out=o),
        }
        times = {k: [] for k in fns}
        for _ in range(max(args.runs, 5)):
            for k, f in fns.items():
                t0 = time.perf_counter()
                f()
                times[k].append(time.perf_counter() - t0)
        row = {"spp": spp, "bit_identical": same, **{k: _stats(v) for k, v in times.items()}}
        row["speedup"] = row["numpy"]["median_s"] / row["fused"]["median_s"]
        row["speedup_out"] = row["numpy"]["median_s"] / row["fused_out"]["median_s"]
        rows.append(row)
    return rows


def resolve_table(rows: list[dict]) -> str:
    lines = ["composite + resolve alone (ms, median [min-max]; same process, alternating)"]
    for r in rows:
        parts = [
            f"{k} {r[k]['median_s'] * 1e3:.1f} [{r[k]['min_s'] * 1e3:.1f}-{r[k]['max_s'] * 1e3:.1f}]"
            for k in ("numpy", "fused", "fused_out")
        ]
        lines.append(
            f"  spp {r['spp']}: " + ", ".join(parts) + f"; numpy/fused {r['speedup']:.1f}x, "
            f"numpy/fused_out {r['speedup_out']:.1f}x; bit-identical: {r['bit_identical']}"
        )
    return "\n".join(lines)


def _threads() -> int:
    import numba

    return numba.get_num_threads()


def table(report: dict) -> str:
    m = report["meta"]
    w, h = m["size"]
    lines = [
        f"refnpr whole-frame benchmark ({m['date']}, {m['cpus']} cpus, numba {m['numba_threads']}"
        f" threads) {m['label'] or ''}",
        f"1-min load average: {m['load_avg_1min'][0]:.2f} at start, "
        f"{m['load_avg_1min'][1]:.2f} at end (a ratio is only as good as its rasterize time)",
        f"render() at {w}x{h}, median of {m['runs']} runs (ms; min-max in brackets)",
        f"{'scene / style':30s} {'spp':>3s} {'engine':8s} {'total':>22s} {'rasterize':>10s} "
        f"{'shade':>8s} {'resolve':>8s} {'ratio':>6s}  target",
    ]
    for r in report["rows"]:
        tot = r["total"]
        extra = f" ({r['vs_tam']:.2f}x tam)" if "vs_tam" in r else ""
        lines.append(
            f"{r['scene'] + ' / ' + r['style']:30s} {r['spp']:3d} {r['engine']:8s} "
            f"{tot['median_s'] * 1e3:8.1f} [{tot['min_s'] * 1e3:5.0f}-{tot['max_s'] * 1e3:5.0f}] "
            f"{r['rasterize']['median_s'] * 1e3:10.1f} {r['shade']['median_s'] * 1e3:8.1f} "
            f"{r['resolve']['median_s'] * 1e3:8.1f} {r['ratio']:6.1f}  {r['target']}{extra}: "
            f"{'MET' if r['met'] else 'NOT MET'}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--spp", default="1,4", help="comma-separated sample counts")
    p.add_argument("--quick", action="store_true", help="480x270, 3 runs")
    p.add_argument("--context", action="store_true", help="also time a RenderContext per row")
    p.add_argument(
        "--sections", default="frame,resolve", help="frame (render per style), resolve (alone)"
    )
    p.add_argument(
        "--styles", default="", help="comma-separated styles to time (default: every row)"
    )
    p.add_argument("--label", default="", help="free text stored in the JSON (before/after)")
    p.add_argument("--json", default=None, help="write the report here")
    args = p.parse_args(argv)
    if args.quick:
        args.size, args.runs = "480x270", 3
    args.size = tuple(int(v) for v in args.size.lower().split("x"))
    args.spp = [int(v) for v in args.spp.split(",")]
    known = {style for _, style in ROWS}
    args.styles = [v for v in args.styles.split(",") if v]
    unknown = sorted(set(args.styles) - known)
    if unknown:
        p.error(f"--styles: unknown {unknown}; choose from {sorted(known)}")
    sections = set(args.sections.split(","))
    report = run(args) if "frame" in sections else {"meta": {"label": args.label}, "rows": []}
    if "frame" in sections:
        print(table(report))
    if "resolve" in sections:
        report["resolve"] = run_resolve(args)
        print(resolve_table(report["resolve"]))
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
