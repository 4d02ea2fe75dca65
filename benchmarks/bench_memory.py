"""Peak memory of a render against the bytes of the buffers it needs (target: growth <= 2x).

Usage::

    python benchmarks/bench_memory.py --json benchmarks/results/memory.json
    python benchmarks/bench_memory.py --size 960x540 --spp 4          # a smaller run

Each row runs in a fresh ``python`` process (so the high-water mark is the row's own): it renders
the scene once at 64x36 (imports, numba cache loads, code pages: the process's baseline), reads
its resident set (``/proc/self/statm``), renders at ``--size`` / ``--spp`` (default 1920x1080,
spp 16, the default scene with its own style) with ``return_gbuffer=True``, and reads the peak
resident set (``getrusage(RUSAGE_SELF).ru_maxrss``, the kernel's high-water mark, which also
sees allocations numpy's tracemalloc hooks miss: numba's, the page cache of mapped files).

*Needed* is what the frame cannot do without: the G-buffer the style asked for (its channels at
their dtypes, ``GBuffer.nbytes()``), the style's per-sample straight-alpha RGBA (float32, 16 B a
sample) and the resolved image (float32 RGBA, 16 B a pixel). Reported: peak RSS, baseline, the
render's growth (peak - baseline), needed, and both ratios; the target is on the growth
(``peak - baseline <= 2 x needed``), with the whole-process ratio printed beside it.
Nothing here asserts anything.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TARGET = 2.0

_CHILD = r"""
import json, os, resource, sys, time
from refnpr.render import render

scene, style, w, h, spp = json.loads(sys.argv[1])
style = style or None
render(scene, style, 64, 36, spp)
page = os.sysconf("SC_PAGE_SIZE")
with open("/proc/self/statm") as f:
    base = int(f.read().split()[1]) * page
t = time.perf_counter()
img, gb = render(scene, style, w, h, spp, return_gbuffer=True)
wall = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
samples = gb.sample_shape[0] * gb.sample_shape[1]
print(json.dumps({
    "baseline_bytes": base, "peak_bytes": peak, "gbuffer_bytes": gb.nbytes(),
    "rgba_bytes": 16 * samples, "image_bytes": int(img.rgba.nbytes), "wall_s": wall,
    "channels": sorted(gb.channels) if hasattr(gb, "channels") else None,
}))
"""


def run_row(scene: str, style: str, size: tuple[int, int], spp: int) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, json.dumps([scene, style, *size, spp])],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        return {"scene": scene, "style": style, "error": proc.stderr[-2000:]}
    row = json.loads(proc.stdout.strip().splitlines()[-1])
    row.update(scene=scene, style=style or "(scene's)", size=list(size), spp=spp)
    row["needed_bytes"] = row["gbuffer_bytes"] + row["rgba_bytes"] + row["image_bytes"]
    row["growth_bytes"] = row["peak_bytes"] - row["baseline_bytes"]
    row["ratio_growth"] = row["growth_bytes"] / row["needed_bytes"]
    row["ratio_process"] = row["peak_bytes"] / row["needed_bytes"]
    row["target"] = f"peak - baseline <= {TARGET} x needed"
    row["met"] = row["ratio_growth"] <= TARGET
    return row


def _mb(n: float) -> str:
    return f"{n / 2**20:8.0f}"


def table(report: dict) -> str:
    lines = [
        f"refnpr peak memory ({report['meta']['date']}, {report['meta']['cpus']} cpus); MiB",
        f"{'scene / style':28s} {'size':>10s} {'spp':>3s} {'gbuffer':>8s} {'needed':>8s} "
        f"{'baseline':>8s} {'peak':>8s} {'growth':>8s} {'grow/need':>9s} {'peak/need':>9s}  target",
    ]
    for r in report["rows"]:
        if "error" in r:
            lines.append(f"{r['scene']} / {r['style']}: failed: {r['error'][-300:]}")
            continue
        lines.append(
            f"{r['scene'] + ' / ' + r['style']:28s} {'x'.join(map(str, r['size'])):>10s} "
            f"{r['spp']:3d} {_mb(r['gbuffer_bytes'])} {_mb(r['needed_bytes'])} "
            f"{_mb(r['baseline_bytes'])} {_mb(r['peak_bytes'])} {_mb(r['growth_bytes'])} "
            f"{r['ratio_growth']:9.2f} {r['ratio_process']:9.2f}  "
            f"{r['target']}: {'MET' if r['met'] else 'NOT MET'}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument(
        "--rows",
        default="default:",
        help="comma-separated scene:style pairs (empty style: the scene's own); default 'default:'",
    )
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    rows = []
    for item in args.rows.split(","):
        scene, _, style = item.partition(":")
        rows.append(run_row(scene, style, size, args.spp))
    report = {
        "meta": {
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "machine": platform.platform(),
            "cpus": os.cpu_count(),
        },
        "rows": rows,
    }
    print(table(report))
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
