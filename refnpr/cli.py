"""The ``refnpr`` command: render, animate, coherence, scenes, styles, info, golden, compare,
gallery, kit, warmup."""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import sys
import threading
import time
import warnings
from pathlib import Path
from typing import Any

__all__ = ["main"]

DEFAULT_SIZE = (768, 432)  # `refnpr render`: a 16:9 frame, the default scene's framing
DEFAULT_SPP = 4  # 2x2 samples per pixel: anti-aliased edges and contours


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--size: expected WxH such as 512x512, got {text!r}"
        ) from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(f"--size: width and height must be positive, got {text!r}")
    return w, h


def _param(text: str) -> tuple[str, object]:
    if "=" not in text or not text.split("=", 1)[0].strip():
        raise argparse.ArgumentTypeError(f"--param: expected KEY=VALUE such as n=3, got {text!r}")
    key, raw = text.split("=", 1)
    if not raw.strip():
        raise argparse.ArgumentTypeError(
            f"--param: {text!r} has no value; give KEY=VALUE such as n=3 (a TOML value, or a "
            "bare word for a string)"
        )
    import tomllib

    try:
        parsed = tomllib.loads(f"v = {raw}")
        if len(parsed) != 1:  # a newline in the value started another key
            raise argparse.ArgumentTypeError(
                f"--param: the value of {key.strip()!r} holds more than one TOML value "
                f"({raw!r}); give one KEY=VALUE per --param"
            )
        value = parsed["v"]
    except tomllib.TOMLDecodeError:
        value = raw  # a bare word is a string
    except RecursionError:  # tomllib parses nested arrays recursively
        raise argparse.ArgumentTypeError(
            f"--param: the value of {key.strip()!r} nests arrays or tables too deeply to parse"
        ) from None
    return key.strip(), value


#: Seconds a render runs before its progress bar appears (a quick render shows none).
_BAR_DELAY = 1.0


def _show_bar(args: argparse.Namespace) -> bool:
    """Whether a command draws a progress bar: never with -q/--quiet; with --progress always;
    else only when stderr is a terminal (captured output gets no ``\\r`` updates)."""
    if getattr(args, "quiet", False):
        return False
    return bool(getattr(args, "progress", False)) or sys.stderr.isatty()


def _tqdm(**kwargs):
    """A tqdm progress bar on stderr (tqdm is one of refnpr's dependencies)."""
    try:
        from tqdm import tqdm
    except ImportError:
        raise ValueError(
            "--progress: progress bars need the tqdm package (`pip install tqdm`); or pass -q"
        ) from None
    return tqdm(file=sys.stderr, dynamic_ncols=True, **kwargs)


class _Progress:
    """A render's progress bar (tqdm): the phase, its share of the work and the time so far,
    refreshed from a thread; shown only once the render has taken ``_BAR_DELAY`` seconds."""

    def __init__(self, delay: float | None = None) -> None:
        self.delay = _BAR_DELAY if delay is None else delay
        self.start = time.perf_counter()
        self.bar = _tqdm(
            total=100, desc="start", bar_format="{desc:10s} {percentage:3.0f}%|{bar}| {elapsed}"
        )
        self.bar.delay = self.delay  # tqdm draws nothing itself before this
        self._shown = False
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def __call__(self, phase: str, fraction: float) -> None:
        self.bar.set_description_str(phase, refresh=False)
        self.bar.n = int(round(100 * fraction))

    def _run(self) -> None:
        if self._done.wait(self.delay):
            return
        self._shown = True
        while True:
            self.bar.refresh()
            if self._done.wait(0.2):
                return

    def close(self) -> None:
        self._done.set()
        self._thread.join()
        if self._shown or time.perf_counter() - self.start >= self.delay:
            self("done", 1.0)
            self.bar.refresh()
        else:
            self.bar.disable = True  # a quick render: no bar at all
        self.bar.close()


class _FrameProgress:
    """`refnpr animate`'s progress bar (tqdm): frames done of the range, frames per second,
    ETA, and the frame just finished (drawn from the first frame on)."""

    def __init__(self) -> None:
        self.bar = None

    def __call__(self, done: int, total: int, frame: int, status: str) -> None:
        if self.bar is None:
            self.bar = _tqdm(
                total=total,
                unit="frame",
                bar_format="frame {n_fmt}/{total_fmt} |{bar}| {rate_noinv_fmt} ETA {remaining}"
                "{postfix}",
            )
        what = {"state": "state only", "skipped": "done"}.get(status, status)
        self.bar.set_postfix_str(f"#{frame} {what}", refresh=False)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _style_params(args: argparse.Namespace) -> dict[str, object]:
    """--style checked, and the --param pairs as a dict: each key once, never the style's name."""
    if args.style is not None and not args.style.strip():
        raise ValueError(
            f"--style: expected a style name, got {args.style!r}; list them with `refnpr styles`, "
            "or leave --style out to use the scene's own style"
        )
    params: dict[str, object] = {}
    for key, value in args.param or []:
        if key == "name":
            raise ValueError(
                f"--param: 'name' is not a style parameter (got name={value!r}); choose the "
                f"style with --style {value}"
            )
        if key in params:
            raise ValueError(
                f"--param: {key!r} given twice ({params[key]!r} and {value!r}); give it once"
            )
        params[key] = value
    return params


def _with_params(style: dict | None, params: dict, scene: str) -> dict:
    """The scene's own style table with the --param values (no --style given). A value of the
    table that the modes --param chooses do not read is left out (it would be reset to its
    default anyway): the warning for an ignored parameter is for what the user gave."""
    if not style:
        raise ValueError(
            f"--param needs --style: the scene {scene!r} names no style; "
            "add --style NAME (list them with `refnpr styles`)"
        )
    merged = {**style, **params}
    from .styles import get_style_class

    try:
        declared = get_style_class(merged.get("name")).PARAMS
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            values = declared.validate({k: v for k, v in merged.items() if k in declared.by_name})
    except (TypeError, ValueError, AttributeError):  # reported when the style is built
        return merged
    return {
        k: v
        for k, v in merged.items()
        if k == "name" or k in params or k not in declared.by_name or declared.reads(k, values)
    }


def _params_over_tracks(scene: Any, params: dict) -> Any:
    """``scene`` without the style tracks of the parameters --param sets, with a warning for
    each: the command line's value holds on every frame, as it does for a still."""
    anim = getattr(scene, "animation", None)
    if anim is None or not params:
        return scene
    kept = []
    for track in anim.tracks:
        part, _, name = track.parts
        if part == "style" and name in params:
            warnings.warn(
                f"--param {name}={params[name]!r} replaces the scene's track {track.target!r}: "
                "every frame uses that value",
                UserWarning,
                stacklevel=2,
            )
        else:
            kept.append(track)
    if len(kept) == len(anim.tracks):
        return scene
    return dataclasses.replace(scene, animation=dataclasses.replace(anim, tracks=tuple(kept)))


def _scene_and_style(args: argparse.Namespace) -> tuple[object, dict | None]:
    """The scene of --scene and the style of --style/--param (None: the scene's own)."""
    from .scenes import load_scene

    params = _style_params(args)
    scene = _params_over_tracks(
        load_scene(args.scene, camera=getattr(args, "camera", None)), params
    )
    if args.style:
        return scene, {"name": args.style, **params}
    return scene, _with_params(scene.style, params, args.scene) if params else None


def _cmd_render(args: argparse.Namespace) -> int:
    from .image import check_png_path
    from .render import render

    check_png_path(args.output, "-o/--output")  # before rendering, not after
    if args.exr is not None:
        from .exr import check_exr_path

        check_exr_path(args.exr, what="--exr")
    scene, style = _scene_and_style(args)
    width, height = args.size
    progress = _Progress() if _show_bar(args) else None
    passes = args.exr is not None
    try:
        image = render(scene, style, width, height, args.spp, progress=progress, passes=passes)
    finally:
        if progress:
            progress.close()
    out = image.save(args.output)
    written = f"{out} and {image.save(args.exr)}" if passes else f"{out}"
    if not args.quiet:
        print(
            f"wrote {written} ({width}x{height}, spp={args.spp}) in {image.timings['total']:.2f} s"
        )
    return 0


def _cmd_animate(args: argparse.Namespace) -> int:
    from ._atomic import check_parent_writable
    from .sequence import _video_suffix, frame_range, render_sequence, write_video

    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o/--output: {args.output!r} is a file; give a directory for the frames")
    check_parent_writable(out / "frame", args.output, "-o/--output")
    if args.video is not None:
        _video_suffix(args.video, "--video")
    scene, style = _scene_and_style(args)
    try:
        frame_range(args.frames, scene.frames)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"--frames: {exc}") from None
    width, height = args.size
    cluster = _cluster_args(args)
    if cluster is None and (args.chunk is not None or args.warmup is not None):
        raise ValueError(
            "--chunk / --warmup: they split a stateful style's frames over a cluster; add "
            "--workers N or --scheduler ADDR (a serial run shades every frame from frame 0)"
        )
    progress = _FrameProgress() if _show_bar(args) else None
    kwargs = dict(out_dir=out, frames=args.frames, exr=args.exr, progress=progress)
    try:
        if cluster is None:
            result = render_sequence(scene, style, width, height, args.spp, **kwargs)
        else:
            from . import distributed

            if args.warmup is not None:
                cluster["warmup"] = args.warmup
            result = distributed.render_sequence(
                scene, style, width, height, args.spp, chunk=args.chunk, **cluster, **kwargs
            )
    finally:
        if progress:
            progress.close()
    if not args.quiet:
        n = len(result.frames)
        print(
            f"wrote {len(result.rendered)} of {n} frame(s) to {out} ({width}x{height}, "
            f"spp={args.spp}; {len(result.skipped)} already done) in {result.seconds:.2f} s"
            + ("; stateful style: ran from frame 0" if result.stateful else "")
        )
    if args.video is not None:
        fps = scene.animation.fps if scene.animation is not None else 24.0
        video = write_video(result.paths, args.video, fps)
        if not args.quiet:
            print(f"wrote {video} ({len(result.paths)} frames at {fps:g} fps)")
    return 0


def _cluster_args(args: argparse.Namespace) -> dict | None:
    """--workers / --scheduler as keyword arguments of refnpr.distributed (None: serial)."""
    if args.workers is None and args.scheduler is None:
        return None
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers: expected a whole number >= 1, got {args.workers}")
    return {"workers": args.workers, "scheduler": args.scheduler}


def _cmd_scenes(args: argparse.Namespace) -> int:
    from .scenes import list_scenes
    from .scenes.toml_format import scene_frames

    for name, desc in list_scenes().items():
        frames = scene_frames(name)
        mark = f"[{frames} frames] " if frames > 1 else ""
        print(f"{name:16s} {mark}{desc}")
    return 0


def _cmd_styles(args: argparse.Namespace) -> int:
    from .styles import get_style_class, list_styles

    if not args.name:
        if args.markdown:
            raise ValueError(
                "--markdown: prints one style's parameter table; name the style, e.g. "
                "`refnpr styles threshold --markdown` (`refnpr styles` lists them)"
            )
        for name, desc in list_styles().items():
            print(f"{name:16s} {desc}")
        return 0
    from .styles._declare import markdown_table, text_table
    from .styles.contours import CONTOURS

    if args.name == "contours":  # the contour layer any style takes (``contours = {...}``)
        params = CONTOURS
    else:
        cls = get_style_class(args.name)
        if cls.PARAMS is None:
            print(f"{cls.name}: parameters {', '.join(cls.parameters())} (see its docstring)")
            return 0
        params = cls.PARAMS
    print(markdown_table(params) if args.markdown else text_table(params), end="")
    kept = {} if args.name == "contours" else get_style_class(args.name).INTERMEDIATES
    if kept and not args.markdown:
        print("\nintermediates (EXR passes of `refnpr render --exr`):")
        for name, what in kept.items():
            print(f"  {name:10s} {what}")
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    import numba
    import numpy
    import skimage
    import trimesh

    from . import __version__, _jit, raster  # noqa: F401  (importing raster decorates its kernels)

    cache = os.environ.get("NUMBA_CACHE_DIR") or "(next to each module, __pycache__)"
    if _jit.FALLBACK:
        where = [f or "none: compiled on every start" for f in _jit.FALLBACK]
        cache += f"; where that is not writable: {', '.join(where)}"
    info = {
        "refnpr": __version__,
        "python": sys.version.split()[0],
        "numpy": numpy.__version__,
        "numba": numba.__version__,
        "scikit-image": skimage.__version__,
        "trimesh": trimesh.__version__,
        "numba threads": numba.get_num_threads(),
        "numba cache dir": cache,
    }
    for k, v in info.items():
        print(f"{k:16s} {v}")
    return 0


def _command(args: argparse.Namespace) -> str:
    """The command as typed: ``golden``, ``kit export``."""
    return " ".join(filter(None, (args.command, getattr(args, "kit_command", None))))


def _suite(args: argparse.Namespace) -> Path:
    """The --suite file, or the suite installed with refnpr (refnpr/suite/suite.toml)."""
    if args.suite is not None:
        return Path(args.suite)
    from .golden import DEFAULT_SUITE

    if not DEFAULT_SUITE.is_file():
        raise ValueError(
            f"--suite: the suite installed with refnpr is missing ({str(DEFAULT_SUITE)!r} does "
            "not exist): reinstall refnpr, or pass --suite FILE"
        )
    return DEFAULT_SUITE


def _cmd_golden(args: argparse.Namespace) -> int:
    from .golden import check_suite, update_suite

    suite = _suite(args)
    cluster = _cluster_args(args)
    if cluster is not None:  # the same files and report, the cases rendered on a Dask cluster
        import functools

        from . import distributed

        check_suite = functools.partial(distributed.check_suite, **cluster)
        update_suite = functools.partial(distributed.update_suite, **cluster)
    if args.update:
        from .golden import check_writable_suite

        check_writable_suite(suite)  # before a cluster starts
        update_suite(suite, only=args.only, log=(lambda line: None) if args.quiet else print)
        return 0
    results = check_suite(suite, only=args.only)
    failed = 0
    for r in results:
        if not (args.quiet and r.passed):  # -q: the failures and the count only
            print(f"{'PASS' if r.passed else 'FAIL'} {r.name:32s} {r.message}")
        failed += not r.passed
    print(f"{len(results) - failed} passed, {failed} failed")
    return 1 if failed else 0


def _fraction(name: str):
    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name}: expected a number, got {text!r}") from None
        if not 0.0 <= v <= 1.0:
            raise argparse.ArgumentTypeError(f"{name}: expected a value in [0, 1], got {text!r}")
        return v

    return parse


def _cmd_warmup(args: argparse.Namespace) -> int:
    from ._jit import usable_cores
    from .warmup import warm

    t0 = time.perf_counter()

    def progress(label: str, fraction: float) -> None:
        if not args.quiet and label != "done":
            print(f"warmup: {label}", file=sys.stderr, flush=True)

    jobs = args.jobs if args.jobs is not None else min(4, usable_cores())
    times = warm(jobs=jobs, progress=progress)
    total = time.perf_counter() - t0
    if args.quiet:
        return 0
    print(
        f"warmup: {len(times)} renders in {total:.1f} s ({jobs} process{'es' if jobs > 1 else ''});"
        " kernels are cached for the next run"
    )
    return 0


def _run_of(module: str):
    """A command whose work is ``run(args)`` of a refnpr module, imported when it runs."""

    def command(args: argparse.Namespace) -> int:
        import importlib

        return importlib.import_module(f"{__package__}.{module}").run(args)

    return command


def _cmd_compare(args: argparse.Namespace) -> int:
    from ._atomic import check_output_file
    from .compare import check_outside_compared, compare_dirs, format_table
    from .image import atomic_file

    if args.out is not None and Path(args.out).exists() and not Path(args.out).is_dir():
        raise ValueError(f"--out: {args.out!r} is a file; give a directory for the diff images")
    if args.json and Path(args.json).is_dir():
        raise ValueError(
            f"--json: {args.json!r} is a directory; give a file name such as "
            f"{str(Path(args.json) / 'metrics.json')!r}"
        )
    if args.json is not None:  # a .json file: never one of the compared PNGs
        check_output_file(args.json, "--json", ".json")
    if args.out is not None:  # its NAME.diff.png would be compared on the next run
        check_outside_compared(args.out, "--out", args.reference, args.candidate)
    results = compare_dirs(
        args.reference, args.candidate, out_dir=args.out, tolerance=args.tolerance
    )
    print(format_table(results))
    cand_dir = Path(args.candidate)
    compared = {f"{m.name}.png" for m in results}
    extra = sorted(p.name for p in cand_dir.glob("*.png") if p.name not in compared)
    if not any(cand_dir.glob("*.png")):
        print(f"note: candidate directory {args.candidate!r} has no .png files")
    elif extra:
        print(
            f"note: {len(extra)} candidate file(s) without a reference image, not compared: "
            + ", ".join(extra)
        )
    bad = [
        m for m in results if not m.passes(max_frac_over=args.max_frac_over, min_ssim=args.min_ssim)
    ]
    if args.json is not None:
        with atomic_file(args.json, suffix=".json") as tmp:
            tmp.write_text(json.dumps([m.as_dict() for m in results], indent=2))
    print(f"{len(results) - len(bad)} passed, {len(bad)} failed")
    return 1 if bad else 0


def _cmd_kit_export(args: argparse.Namespace) -> int:
    from .golden import load_suite
    from .kit.export import export_kit
    from .kit.provenance import describe, describe_source, provenance

    log = (lambda line: None) if args.quiet else print
    if args.scene is None:
        for flag in ("style", "param", "name", "size", "spp"):
            if getattr(args, flag) is not None:
                raise ValueError(f"--{flag}: only with --scene FILE (a case of your own scene)")
        suite = _suite(args)
        load_suite(suite)  # a bad suite is reported before the line that names it
        print(describe_source(suite))
        written = export_kit(args.dir, suite=suite, only=args.only, log=log)
    else:
        if args.suite is not None or args.only is not None:
            raise ValueError("--scene: export either a case of your own scene or suite cases")
        case = _scene_case(args)
        print(f"{describe(provenance())}; case {case.name!r} of {args.scene!r}")
        written = export_kit(args.dir, cases=[case], log=log)
    print(f"exported {len(written)} case(s) to {args.dir}")
    return 0


def _scene_case(args: argparse.Namespace):
    """The kit case of ``kit export --scene``: its name (--name, else the scene's file name and
    the style) and style (--style/--param, else the scene's own with --param applied)."""
    import re

    from .golden import scene_case
    from .render import DEFAULT_STYLE

    with warnings.catch_warnings():  # the export reads the scene again and notes what it must
        warnings.simplefilter("ignore")
        scene, style = _scene_and_style(args)
    spec = style or scene.style or DEFAULT_STYLE
    label = spec if isinstance(spec, str) else spec.get("name", "style")
    stem = Path(args.scene).stem if Path(args.scene).suffix else args.scene
    name = args.name or re.sub(r"[^a-z0-9_-]+", "-", f"{stem}-{label}".lower()).strip("-_")[:128]
    width, height = args.size or (256, 192)
    spp = 1 if args.spp is None else args.spp
    return scene_case(name, args.scene, style=style, width=width, height=height, spp=spp)


def _add_style_options(p: argparse.ArgumentParser, style_help: str) -> None:
    p.add_argument("--style", help=style_help)
    p.add_argument(
        "--param",
        action="append",
        type=_param,
        metavar="KEY=VALUE",
        help="style parameter (TOML value), repeatable; `refnpr styles NAME` lists them",
    )


def _add_camera_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--camera",
        metavar="NAME",
        help="glTF scenes: the camera (camera or node name) to render from (default: the file's "
        "first camera)",
    )


def _add_suite_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--suite",
        metavar="FILE",
        help="suite file (default: the suite installed with refnpr, refnpr/suite/suite.toml)",
    )
    p.add_argument("--only", nargs="+", metavar="NAME", help="only these cases")


def _add_quiet_progress(p: argparse.ArgumentParser) -> None:
    """-q/--quiet and --progress of a command that draws a progress bar."""
    p.add_argument(
        "-q", "--quiet", action="store_true", help="print nothing but errors (no progress bar)"
    )
    p.add_argument(
        "--progress",
        action="store_true",
        help="draw the progress bar even when stderr is not a terminal (default: only on one)",
    )


def _add_cluster_options(parser: argparse.ArgumentParser) -> None:
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="render on a local Dask cluster of N worker processes (pip install "
        "'refnpr[distributed]'); results identical to a serial run",
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="render on a running Dask cluster, e.g. tcp://10.0.0.5:8786",
    )


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="refnpr", description="CPU reference renderer for NPR shading")
    sub = p.add_subparsers(dest="command", required=True)
    own_style = "style name (default: the scene's own style)"

    r = sub.add_parser(
        "render",
        help="render a scene to a PNG",
        description=(
            "Render a scene to a PNG. With no options: the default scene (Newell's teapot in "
            "Freudenberg et al.'s halftone engraving, with contours) at 768x432, spp 4."
        ),
    )
    r.add_argument(
        "--scene",
        default="default",
        help="built-in scene name, .toml, .gltf or .glb file (default: default)",
    )
    _add_camera_option(r)
    _add_style_options(r, "style name (default: the scene's own style, toon if it names none)")
    r.add_argument("--size", type=_size, default=DEFAULT_SIZE, help="WxH (default 768x432, 16:9)")
    r.add_argument(
        "--spp",
        type=int,
        default=DEFAULT_SPP,
        help="samples per pixel, a square (1, 4, 9, 16; default 4, anti-aliased)",
    )
    r.add_argument("-o", "--output", default="out.png", help="output PNG (default out.png)")
    r.add_argument(
        "--exr",
        metavar="FILE.exr",
        help="also write one OpenEXR file: linear RGBA (premultiplied) and the G-buffer passes "
        "(depth.Z, normal.X/Y/Z, uv.U/V, position.X/Y/Z, tri_id, mesh_id, ...; see docs)",
    )
    _add_quiet_progress(r)
    r.set_defaults(func=_cmd_render)

    a = sub.add_parser(
        "animate",
        help="render the frames of an animated scene to DIR (restartable), optionally a video",
        description=(
            "Render frames of an animated scene (one with an [animation] table; a still scene is "
            "one frame) as DIR/frame_00000.png, ... Frames already in DIR with matching metadata "
            "are skipped, so a killed run can be restarted (see docs/animation.md)."
        ),
    )
    a.add_argument(
        "scene", help="built-in scene name, .toml, .gltf or .glb file (see `refnpr scenes`)"
    )
    _add_camera_option(a)
    _add_style_options(a, own_style)
    a.add_argument("--size", type=_size, default=DEFAULT_SIZE, help="WxH (default 768x432)")
    a.add_argument(
        "--spp", type=int, default=DEFAULT_SPP, help="samples per pixel, a square (default 4)"
    )
    a.add_argument(
        "--frames",
        metavar="A:B",
        help="frames A to B-1, like a Python slice (10:, :24, -10: for the last ten); default all",
    )
    a.add_argument("-o", "--output", required=True, metavar="DIR", help="directory for the frames")
    a.add_argument(
        "--exr",
        action="store_true",
        help="also write OpenEXR frames: linear RGBA and the frame's G-buffer passes",
    )
    a.add_argument("--video", metavar="FILE", help="also encode FILE.mp4 or FILE.gif")
    _add_cluster_options(a)
    a.add_argument(
        "--chunk",
        type=int,
        metavar="N",
        help="with --workers/--scheduler, stateful styles: frames per chunk (default: split "
        "evenly over the workers)",
    )
    a.add_argument(
        "--warmup",
        type=int,
        metavar="K",
        help="with --workers/--scheduler, stateful styles: frames shaded before each chunk for "
        "the state only (default 8)",
    )
    _add_quiet_progress(a)
    a.set_defaults(func=_cmd_animate)

    sub.add_parser("scenes", help="list built-in scenes").set_defaults(func=_cmd_scenes)
    st = sub.add_parser(
        "styles", help="list styles, or one style's parameters (what --param takes)"
    )
    st.add_argument(
        "name", nargs="?", help="a style (or contours, the contour layer): list its parameters"
    )
    st.add_argument("--markdown", action="store_true", help="as the table of the docs")
    st.set_defaults(func=_cmd_styles)
    sub.add_parser("info", help="versions, numba threads, cache dir").set_defaults(func=_cmd_info)

    g = sub.add_parser("golden", help="check (default) or regenerate the golden images")
    mode = g.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true", help="re-render and compare (default)")
    mode.add_argument("--update", action="store_true", help="re-render and overwrite")
    _add_suite_options(g)
    _add_cluster_options(g)
    g.add_argument(
        "-q", "--quiet", action="store_true", help="only failing cases and the count; no 'wrote'"
    )
    g.set_defaults(func=_cmd_golden)

    c = sub.add_parser("compare", help="compare another backend's renders with reference images")
    c.add_argument("reference", help="directory of reference PNGs (e.g. refnpr/suite/)")
    c.add_argument("candidate", help="directory of candidate PNGs with the same file names")
    c.add_argument(
        "--out", help="write NAME.diff.png and report.json here (outside both directories)"
    )
    c.add_argument("--json", help="write the metrics as JSON to this .json file")
    c.add_argument("--tolerance", type=_fraction("--tolerance"), default=2.0 / 255)
    c.add_argument("--max-frac-over", type=_fraction("--max-frac-over"), default=0.001)
    c.add_argument("--min-ssim", type=_fraction("--min-ssim"), default=0.99)
    c.set_defaults(func=_cmd_compare)

    gal = sub.add_parser(
        "gallery", help="render one small image per paper into DIR (the README gallery)"
    )
    gal.add_argument("out_dir", help="directory for the PNGs (e.g. docs/images/gallery)")
    gal.add_argument("--size", type=_size, default=(320, 240), help="WxH of each image (320x240)")
    gal.add_argument(
        "--suite", metavar="FILE", help="golden suite file (default: the one installed with refnpr)"
    )
    gal.add_argument("--spp", type=int, help="samples per pixel (the cases')")
    gal.add_argument("--only", nargs="+", metavar="FILE", help="only these entries (by file name)")
    gal.add_argument("--markdown", action="store_true", help="print the README table")
    gal.add_argument("-q", "--quiet", action="store_true", help="no line per image")
    gal.set_defaults(func=_run_of("gallery"))

    kit = sub.add_parser(
        "kit",
        help="conformance kit: export every input of the golden cases; check a backend's renders",
        description=(
            "Test a GPU implementation against refnpr: `refnpr kit export KIT` writes every "
            "input of the golden cases in standard formats (glTF, OpenEXR, PNG, JSON; see "
            "docs/kit.md), your backend renders KIT into RENDERS, `refnpr kit check KIT "
            "RENDERS` compares them with each case's own tolerance."
        ),
    )
    ksub = kit.add_subparsers(dest="kit_command", required=True)
    ke = ksub.add_parser("export", help="write the conformance kit of the golden suite to DIR")
    ke.add_argument("dir", help="kit directory (created; existing cases are replaced)")
    _add_suite_options(ke)
    ke.add_argument(
        "--scene",
        metavar="FILE",
        help="export one case of your own scene (.gltf, .glb, .toml or a built-in name) instead of "
        "the suite's: same schema, tolerances and derived texts; added to the kit's cases",
    )
    ke.add_argument("--name", help="with --scene: the case name (default: SCENE-STYLE)")
    _add_style_options(ke, "with --scene: the style (default: the scene's own)")
    ke.add_argument("--size", type=_size, help="with --scene: WxH (default 256x192)")
    ke.add_argument("--spp", type=int, help="with --scene: samples per pixel (default 1)")
    ke.add_argument("-q", "--quiet", action="store_true", help="no line per case")
    ke.set_defaults(func=_cmd_kit_export)
    kc = ksub.add_parser("check", help="compare a backend's renders with a kit")
    kc.add_argument("kit_dir", help="an exported kit (refnpr kit export)")
    kc.add_argument("renders_dir", help="the backend's renders: <case>.png, <case>/<channel>.npy")
    kc.add_argument("--report", metavar="DIR", help="write index.html and masks")
    kc.add_argument("--json", metavar="FILE", help="write the metrics as JSON")
    kc.add_argument("--only", nargs="+", metavar="NAME", help="only these cases")
    kc.add_argument("--styles", nargs="+", metavar="NAME", help="only the cases of these styles")
    kc.add_argument(
        "-q", "--quiet", action="store_true", help="only failing cases and the summary line"
    )
    kc.add_argument(
        "--missing",
        choices=("fail", "skip"),
        default="fail",
        help="a case without a render: fail (default) or skip; listed apart, last, either way",
    )
    kc.set_defaults(func=_run_of("kit.check"))
    kd = ksub.add_parser(
        "diff",
        help="list the cases that changed between two exported kits",
        description=(
            "List the cases added, removed and changed between two exported kits, and what "
            "changed in each: its inputs, tolerance, expected images or only its derived texts "
            "(with the case.json keys and files that differ). Both kits are read as untrusted "
            "input. Exit status: 0 identical, 1 changed, 2 an error."
        ),
    )
    kd.add_argument("old", help="the kit you tested against")
    kd.add_argument("new", help="the updated kit")
    kd.add_argument("--json", metavar="FILE", help="write the changes as JSON")
    kd.set_defaults(func=_run_of("kit.diff"))
    km = ksub.add_parser(
        "mutants",
        help="render a kit with refnpr under typical GPU-port bugs and show which cases catch them",
    )
    km.add_argument("kit_dir", help="an exported kit (refnpr kit export)")
    km.add_argument("--only", nargs="+", metavar="NAME", help="only these cases")
    km.add_argument("--bugs", nargs="+", metavar="BUG", help="only these bugs (default all)")
    km.add_argument("--json", metavar="FILE", help="write the case x bug matrix as JSON")
    km.add_argument("--markdown", action="store_true", help="print the matrix as a Markdown table")
    km.add_argument("-q", "--quiet", action="store_true", help="no progress line per case")
    km.set_defaults(func=_run_of("kit.mutants"))

    co = sub.add_parser(
        "coherence",
        help="temporal coherence of an animated scene (exact motion field)",
        description=(
            "Render frames A..B-1 of an animated scene and measure each consecutive pair with "
            "the exact motion field: warping error E, plain difference D on the same mask, "
            "E / D and the flip fraction (docs/coherence.md)."
        ),
    )
    co.add_argument(
        "scene",
        help="built-in scene name, .toml file with an [animation] table, or an animated .gltf/.glb",
    )
    _add_camera_option(co)
    _add_style_options(co, own_style)
    co.add_argument("--size", type=_size, default=(256, 192), help="WxH (default 256x192)")
    co.add_argument("--spp", type=int, default=1, help="samples per pixel of the frames (1)")
    co.add_argument(
        "--frames", metavar="A:B", help="frames A..B-1, like a Python slice (default all)"
    )
    co.add_argument(
        "--depth-rtol",
        type=float,
        help="relative depth tolerance of the visibility test (default 0.01, DEPTH_RTOL)",
    )
    co.add_argument(
        "--strokes",
        action="store_true",
        help="also measure strokes by id (TAMISS): endpoint jitter, strokes appearing/vanishing",
    )
    co.add_argument("--json", metavar="FILE.json", help="write the report as JSON")
    co.add_argument("--plot", metavar="FILE.png", help="plot the numbers over frames")
    co.add_argument("-q", "--quiet", action="store_true", help="no table")
    co.set_defaults(func=_run_of("coherence.cli"))

    w = sub.add_parser(
        "warmup",
        help="compile and cache the kernels of every style's default path (once, after install)",
        description=(
            "Render tiny frames of each style's benchmark scene and of the default scene (spp 1, "
            "and spp 4 with contours) so that numba compiles and caches their kernels now, not "
            "on the first real render (refnpr.warmup)."
        ),
    )
    w.add_argument("-q", "--quiet", action="store_true", help="print nothing (errors only)")
    w.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        help="processes compiling at once (default: one per core, at most 4; 1: this process)",
    )
    w.set_defaults(func=_cmd_warmup)
    return p


#: An option value that argparse would take for an option: a slice starting with a minus sign.
_NEGATIVE_SLICE = re.compile(r"-\d+:-?\d*")


def _slices_attached(argv: list[str]) -> list[str]:
    """``argv`` with ``--frames -10:`` written ``--frames=-10:``: argparse reads a value that
    starts with "-" (other than a plain negative number) as an option and fails. An
    abbreviation that argparse takes for ``--frames`` (``--fram``; no other option of refnpr
    starts with ``--f``) is written out in full."""
    out: list[str] = []
    for a in argv:
        prev = out[-1] if out else ""
        if len(prev) >= 3 and "--frames".startswith(prev) and _NEGATIVE_SLICE.fullmatch(a):
            out[-1] = f"--frames={a}"
        else:
            out.append(a)
    return out


def main(argv: list[str] | None = None) -> int:
    argv = _slices_attached(list(sys.argv[1:] if argv is None else argv))
    args = build_parser().parse_args(argv)
    show = warnings.showwarning

    def note(message, category, *rest, **kw):  # one line, without the source location
        from .scenes.gltf import GltfWarning

        kind = "note" if issubclass(category, GltfWarning) else "warning"
        print(f"refnpr {_command(args)}: {kind}: {message}", file=sys.stderr)

    warnings.showwarning = note
    try:
        return int(args.func(args) or 0)
    except (ValueError, TypeError, OSError) as exc:
        print(f"refnpr {_command(args)}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        warnings.showwarning = show


if __name__ == "__main__":
    sys.exit(main())
