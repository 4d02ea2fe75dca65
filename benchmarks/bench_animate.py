"""`refnpr animate` throughput: frames per second serially vs on a Dask LocalCluster.

Usage::

    python benchmarks/bench_animate.py                 # 640x360, 16 frames, 2 workers, 5 runs
    python benchmarks/bench_animate.py --quick --json /tmp/a.json   # smoke run (tiny frames)

What is measured: a stateless sequence (``--scene``, default
``halftone_light_orbit``: the engraved teapot with contours under an orbiting light) rendered
into a fresh directory by :func:`refnpr.sequence.render_sequence` (one process, numba on all its
cores) and by :func:`refnpr.distributed.render_sequence` on a ``LocalCluster`` of ``--workers``
processes (one task at a time each, ``cores // workers`` numba threads each), files written as
``refnpr animate`` writes them. Runs alternate serial / distributed so that drift on a shared
machine hits both alike; each row is the median, minimum and maximum over ``--runs`` runs of
frames per second (frames / wall time of the call), and the ratio is taken per pair of side by
side runs (its median and range). The cluster is started once (its start-up time, and the first
distributed run that loads every worker's kernels, are reported apart and not in the medians);
one serial and one distributed warm-up run come first. Every distributed run's directory is
compared with the serial run's byte for byte (``identical`` in the JSON).

Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))


def _files(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def _stats(values: list[float]) -> dict[str, float]:
    return {
        "median": statistics.median(values),
        "min": min(values),
        "max": max(values),
        "runs": len(values),
    }


def run(args: argparse.Namespace, tmp: Path) -> dict:
    import numba

    from refnpr import __version__, distributed
    from refnpr.sequence import render_sequence

    width, height = args.size
    frames = f"0:{args.frames}"
    common = dict(frames=frames)
    counter = iter(range(10**6))

    def fresh() -> Path:
        return tmp / f"run{next(counter)}"

    def serial() -> tuple[float, Path]:
        out = fresh()
        t0 = time.perf_counter()
        render_sequence(args.scene, None, width, height, args.spp, out_dir=out, **common)
        return time.perf_counter() - t0, out

    print(f"serial warm-up ({args.scene} {width}x{height} spp {args.spp}, {frames}) ...")
    serial_warm, _ = serial()
    t0 = time.perf_counter()
    with distributed.open_client(workers=args.workers) as client:
        startup = time.perf_counter() - t0
        print(f"LocalCluster of {args.workers} workers started in {startup:.1f} s")

        def dist() -> tuple[float, Path]:
            out = fresh()
            t0 = time.perf_counter()
            distributed.render_sequence(
                args.scene, None, width, height, args.spp, out_dir=out, client=client, **common
            )
            return time.perf_counter() - t0, out

        first_dist, _ = dist()  # every worker loads (or compiles) its kernels here
        print(f"first distributed run (kernels loading on the workers): {first_dist:.2f} s")
        s_fps, d_fps, ratios, identical = [], [], [], True
        for i in range(args.runs):
            ts, out_s = serial()
            td, out_d = dist()
            same = _files(out_s) == _files(out_d)
            identical &= same
            s_fps.append(args.frames / ts)
            d_fps.append(args.frames / td)
            ratios.append(ts / td)
            print(
                f"run {i + 1}/{args.runs}: serial {args.frames / ts:6.2f} fps, "
                f"{args.workers} workers {args.frames / td:6.2f} fps, x{ts / td:.2f}, "
                f"identical bytes: {same}"
            )
    result = {
        "benchmark": "animate",
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "label": args.label,
        "refnpr": __version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "numba_threads_serial": numba.get_num_threads(),
        "numba_threads_per_worker": distributed.worker_threads(args.workers),
        "scene": args.scene,
        "size": [width, height],
        "spp": args.spp,
        "frames": args.frames,
        "workers": args.workers,
        "serial_fps": _stats(s_fps),
        "distributed_fps": _stats(d_fps),
        "speedup": _stats(ratios),
        "identical": identical,
        "cluster_startup_s": startup,
        "first_distributed_run_s": first_dist,
        "serial_warmup_run_s": serial_warm,
    }
    for key in ("serial_fps", "distributed_fps", "speedup"):
        r = result[key]
        print(f"{key:16s} median {r['median']:.2f} (min {r['min']:.2f}, max {r['max']:.2f})")
    print(f"identical bytes in every run: {identical}")
    return result


def _size(text: str) -> tuple[int, int]:
    w, h = (int(v) for v in text.lower().split("x"))
    return w, h


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="halftone_light_orbit", help="a stateless animated scene")
    p.add_argument("--size", type=_size, default=(640, 360), help="WxH (640x360)")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--frames", type=int, default=16, help="frames 0 .. N-1 (16)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--quick", action="store_true", help="smoke run: 64x36, 4 frames, 1 run")
    p.add_argument("--label", default="")
    p.add_argument("--json", default=str(HERE / "results" / "animate.json"))
    args = p.parse_args(argv)
    if args.quick:
        args.size, args.frames, args.runs = (64, 36), 4, 1
    tmp = Path(tempfile.mkdtemp(prefix="bench_animate_"))
    try:
        result = run(args, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    out = Path(args.json)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":  # the LocalCluster's worker processes re-import this file (spawn)
    sys.exit(main())
