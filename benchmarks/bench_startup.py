"""Cold start: what the first renders of a process cost on an empty numba cache, and which
kernels that time goes to.

Usage::

    python benchmarks/bench_startup.py --json benchmarks/results/startup.json
    python benchmarks/bench_startup.py --sections styles      # only the in-process style renders
    python benchmarks/bench_startup.py --sections cli         # only `refnpr render` (default scene)

Sections (``--sections``, comma separated; default both):

``styles``
    One fresh ``python`` process with ``NUMBA_CACHE_DIR`` set to an empty temporary directory
    renders, in this order, each style's benchmark scene (the rows of ``bench_frame.py``) at
    ``--size`` (default 480x270), first at spp 1 and then at spp 4 with the contour layer
    (``contours=True``). Each render's wall time is recorded; their sum is the target's "in total"
    (import excluded and reported apart). A numba event listener records every compilation
    (``numba:compile`` events: the dispatcher's qualified name and the wall time from start to
    end, nested compiles included in their caller's), so the table can say which kernels cost
    the most. The same process then repeats every render (warm, in memory) for comparison.
``cli``
    ``refnpr render -o <tmp>/x.png`` (the default scene at the command's default size) as a
    whole process with an empty ``NUMBA_CACHE_DIR`` (a fresh install: nothing compiled yet),
    then ``--cli-runs`` times with that cache filled.

Targets (printed MET / NOT MET, never asserted): the styles' first renders <= 20 s in total;
the first ``refnpr render`` in a fresh install <= 6 s.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from bench_frame import ROWS  # noqa: E402

TARGET_STYLES_S = 20.0
TARGET_CLI_S = 6.0

_CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
from numba.core import event

compiles = []


class _Listener(event.Listener):
    def __init__(self):
        self.starts = {}

    def on_start(self, ev):
        self.starts[id(ev.data["dispatcher"]), str(ev.data["args"])] = time.perf_counter()

    def on_end(self, ev):
        key = id(ev.data["dispatcher"]), str(ev.data["args"])
        start = self.starts.pop(key, None)
        if start is not None:
            d = ev.data["dispatcher"]
            f = getattr(d, "py_func", d)
            name = f"{f.__module__ or '?'}.{f.__qualname__}"
            compiles.append({"kernel": name, "args": str(ev.data["args"]),
                             "s": time.perf_counter() - start, "at": start})


event.register("numba:compile", _Listener())
import refnpr
from refnpr.render import render
t_import = time.perf_counter() - t0
rows = json.loads(sys.argv[1])
w, h = json.loads(sys.argv[2])
renders = []
for spp, contours in ((1, False), (4, True)):
    for scene, style in rows:
        spec = {"name": style, "contours": True} if contours else style
        t = time.perf_counter()
        render(scene, spec, w, h, spp)
        renders.append({"scene": scene, "style": style, "spp": spp, "contours": contours,
                        "cold_s": time.perf_counter() - t, "start": t})
for r in renders:
    spec = {"name": r["style"], "contours": True} if r["contours"] else r["style"]
    t = time.perf_counter()
    render(r["scene"], spec, w, h, r["spp"])
    r["warm_s"] = time.perf_counter() - t
# numba's cost for a kernel with next to no code (set-up already paid): the per-kernel floor
import numba
import numpy as np
trivial = []
n_compiles = len(compiles)
for i in range(3):
    ns = {"__name__": "bench_startup_trivial"}
    exec(f"def k{i}(a):\n    return a[0] + {i}", ns)
    f = numba.njit(cache=False, nogil=True, error_model="numpy")(ns[f"k{i}"])
    t = time.perf_counter()
    f(np.zeros(3))
    trivial.append(time.perf_counter() - t)
del compiles[n_compiles:]  # not the renders' compiles
print(json.dumps({"import_s": t_import, "renders": renders, "compiles": compiles,
                  "trivial_kernel_s": trivial}))
"""


def _env(cache_dir: str) -> dict:
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = cache_dir
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _outermost(compiles: list[dict]) -> list[dict]:
    """Compiles not nested inside another one (their times add up to the wall time spent)."""
    spans = sorted(compiles, key=lambda c: c["at"])
    out, end = [], -1.0
    for c in spans:
        if c["at"] >= end:
            out.append(c)
            end = c["at"] + c["s"]
    return out


def bench_styles(args) -> dict:
    cache = tempfile.mkdtemp(prefix="refnpr-cold-")
    try:
        t = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-c", _CHILD, json.dumps(ROWS), json.dumps(args.size)],
            env=_env(cache),
            cwd=str(ROOT),  # `-c` puts the working directory first on sys.path: this checkout's
            capture_output=True,
            text=True,
            check=False,
        )
        wall = time.perf_counter() - t
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    if proc.returncode != 0:
        raise SystemExit(f"child failed:\n{proc.stderr[-3000:]}")
    data = json.loads(proc.stdout.strip().splitlines()[-1])
    data["process_wall_s"] = wall
    data["total_first_renders_s"] = sum(r["cold_s"] for r in data["renders"])
    by_kernel: dict[str, dict] = {}
    for c in _outermost(data["compiles"]):
        k = by_kernel.setdefault(c["kernel"], {"kernel": c["kernel"], "s": 0.0, "n": 0})
        k["s"] += c["s"]
        k["n"] += 1
    data["kernels"] = sorted(by_kernel.values(), key=lambda k: -k["s"])
    outer = sorted(c["s"] for c in _outermost(data["compiles"]))
    data["outermost"] = {
        "n": len(outer),
        "min_s": outer[0] if outer else None,
        "median_s": statistics.median(outer) if outer else None,
        "target_mean_s": TARGET_STYLES_S / len(outer) if outer else None,
        "trivial_kernel_median_s": statistics.median(data["trivial_kernel_s"]),
    }
    data["specialisations"] = len(data["compiles"])
    data["compile_s"] = sum(k["s"] for k in data["kernels"])
    data["target"] = f"first renders in total <= {TARGET_STYLES_S} s"
    data["met"] = data["total_first_renders_s"] <= TARGET_STYLES_S
    return data


def bench_cli(args) -> dict:
    exe = shutil.which("refnpr", path=str(Path(sys.executable).parent)) or shutil.which("refnpr")
    if exe is None:
        return {"available": False, "reason": "no `refnpr` command next to this Python"}
    cache = tempfile.mkdtemp(prefix="refnpr-cold-cli-")
    out = tempfile.mkdtemp(prefix="refnpr-cli-out-")
    try:
        times = []
        for i in range(1 + args.cli_runs):
            t = time.perf_counter()
            proc = subprocess.run(
                [exe, "render", "-o", os.path.join(out, f"x{i}.png")],
                env=_env(cache),
                capture_output=True,
                text=True,
                check=False,
            )
            times.append(time.perf_counter() - t)
            if proc.returncode != 0:
                return {"available": False, "reason": proc.stderr[-2000:]}
    finally:
        shutil.rmtree(cache, ignore_errors=True)
        shutil.rmtree(out, ignore_errors=True)
    warm = times[1:]
    return {
        "available": True,
        "cold_s": times[0],
        "warm_median_s": statistics.median(warm) if warm else None,
        "warm_runs_s": warm,
        "target": f"first `refnpr render` in a fresh install <= {TARGET_CLI_S} s",
        "met": times[0] <= TARGET_CLI_S,
    }


def table(report: dict) -> str:
    lines = [
        f"refnpr cold start ({report['meta']['date']}, {report['meta']['cpus']} cpus, "
        f"load {report['meta']['load_avg_1min'][0]:.2f} -> {report['meta']['load_avg_1min'][1]:.2f})"
    ]
    st = report.get("styles")
    if st:
        w, h = report["meta"]["size"]
        lines.append(
            f"\nfirst render of each style in one process, empty numba cache, {w}x{h} "
            f"(import {st['import_s']:.2f} s, process {st['process_wall_s']:.1f} s)"
        )
        lines.append(
            f"{'scene / style':30s} {'spp':>3s} {'contours':>8s} {'cold s':>8s} {'warm s':>8s}"
        )
        for r in st["renders"]:
            lines.append(
                f"{r['scene'] + ' / ' + r['style']:30s} {r['spp']:3d} {str(r['contours']):>8s} "
                f"{r['cold_s']:8.2f} {r['warm_s']:8.3f}"
            )
        lines.append(
            f"total first renders {st['total_first_renders_s']:.1f} s "
            f"({st['target']}: {'MET' if st['met'] else 'NOT MET'}); "
            f"{st['specialisations']} compilations, {st['compile_s']:.1f} s of it compiling"
        )
        o = st.get("outermost")
        if o and o["n"]:
            lines.append(
                f"{o['n']} outermost compiles: smallest {o['min_s']:.2f} s, median "
                f"{o['median_s']:.2f} s; the target leaves {o['target_mean_s']:.2f} s each on "
                f"average; a kernel with next to no code compiles in "
                f"{o['trivial_kernel_median_s']:.3f} s"
            )
        lines.append("\nkernels by compile time (outermost compiles; n = specialisations)")
        for k in st["kernels"][: report["meta"]["top"]]:
            lines.append(f"  {k['s']:6.2f} s  n={k['n']:2d}  {k['kernel']}")
    cli = report.get("cli")
    if cli:
        if not cli["available"]:
            lines.append(f"\nrefnpr render: not available: {cli['reason']}")
        else:
            lines.append(
                f"\n`refnpr render -o x.png` (default scene): fresh install (empty cache) "
                f"{cli['cold_s']:.2f} s, cached median {cli['warm_median_s']:.2f} s "
                f"({cli['target']}: {'MET' if cli['met'] else 'NOT MET'})"
            )
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", default="480x270")
    p.add_argument("--sections", default="styles,cli")
    p.add_argument("--cli-runs", type=int, default=3)
    p.add_argument("--top", type=int, default=15, help="kernels listed (default 15)")
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    args.size = [int(v) for v in args.size.lower().split("x")]
    sections = [s for s in args.sections.split(",") if s]
    unknown = sorted(set(sections) - {"styles", "cli"})
    if unknown:
        p.error(f"--sections: unknown {unknown}; choose from styles, cli")
    load0 = os.getloadavg()[0]
    report: dict = {}
    if "styles" in sections:
        report["styles"] = bench_styles(args)
    if "cli" in sections:
        report["cli"] = bench_cli(args)
    report["meta"] = {
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "machine": platform.platform(),
        "cpus": os.cpu_count(),
        "size": args.size,
        "top": args.top,
        "load_avg_1min": [load0, os.getloadavg()[0]],
    }
    print(table(report))
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
