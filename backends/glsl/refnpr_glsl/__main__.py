"""``python -m refnpr_glsl KIT_DIR OUT_DIR [--only NAME ...] [--derivatives analytic|quad]``.

Renders every case of a refnpr conformance kit with OpenGL 4.5 core (headless EGL) and writes
OUT_DIR/<case>.png and .exr (image cases) or OUT_DIR/<case>/<channel>.npy (G-buffer cases), plus
OUT_DIR/backend.json (renderer, mode, per-case status and timings). Cases whose style has no
module print "style X not implemented" and get no image (``refnpr kit check`` counts them
missing). Exit status 1 when a case failed with an error, else 0.
"""

from __future__ import annotations

import argparse
import json
import sys
import traceback
from pathlib import Path

from .context import GL
from .kit_io import Kit
from .raster import DERIVATIVE_MODES
from .render import StyleNotImplemented, render_case, write_result


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m refnpr_glsl",
        description="Render a refnpr conformance kit with the GLSL backend (reads only the kit).",
    )
    p.add_argument("kit_dir", type=Path, help="an exported kit (refnpr kit export DIR)")
    p.add_argument("out_dir", type=Path, help="where to write <case>.png/.exr/<case>/*.npy")
    p.add_argument("--only", nargs="+", metavar="NAME", help="render only these cases")
    p.add_argument("--derivatives", choices=DERIVATIVE_MODES, default="analytic")
    p.add_argument("--backend", default="egl", help="moderngl context backend (default egl)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only failures")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        kit = Kit(args.kit_dir)
        cases = kit.cases(args.only)
    except (ValueError, KeyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.out_dir.exists() and not args.out_dir.is_dir():
        print(f"error: OUT_DIR {str(args.out_dir)!r} is a file", file=sys.stderr)
        return 2
    args.out_dir.mkdir(parents=True, exist_ok=True)
    gl = GL(backend=args.backend)
    report = {
        "renderer": gl.renderer,
        "derivatives": args.derivatives,
        "kit": str(args.kit_dir),
        "cases": {},
    }
    failed = 0
    for case in cases:
        try:
            result = render_case(gl, case, derivatives=args.derivatives)
        except StyleNotImplemented as exc:
            print(f"{case.name}: {exc}; no image written")
            report["cases"][case.name] = {"status": "not implemented", "style": case.style_name}
            continue
        except Exception as exc:  # noqa: BLE001 -- one broken case must not stop the others
            failed += 1
            print(f"{case.name}: ERROR {type(exc).__name__}: {exc}", file=sys.stderr)
            if isinstance(exc, (ValueError, TypeError)):  # bad input (or a bug): where, briefly
                last = traceback.extract_tb(exc.__traceback__)[-1]
                print(f"  raised at {last.filename}:{last.lineno} ({last.name})", file=sys.stderr)
            else:  # a bug of the backend: the whole traceback
                traceback.print_exc(file=sys.stderr)
            report["cases"][case.name] = {"status": "error", "error": f"{exc}"}
            continue
        write_result(result, args.out_dir)
        report["cases"][case.name] = {
            "status": "rendered",
            "style": case.style_name,
            "timings": result.timings,
        }
        if not args.quiet:
            print(f"{case.name}: rendered in {result.timings['total']:.3f} s")
    (args.out_dir / "backend.json").write_text(json.dumps(report, indent=2) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
