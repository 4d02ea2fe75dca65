"""``refnpr coherence SCENE``: temporal-coherence numbers of an animated scene's frames.

``refnpr.cli`` builds the command's parser; ``run(args)`` does the work. The renderer is imported
by run(), not here: building the `refnpr` parser stays cheap.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import math

__all__ = ["run", "parse_frames"]


def parse_frames(text: str | None, count: int) -> range:
    """Frames ``A .. B - 1`` of ``A:B`` (as :func:`refnpr.sequence.frame_range`); None: every
    frame. At least two frames (one pair).

    Raises
    ------
    ValueError
        Malformed text, or a range outside ``[0, count)`` or shorter than two frames.
    """
    from ..sequence import frame_range

    try:
        frames = frame_range(text, count)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"--frames: {exc}") from None
    if len(frames) < 2:
        raise ValueError(
            f"--frames: {text!r} selects {len(frames)} of the scene's {count} frames "
            f"(0..{count - 1}); coherence needs at least two consecutive frames, A:B with "
            f"0 <= A < B - 1 < {count}"
        )
    return frames


def _fmt(v: float | None) -> str:
    return "       -" if v is None or math.isnan(v) else f"{v:8.5f}"


def run(args: argparse.Namespace) -> int:
    """The ``refnpr coherence`` command; returns 0 (errors are ValueError / TypeError)."""
    from .._atomic import check_output_file
    from ..image import check_png_path
    from ..scenes import load_scene
    from .driver import measure
    from .motion import DEPTH_RTOL

    if args.json is not None:
        check_output_file(args.json, "--json", ".json")  # before rendering, not after
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
    scene = load_scene(args.scene, camera=getattr(args, "camera", None))
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
        previous=scene.at(frames.start - 1) if frames.start > 0 else None,
    )
    if args.json is not None:
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
        keys = ("warp_error", "plain_diff", "ratio", "flip", "flip_plain", "motion_px")
        for stat in ("median", "max"):
            print(f"{stat:>8} {' '.join(_fmt(s[k][stat]) for k in keys)}")
        if report.strokes:
            print("   frame  strokes  appeared  vanished  ends  jitter_mean  jitter_p95  (px)")
            for r in report.strokes:
                print(
                    f"{r.frame:8d} {r.n_strokes:8d} {r.appeared:9d} {r.vanished:9d} "
                    f"{r.n_ends:5d}     {_fmt(r.jitter_mean)}    {_fmt(r.jitter_p95)}"
                )
    return 0
