"""``refnpr coherence SCENE``: temporal-coherence numbers of an animated scene's frames.

Wired into the ``refnpr`` command by ``refnpr.cli`` (``add_parser(subparsers)``); ``run(args)``
does the work and returns the exit status.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import math
import tomllib
from typing import Any

__all__ = ["add_parser", "run", "parse_frames"]

DEFAULT_SIZE = (256, 192)
# The renderer is imported by run(), not here: building the `refnpr` parser stays cheap.


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--size: expected WxH such as 256x192, got {text!r}"
        ) from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(f"--size: width and height must be positive, got {text!r}")
    return w, h


def _param(text: str) -> tuple[str, object]:
    key, sep, raw = text.partition("=")
    if not sep or not key.strip() or not raw.strip():
        raise argparse.ArgumentTypeError(f"--param: expected KEY=VALUE such as n=3, got {text!r}")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw  # a bare word is a string
    return key.strip(), value


def parse_frames(text: str | None, count: int) -> range:
    """Frames ``A .. B - 1`` of ``A:B`` (a Python slice: B excluded, either end may be left out,
    negative numbers count from the end); None: every frame. At least two frames (one pair).

    Raises
    ------
    ValueError
        Malformed text, or a range outside ``[0, count)`` or shorter than two frames.
    """
    if text is None:
        a, b = 0, count
    else:
        parts = text.split(":")
        try:
            if len(parts) != 2:
                raise ValueError
            a, b = (int(p) if p.strip() else None for p in parts)
        except ValueError:
            raise ValueError(
                f"--frames: expected A:B (frames A to B - 1, e.g. 0:24 or 10:), got {text!r}"
            ) from None
        a = 0 if a is None else (a + count if a < 0 else a)
        b = count if b is None else (b + count if b < 0 else b)
    if not 0 <= a < b <= count or b - a < 2:
        raise ValueError(
            f"--frames: {text!r} selects {max(b - a, 0)} of the scene's {count} frames "
            f"(0..{count - 1}); coherence needs at least two consecutive frames, A:B with "
            f"0 <= A < B - 1 < {count}"
        )
    return range(a, b)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``coherence`` command to ``subparsers`` (from ``ArgumentParser.add_subparsers``)."""
    p = subparsers.add_parser(
        "coherence",
        help="temporal coherence of an animated scene (exact motion field)",
        description=(
            "Render frames A..B-1 of an animated scene and measure each consecutive pair with "
            "the exact motion field: warping error E, plain difference D on the same mask, "
            "E / D and the flip fraction (docs/coherence.md)."
        ),
    )
    p.add_argument("scene", help="built-in scene name or .toml file with an [animation] table")
    p.add_argument("--style", default=None, help="style name (default: the scene's own style)")
    p.add_argument(
        "--param", action="append", type=_param, metavar="KEY=VALUE", help="style parameter"
    )
    p.add_argument("--size", type=_size, default=DEFAULT_SIZE, help="WxH (default 256x192)")
    p.add_argument("--spp", type=int, default=1, help="samples per pixel of the frames (1)")
    p.add_argument("--frames", default=None, metavar="A:B", help="frames A..B-1 (default all)")
    p.add_argument(
        "--depth-rtol",
        type=float,
        default=None,
        help="relative depth tolerance of the visibility test (default 0.01, DEPTH_RTOL)",
    )
    p.add_argument(
        "--strokes",
        action="store_true",
        help="also measure strokes by id (TAMISS): endpoint jitter, strokes appearing/vanishing",
    )
    p.add_argument("--json", default=None, metavar="FILE", help="write the report as JSON")
    p.add_argument("--plot", default=None, metavar="FILE.png", help="plot the numbers over frames")
    p.add_argument("-q", "--quiet", action="store_true", help="no table")
    p.set_defaults(func=run)
    return p


def _fmt(v: float) -> str:
    return "       -" if math.isnan(v) else f"{v:8.5f}"


def _previous(scene: Any, start: int) -> Any:
    """The still of frame ``start - 1`` (what the style's ``for_frame`` sees as the previous
    frame of the first one measured), or None at frame 0."""
    return None if start == 0 else scene.at(start - 1)


def run(args: argparse.Namespace) -> int:
    """The ``refnpr coherence`` command; returns 0 (errors are ValueError / TypeError)."""
    from ..image import check_png_path
    from ..scenes import load_scene
    from .driver import measure
    from .motion import DEPTH_RTOL

    if args.plot is not None:
        check_png_path(args.plot)  # before rendering, not after
        if importlib.util.find_spec("matplotlib") is None:
            raise ValueError("--plot: needs matplotlib (`pip install matplotlib`)")
    if args.style is not None and not args.style.strip():
        raise ValueError(f"--style: expected a style name, got {args.style!r}")
    params: dict[str, object] = {}
    for key, value in args.param or []:
        if key == "name" or key in params:
            raise ValueError(f"--param: {key!r} is the style's name or given twice; give it once")
        params[key] = value
    scene = load_scene(args.scene)
    count = getattr(scene, "frames", 1)
    if getattr(scene, "animation", None) is None or count < 2:
        raise ValueError(
            f"scene: {args.scene!r} is a still (no [animation] table with 2 or more frames); "
            "coherence compares consecutive frames of an animated scene"
        )
    frames = parse_frames(args.frames, count)
    stills = [scene.at(f) for f in frames]
    style = None
    if args.style:
        style = {"name": args.style, **params}
    elif params:
        if not stills[0].style:
            raise ValueError(
                f"--param needs --style: the scene {args.scene!r} names no style; add --style NAME"
            )
        stills = [dataclasses.replace(s, style={**s.style, **params}) for s in stills]
    width, height = args.size
    report = measure(
        stills,
        style,
        width,
        height,
        args.spp,
        depth_rtol=DEPTH_RTOL if args.depth_rtol is None else args.depth_rtol,
        frames=list(frames),
        strokes=args.strokes,
        previous=_previous(scene, frames.start),
    )
    if args.json:
        report.save(args.json)
    if args.plot:
        report.plot(args.plot)
    if not args.quiet:
        print(
            f"{scene.name}: frames {frames.start}..{frames.stop - 1}, style "
            f"{report.meta['style']}, {width}x{height} spp {args.spp}"
        )
        print("   frame  warp_err  plain_diff  ratio     flip  flip_plain  motion_px  n_valid")
        for r in report.rows:
            print(
                f"{r.frame:8d} {_fmt(r.warp_error)} {_fmt(r.plain_diff)}  {_fmt(r.ratio)} "
                f"{_fmt(r.flip)} {_fmt(r.flip_plain)}  {_fmt(r.motion_px)}  {r.n_valid:7d}"
            )
        s = report.summary()
        for stat in ("median", "max"):
            keys = ("warp_error", "plain_diff", "ratio", "flip", "flip_plain", "motion_px")
            vals = [s[k][stat] for k in keys]
            cells = " ".join(_fmt(float("nan") if v is None else v) for v in vals)
            print(f"{stat:>8} {cells}")
        if report.strokes:
            print("   frame  strokes  appeared  vanished  ends  jitter_mean  jitter_p95  (px)")
            for r in report.strokes:
                print(
                    f"{r.frame:8d} {r.n_strokes:8d} {r.appeared:9d} {r.vanished:9d} "
                    f"{r.n_ends:5d}     {_fmt(r.jitter_mean)}    {_fmt(r.jitter_p95)}"
                )
    return 0
