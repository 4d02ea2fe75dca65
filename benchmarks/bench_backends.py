"""Style-layer benchmark: refnpr ``render()`` against the GLSL backend (OpenGL 4.5 through
moderngl/EGL: Mesa llvmpipe on CPU, or a GPU driver) for the same case at 1920x1080.

Usage::

    python benchmarks/bench_backends.py --repeat 5 --json benchmarks/results/backends.json
    python benchmarks/bench_backends.py --styles smooth,toon --size 640x360 --repeat 2   # quick

Per style, the first golden case of that style (``refnpr/suite/*.toml``) is re-exported as a kit case
at ``--size`` (its scene, style table and spp unchanged; ``refnpr kit export`` into a temporary
directory), then, alternating in one process:

* refnpr: ``render(scene, style, W, H, spp)`` (scene loaded once; the first call, which compiles
  the numba kernels, is a warm-up and not counted);
* GLSL: ``refnpr_glsl.render.render_case`` end to end: G-buffer pass, the style's shade pass,
  contours, composite + resolve and the read-back of the linear RGBA image (``glFinish`` after
  each stage). The geometry upload (``prepare``) is excluded (a GPU keeps its mesh resident);
  textures a style uploads inside ``shade`` are included. The first call (shader compilation) is
  a warm-up.

Reported per style: median and spread (min, max) of each, the ratio refnpr / GLSL (the
performance anchor of the style layer), the GLSL stage medians, and whether the GLSL image of
the last run passes the case's own tolerance against refnpr's (``refnpr.kit.check``). Thread
settings: ``--threads`` sets NUMBA_NUM_THREADS and LP_NUM_THREADS (llvmpipe) before anything is
imported. Nothing here asserts a time.

``--derivatives-kit KIT`` (instead of the timing): renders an exported kit with both
``--derivatives analytic`` and ``quad``, checks both with ``refnpr.kit.check`` and writes the
per-case table of the difference the choice makes (pass, frac_over_position, max_abs, ssim; per
channel max_abs for G-buffer cases) to ``--json`` (default
``benchmarks/results/backends_derivatives.json``)::

    refnpr kit export /tmp/kit
    python benchmarks/bench_backends.py --derivatives-kit /tmp/kit
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
SUITE = REPO / "refnpr" / "suite" / "suite.toml"
STYLES = ("smooth", "toon", "threshold", "halftone", "xtoon", "tam", "tamiss", "contours")


def _toml_value(v: Any) -> str:
    """A TOML inline value (strings, numbers, booleans, lists, tables)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} {v!r} as TOML")


def pick_cases(styles: list[str]) -> dict[str, Any]:
    """style -> the first golden image case of that style ("contours": the first smooth/toon
    or other case with a contour layer)."""
    from refnpr.golden import load_suite
    from refnpr.kit.styles import style_name
    from refnpr.scenes import load_scene
    from refnpr.styles import style_from_spec

    out: dict[str, Any] = {}
    for case in load_suite(SUITE):
        if case.kind != "image":
            continue
        spec = case.params.get("style")
        if spec is None:
            spec = getattr(load_scene(case.scene), "style", None)
        if spec is None:
            continue
        name = style_name(style_from_spec(spec))
        key = "contours" if isinstance(spec, dict) and spec.get("contours") else name
        if key in styles and key not in out:
            out[key] = case
        if name in styles and name not in out:
            out[name] = case
    return out


def export_at_size(cases: dict[str, Any], width: int, height: int, kit_dir: Path) -> dict:
    """Export each chosen case at width x height under the name ``bench-<style>``."""
    from refnpr.kit import export_kit

    lines = []
    for style, case in cases.items():
        lines.append("[[case]]")
        lines.append(f'name = "bench-{style}"')
        lines.append(f"scene = {_toml_value(case.scene)}")
        for k, v in case.params.items():
            if k in ("name", "scene", "width", "height", "description", "kind") or v is None:
                continue
            lines.append(f"{k} = {_toml_value(v)}")
        lines.append(f"width = {width}")
        lines.append(f"height = {height}")
        lines.append("")
    suite = kit_dir.parent / "bench_suite.toml"
    suite.write_text("\n".join(lines))
    export_kit(kit_dir, suite=suite)
    return {style: f"bench-{style}" for style in cases}


def _stats(xs: list[float]) -> dict[str, float]:
    return {"median": statistics.median(xs), "min": min(xs), "max": max(xs), "n": len(xs)}


def bench_style(style: str, golden: Any, kit_dir: Path, name: str, repeat: int, gl) -> dict:
    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.render import prepare, render_case, write_result

    from refnpr.kit.check import check_kit
    from refnpr.render import render
    from refnpr.scenes import load_scene

    case = Case(kit_dir / name)
    scene = load_scene(golden.scene)
    spec = golden.params.get("style")
    w, h, spp = case.width, case.height, case.spp
    uploaded = prepare(gl, case)
    render(scene, spec, w, h, spp)  # warm-up: numba compilation
    render_case(gl, case, uploaded=uploaded)  # warm-up: shader compilation
    t_ref, t_gl, stages = [], [], []
    result = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        render(scene, spec, w, h, spp)
        t_ref.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        result = render_case(gl, case, uploaded=uploaded)
        t_gl.append(time.perf_counter() - t0)
        stages.append(result.timings)
    uploaded.release()
    out_dir = kit_dir.parent / "renders"
    write_result(result, out_dir)
    check = next(c for c in check_kit(kit_dir, out_dir) if c.name == name)
    ref, glt = _stats(t_ref), _stats(t_gl)
    return {
        "style": style,
        "golden_case": golden.name,
        "scene": golden.scene,
        "size": [w, h],
        "spp": spp,
        "refnpr_s": ref,
        "glsl_s": glt,
        "ratio_refnpr_over_glsl": ref["median"] / glt["median"],
        "glsl_stages_median_s": {
            k: statistics.median(s[k] for s in stages) for k in stages[0] if k != "total"
        },
        "glsl_passes_tolerance": bool(check.passed),
        "glsl_frac_over_position": check.metrics.get("frac_over_position"),
    }


def derivative_table(kit: Path, out_json: Path) -> dict:
    """Render ``kit`` in both derivative modes and tabulate the check results per case."""
    import subprocess

    from refnpr.kit.check import check_kit

    table: dict[str, dict] = {}
    with tempfile.TemporaryDirectory(prefix="bench_derivatives_") as tmp:
        for mode in ("analytic", "quad"):
            out = Path(tmp) / mode
            proc = subprocess.run(
                [sys.executable, "-m", "refnpr_glsl", str(kit), str(out), "-q",
                 "--derivatives", mode],
                capture_output=True, text=True,
            )  # fmt: skip
            if proc.returncode != 0:
                print(proc.stderr[-3000:])
            for c in check_kit(kit, out):
                row = table.setdefault(c.name, {"kind": c.kind})
                if c.kind == "gbuffer":
                    row[mode] = {
                        "passed": c.passed,
                        "channels_max_abs": {k: v.get("max_abs") for k, v in c.channels.items()},
                        "channels_frac_bad": {k: v.get("frac_bad") for k, v in c.channels.items()},
                    }
                else:
                    keys = ("frac_over_position", "max_abs", "rmse", "ssim")
                    row[mode] = {"passed": c.passed, **{k: c.metrics.get(k) for k in keys}}
    summary = {
        m: sum(bool(r.get(m, {}).get("passed")) for r in table.values())
        for m in ("analytic", "quad")
    }
    print(f"{'case':48s} {'analytic':>20s} {'quad':>20s}")
    for name, r in table.items():
        cells = []
        for m in ("analytic", "quad"):
            v = r.get(m, {})
            f = v.get("frac_over_position")
            cells.append(
                f"{'PASS' if v.get('passed') else 'FAIL'} {f if f is not None else '-':>10.6}"
            )
        print(f"{name:48s} {cells[0]:>20s} {cells[1]:>20s}")
    print(f"passed: {summary} of {len(table)}")
    report = {"kit": str(kit), "passed": summary, "cases": table}
    out_json.parent.mkdir(parents=True, exist_ok=True)
    out_json.write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {out_json}")
    return report


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--styles", default=",".join(STYLES), help="comma-separated subset")
    p.add_argument("--size", default="1920x1080", help="WxH (default 1920x1080)")
    p.add_argument("--repeat", type=int, default=5, help="timed runs per backend (default 5)")
    p.add_argument("--threads", type=int, default=None, help="NUMBA/LP_NUM_THREADS")
    p.add_argument("--json", type=Path, default=None, help="output (see the module docstring)")
    p.add_argument("--derivatives-kit", type=Path, default=None, metavar="KIT")
    args = p.parse_args(argv)
    if args.derivatives_kit is not None:
        derivative_table(
            args.derivatives_kit, args.json or HERE / "results" / "backends_derivatives.json"
        )
        return 0
    args.json = args.json or HERE / "results" / "backends.json"
    if args.threads:
        os.environ["NUMBA_NUM_THREADS"] = os.environ["LP_NUM_THREADS"] = str(args.threads)
    styles = [s.strip() for s in args.styles.split(",") if s.strip()]
    unknown = sorted(set(styles) - set(STYLES))
    if unknown:
        p.error(f"--styles: unknown {unknown}; choose from {list(STYLES)}")
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        p.error(f"--size: expected WxH such as 1920x1080, got {args.size!r}")
    if args.repeat < 1:
        p.error(f"--repeat: expected >= 1, got {args.repeat}")

    from refnpr_glsl.context import GL

    gl = GL()
    rows, errors = [], {}
    with tempfile.TemporaryDirectory(prefix="bench_backends_") as tmp:
        kit = Path(tmp) / "kit"
        chosen = pick_cases(styles)
        names = {}
        for style, case in chosen.items():  # one export per case: one failure stays local
            try:
                names.update(export_at_size({style: case}, width, height, kit))
            except Exception as exc:  # noqa: BLE001 -- reported in the table
                errors[style] = f"export: {type(exc).__name__}: {exc}"
        for style in styles:
            if style not in chosen:
                errors.setdefault(style, "no golden case of this style")
                continue
            if style not in names:
                continue
            try:
                rows.append(bench_style(style, chosen[style], kit, names[style], args.repeat, gl))
            except Exception as exc:  # noqa: BLE001 -- reported in the table
                errors[style] = f"{type(exc).__name__}: {exc}"
            print(rows[-1] if rows and rows[-1]["style"] == style else errors.get(style))
    print()
    print(f"GL renderer: {gl.renderer}")
    print(
        f"{'style':10s} {'case':38s} {'refnpr s (min-max)':>22s} {'GLSL s (min-max)':>22s} "
        f"{'ratio':>6s} pass"
    )
    for r in rows:
        a, b = r["refnpr_s"], r["glsl_s"]
        print(
            f"{r['style']:10s} {r['golden_case']:38s} "
            f"{a['median']:8.3f} ({a['min']:.3f}-{a['max']:.3f}) "
            f"{b['median']:8.3f} ({b['min']:.3f}-{b['max']:.3f}) "
            f"{r['ratio_refnpr_over_glsl']:6.2f} {r['glsl_passes_tolerance']}"
        )
    for style, err in errors.items():
        print(f"{style:10s} not measured: {err}")
    report = {
        "benchmark": "bench_backends",
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "machine": {
            "platform": platform.platform(),
            "python": sys.version.split()[0],
            "cpus": os.cpu_count(),
            "gl_renderer": gl.renderer,
            "threads": args.threads,
        },
        "size": [width, height],
        "repeat": args.repeat,
        "timing": "wall seconds; refnpr render() vs refnpr_glsl render_case (upload excluded, "
        "readback included), alternating in one process, after one warm-up each",
        "rows": rows,
        "not_measured": errors,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {args.json}")
    gl.release()
    return 0


if __name__ == "__main__":
    sys.exit(main())
