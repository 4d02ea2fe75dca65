"""Whole-frame benchmark: ``render()`` at 1920x1080 per scene/style, spp 1 and spp 4, with the
phase breakdown from ``img.timings`` and the ratio total / rasterize; or an A/B of two checkouts.

Usage::

    python benchmarks/bench_frame.py --runs 5 --json benchmarks/results/frame.json
    python benchmarks/bench_frame.py --quick --json /tmp/frame.json      # 480x270, 3 runs
    python benchmarks/bench_frame.py --context                           # also a RenderContext
    python benchmarks/bench_frame.py --baseline ../base --json /tmp/ab.json   # A/B, two checkouts

Each (scene, style, spp) is rendered once as a warm-up (numba cache load, texture pyramids,
memoized meshes), then ``--runs`` times; medians are quoted with min-max. Every row of one spp
is timed in turn before the next run, so drift on a shared machine hits all rows alike. With
``--context`` each row is also timed through ``refnpr.render.RenderContext`` (buffers reused
between frames), beside ``render()``.

Targets, printed as MET / NOT MET against total / rasterize (how much the style adds on top of
producing its G-buffer): at most 2x for toon, smooth and xtoon; 3x for threshold and halftone; 4x
for tam; and the tamiss frame at most 1.5x the tam frame (same scene, same spp, same engine).

``--baseline DIR`` (A/B mode) times the same rows for another checkout of the project (``DIR``,
holding ``refnpr/``) and for this one in one run. Each side is its own child ``python`` process
(this interpreter) started with ``PYTHONPATH=<checkout>`` and that checkout as its working
directory, with setuptools' editable-install finder for refnpr removed; the child reports which
``refnpr/__init__.py`` it imported (printed, and refused if it is not the checkout's own) and,
after its warm-up, any ``refnpr`` module loaded from elsewhere (refused too). Both children warm
up, then take turns, one round each (every row once), the order flipping every round (baseline,
current, current, baseline, ...), so drift on a shared machine hits both alike and only one side
runs at a time. Per (scene, style, spp, engine): the wall time of the ``render()`` call in each
side, median with min-max, the ratio current / baseline of the medians and the median of the
per-round ratios; rows whose ratio exceeds ``--flag-above`` (default 1.05) are flagged. The
baseline child writes no bytecode and keeps its numba cache in ``NUMBA_CACHE_DIR`` (default
``~/.cache/refnpr-bench/numba``; numba keys that cache by each source folder's full path, so
checkouts do not collide): the baseline checkout is only read. Its first warm-up may therefore
compile every kernel (not timed).

Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: (scene, style) rows: each style on its benchmark scene; "teapot" is the old default scene.
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
    rows = _selected_rows(args)
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
    """What render() ran before the fused composite + resolve kernel, verbatim: the peer."""
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


# ---------------------------------------------------------------------------------------------
# A/B mode: two checkouts, each in its own child process, taking turns
# ---------------------------------------------------------------------------------------------
AB_PREFIX = "BENCH-AB "
#: Loads this file as a module (without putting its folder or this checkout on sys.path) and
#: runs the worker: the child's refnpr comes from its PYTHONPATH / working directory only.
AB_BOOT = (
    "import importlib.util, sys\n"
    "spec = importlib.util.spec_from_file_location('bench_frame_ab_worker', sys.argv[1])\n"
    "mod = importlib.util.module_from_spec(spec)\n"
    "spec.loader.exec_module(mod)\n"
    "mod.ab_worker()\n"
)


def _ab_send(msg: dict) -> None:
    sys.stdout.write(AB_PREFIX + json.dumps(msg) + "\n")
    sys.stdout.flush()


def _timed(fn) -> dict:
    t0 = time.perf_counter()
    img = fn()
    wall = time.perf_counter() - t0
    timings = {k: float(v) for k, v in dict(getattr(img, "timings", {}) or {}).items()}
    return {"wall_s": wall, "timings": timings}


def _drop_editable_finders(package: str) -> None:
    """Remove setuptools' editable-install finders that map ``package`` to another checkout:
    they resolve a submodule missing from this checkout to that one's file."""
    keep = []
    for finder in sys.meta_path:
        mod = sys.modules.get(getattr(finder, "__module__", ""), None)
        if package not in getattr(mod, "MAPPING", {}):
            keep.append(finder)
    sys.meta_path[:] = keep


def _foreign_modules(package_dir: Path) -> list[str]:
    """Loaded ``refnpr`` modules whose file is not under ``package_dir``."""
    out = []
    for name, mod in list(sys.modules.items()):
        if name != "refnpr" and not name.startswith("refnpr."):
            continue
        f = getattr(mod, "__file__", None)
        if f is not None and package_dir not in Path(f).resolve().parents:
            out.append(f"{name}: {f}")
    return out


def ab_worker() -> None:
    """The child of ``--baseline``: imports refnpr from its own checkout, then answers the
    parent's commands (one JSON line each on stdin): ``setup`` (spp: warm-up frames, contexts),
    ``round`` (every row once, timed), ``quit``. Replies are ``BENCH-AB {json}`` lines on stdout,
    so that anything else printed there is ignored."""
    try:
        _drop_editable_finders("refnpr")
        t0 = time.perf_counter()
        import refnpr
        from refnpr.render import render

        package_dir = Path(refnpr.__file__).resolve().parent

        _ab_send(
            {
                "hello": {
                    "refnpr_file": str(Path(refnpr.__file__).resolve()),
                    "cwd": os.getcwd(),
                    "python": sys.executable,
                    "pythonpath": os.environ.get("PYTHONPATH", ""),
                    "numba_threads": _threads(),
                    "numba_cache_dir": os.environ.get("NUMBA_CACHE_DIR", ""),
                    "import_s": time.perf_counter() - t0,
                }
            }
        )
        cfg = json.loads(sys.stdin.readline())
        width, height = cfg["size"]
        rows = [tuple(r) for r in cfg["rows"]]
        ctx_cls = None
        if cfg["context"]:
            from refnpr.render import RenderContext as ctx_cls
        spp, contexts = None, {}
        for line in sys.stdin:
            cmd = json.loads(line)
            if cmd["cmd"] == "setup":
                spp, contexts = cmd["spp"], {}
                t0 = time.perf_counter()
                for scene, style in rows:  # warm-up: one untimed frame per row (and context)
                    render(scene, style, width, height, spp)
                    if ctx_cls is not None:
                        c = ctx_cls(scene, style, width, height, spp)
                        c.render()
                        contexts[(scene, style)] = c
                ready = {"spp": spp, "warmup_s": time.perf_counter() - t0}
                ready["foreign_modules"] = _foreign_modules(package_dir)
                _ab_send({"ready": ready})
            elif cmd["cmd"] == "round":
                out = []
                for scene, style in rows:
                    rec = _timed(lambda s=scene, st=style, n=spp: render(s, st, width, height, n))
                    out.append({"scene": scene, "style": style, "engine": "render", **rec})
                    if ctx_cls is not None:
                        rec = _timed(contexts[(scene, style)].render)
                        out.append({"scene": scene, "style": style, "engine": "context", **rec})
                _ab_send({"round": out})
            else:
                break
    except BaseException:  # noqa: BLE001 - reported to the parent, which stops the run
        _ab_send({"error": traceback.format_exc()})
        raise SystemExit(1) from None


def _git_describe(path: Path) -> str:
    def git(*args: str) -> str:
        cmd = ["git", "-C", str(path), *args]
        return subprocess.run(cmd, capture_output=True, text=True, timeout=30).stdout.strip()

    try:
        head = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError):
        return "not a git checkout"
    if not head:
        return "not a git checkout"
    return head + (" + uncommitted changes" if dirty else "")


class _ABChild:
    """One side of the A/B: a child process importing ``refnpr`` from ``checkout``."""

    def __init__(self, name: str, checkout: Path, env_extra: dict[str, str]):
        self.name, self.checkout = name, checkout
        env = dict(os.environ)
        env["PYTHONPATH"] = str(checkout)
        env.update(env_extra)
        self.stderr = tempfile.TemporaryFile(mode="w+")
        self.proc = subprocess.Popen(
            [sys.executable, "-c", AB_BOOT, str(Path(__file__).resolve())],
            cwd=str(checkout),
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            text=True,
            bufsize=1,
        )
        try:
            self.hello = self.recv("hello")
        except BaseException:
            self.close()
            raise
        want = (checkout / "refnpr").resolve()
        got = Path(self.hello["refnpr_file"])
        if got.parent != want:
            self.close()
            raise RuntimeError(
                f"{name}: the child imported {got}, not {want / '__init__.py'} "
                "(is refnpr/ in that checkout? is PYTHONPATH overridden?)"
            )

    def send(self, msg: dict) -> None:
        self.proc.stdin.write(json.dumps(msg) + "\n")
        self.proc.stdin.flush()

    def recv(self, key: str) -> dict:
        while True:
            line = self.proc.stdout.readline()
            if not line:
                self.proc.wait()
                self.stderr.seek(0)
                tail = self.stderr.read().strip().splitlines()[-15:]
                raise RuntimeError(
                    f"{self.name} child exited ({self.proc.returncode}):\n  " + "\n  ".join(tail)
                )
            if not line.startswith(AB_PREFIX):
                continue  # the library's own prints
            msg = json.loads(line[len(AB_PREFIX) :])
            if "error" in msg:
                raise RuntimeError(f"{self.name} child failed:\n{msg['error']}")
            if key in msg:
                return msg[key]

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                self.send({"cmd": "quit"})
                self.proc.wait(timeout=60)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait()
        self.stderr.close()


def run_ab(args) -> dict:
    """Both checkouts' frames, alternating round by round (module docstring, A/B mode)."""
    width, height = args.size
    current = HERE.parent.resolve()
    baseline = Path(args.baseline).expanduser().resolve()
    if not (baseline / "refnpr" / "__init__.py").is_file():
        raise SystemExit(f"--baseline: {baseline} holds no refnpr/__init__.py")
    rows = _selected_rows(args)
    cache = os.environ.get("NUMBA_CACHE_DIR") or str(Path.home() / ".cache/refnpr-bench/numba")
    base_env = {"PYTHONDONTWRITEBYTECODE": "1", "NUMBA_CACHE_DIR": cache}
    load_start = os.getloadavg()[0]
    children: dict[str, _ABChild] = {}
    info: dict[str, dict] = {}
    try:
        for name, path, extra in (
            ("baseline", baseline, base_env),
            ("current", current, {}),
        ):
            children[name] = child = _ABChild(name, path, extra)
            info[name] = {
                "checkout": str(path),
                "git": _git_describe(path),
                **child.hello,
                "warmup_s": {},
            }
            print(
                f"{name:8s}: {path} ({info[name]['git']}) -> imports {child.hello['refnpr_file']}"
                f"; numba {child.hello['numba_threads']} threads",
                flush=True,
            )
        for child in children.values():
            child.send({"size": [width, height], "rows": rows, "context": bool(args.context)})
        samples: dict[tuple, dict[str, list[dict]]] = {}
        names = list(children)
        for spp in args.spp:
            for child in children.values():  # warm-ups run at the same time: not timed
                child.send({"cmd": "setup", "spp": spp})
            for name, child in children.items():
                ready = child.recv("ready")
                info[name]["warmup_s"][str(spp)] = ready["warmup_s"]
                if ready["foreign_modules"]:
                    raise RuntimeError(
                        f"{name}: refnpr modules loaded from outside {child.checkout}: "
                        + "; ".join(ready["foreign_modules"][:5])
                    )
            for i in range(args.runs):
                order = names if i % 2 == 0 else names[::-1]
                sums = {}
                for name in order:
                    children[name].send({"cmd": "round"})
                    recs = children[name].recv("round")
                    sums[name] = sum(r["wall_s"] for r in recs if r["engine"] == "render")
                    for r in recs:
                        key = (r["scene"], r["style"], spp, r["engine"])
                        samples.setdefault(key, {n: [] for n in names})[name].append(r)
                print(
                    f"  spp {spp} round {i + 1}/{args.runs} ({' then '.join(order)}): "
                    + ", ".join(f"{n} {sums[n] * 1e3:.0f} ms" for n in names)
                    + " (every row's render(), summed)",
                    flush=True,
                )
    finally:
        for child in children.values():
            child.close()
    ab_rows = []
    for (scene, style, spp, engine), by_side in samples.items():
        row = {"scene": scene, "style": style, "spp": spp, "engine": engine}
        for name in names:
            recs = by_side[name]
            side = {"wall": _stats([r["wall_s"] for r in recs])}
            keys = [k for k in PHASES if all(k in r["timings"] for r in recs)]
            side["phases_median_s"] = {
                k: statistics.median(r["timings"][k] for r in recs) for k in keys
            }
            row[name] = side
        b, c = row["baseline"]["wall"], row["current"]["wall"]
        row["ratio"] = c["median_s"] / b["median_s"]
        row["paired_ratio"] = statistics.median(
            x / y for x, y in zip(c["runs_s"], b["runs_s"], strict=True)
        )
        row["flagged"] = row["ratio"] > args.flag_above
        ab_rows.append(row)
    return {
        "meta": {
            "mode": "ab",
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "machine": platform.platform(),
            "cpus": os.cpu_count(),
            "size": [width, height],
            "runs": args.runs,
            "label": args.label,
            "flag_above": args.flag_above,
            "statistic": "wall time of the render() call in the child, median over the rounds; "
            "ratio = current median / baseline median; paired_ratio = median of per-round "
            "current / baseline (the two sides take turns, order flipped every round)",
            "load_avg_1min": [load_start, os.getloadavg()[0]],
        },
        "sides": info,
        "ab": ab_rows,
        "rows": [],
    }


def ab_table(report: dict) -> str:
    m, sides = report["meta"], report["sides"]
    w, h = m["size"]

    def cell(st: dict) -> str:
        return f"{st['median_s'] * 1e3:8.1f} [{st['min_s'] * 1e3:6.1f}-{st['max_s'] * 1e3:6.1f}]"

    lines = [
        f"A/B render() at {w}x{h}: {m['runs']} rounds per side, taking turns "
        f"({m['date']}, {m['cpus']} cpus) {m['label'] or ''}",
        *(
            f"  {n}: {s['checkout']} ({s['git']}), refnpr from {s['refnpr_file']}"
            for n, s in sides.items()
        ),
        f"1-min load average: {m['load_avg_1min'][0]:.2f} at start, "
        f"{m['load_avg_1min'][1]:.2f} at end",
        "wall time of render() per frame, ms: median [min-max]; ratio = current / baseline "
        "(medians); paired = median of the per-round ratios",
        f"{'scene / style':30s} {'spp':>3s} {'engine':8s} {'baseline':>24s} {'current':>24s} "
        f"{'ratio':>6s} {'paired':>7s}",
    ]
    for r in report["ab"]:
        flag = f"  SLOWER (> {m['flag_above']:g})" if r["flagged"] else ""
        lines.append(
            f"{r['scene'] + ' / ' + r['style']:30s} {r['spp']:3d} {r['engine']:8s} "
            f"{cell(r['baseline']['wall']):>24s} {cell(r['current']['wall']):>24s} "
            f"{r['ratio']:6.3f} {r['paired_ratio']:7.3f}{flag}"
        )
    flagged = [r for r in report["ab"] if r["flagged"]]
    lines.append(
        f"{len(flagged)} of {len(report['ab'])} rows over {m['flag_above']:g}x the baseline"
        + (
            ": " + ", ".join(f"{r['style']} spp {r['spp']} {r['engine']}" for r in flagged)
            if flagged
            else ""
        )
    )
    return "\n".join(lines)


def _selected_rows(args) -> list[tuple[str, str]]:
    rows = ROWS
    if args.styles:
        wanted = set(args.styles)
        if "tamiss" in wanted:
            wanted.add("tam")  # tamiss's target is relative to tam's frame
        rows = tuple(r for r in ROWS if r[1] in wanted)
    return [tuple(r) for r in rows]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
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
    p.add_argument(
        "--baseline",
        default=None,
        metavar="DIR",
        help="A/B mode: also time the checkout DIR (holding refnpr/), each side in its own "
        "child process, taking turns round by round (frame section only)",
    )
    p.add_argument(
        "--flag-above",
        type=float,
        default=1.05,
        help="A/B mode: flag rows whose current / baseline ratio exceeds this (default 1.05)",
    )
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
    if args.baseline is not None:
        if sections != {"frame"}:
            print("A/B mode (--baseline) times the frame section only", flush=True)
        try:
            report = run_ab(args)
        except RuntimeError as exc:
            print(f"A/B run failed: {exc}", file=sys.stderr)
            return 1
        print(ab_table(report))
        if args.json:
            path = Path(args.json)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(report, indent=1) + "\n")
        return 0
    sys.path.insert(0, str(HERE.parent))  # this checkout's refnpr first
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
