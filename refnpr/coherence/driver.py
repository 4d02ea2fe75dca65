"""``measure``: render a sequence of still scenes in order and measure each consecutive pair."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..raster import rasterize
from ..render import DEFAULT_STYLE, RenderContext, _check_args
from ..scenes._params import check_int
from ..styles import Style, style_from_spec
from .metrics import pair_metrics
from .motion import DEPTH_RTOL, MOTION_CHANNELS, motion_field
from .report import CoherenceReport
from .strokes import _scenes, frame_stroke_ends, stroke_pair_metrics, stroke_style

__all__ = ["measure", "render_frame"]


def render_frame(
    style: Style, scene: Any, width: int, height: int, spp: int, state: Any
) -> tuple[np.ndarray, Any]:
    """One frame of a sequence through the style protocol (``style.shade_frame`` from
    ``state``): :meth:`refnpr.render.RenderContext.render_frame`, bit-identical to
    :func:`refnpr.render.render` for a stateless style.

    Returns
    -------
    rgba : (H, W, 4) float32
        Linear straight-alpha pixels over ``scene.background``.
    state
        The style's state for the next frame.
    """
    ctx = RenderContext(scene, style, width, height, spp)
    image, state = ctx.render_frame(scene, style, state, copy=True)
    return image.rgba, state


def measure(
    scenes: Sequence[Any],
    style: Any = None,
    width: int = 256,
    height: int = 256,
    spp: int = 1,
    *,
    depth_rtol: float = DEPTH_RTOL,
    frames: Sequence[int] | None = None,
    keep_images: bool = False,
    strokes: bool = False,
    progress: Callable[[int, int], None] | None = None,
    previous: Any = None,
) -> CoherenceReport:
    """Render ``scenes`` in order with ``style`` and measure every consecutive pair.

    Frame t is shaded through the sequence protocol (``for_frame(scenes[t], scenes[t-1])``, then
    ``shade_frame`` from the previous frame's state), so stateful styles see their frames in
    order; its exact motion field comes from a separate G-buffer (spp 1, float64,
    ``MOTION_CHANNELS``).

    Parameters
    ----------
    scenes : sequence of Scene
        Still scenes of consecutive frames (``[anim.at(f) for f in range(a, b)]``), at least
        two, with the same objects and meshes.
    style : Style, str, dict or None
        One style for every frame, as for :func:`refnpr.render.render`; None: each frame's own
        ``scene.style`` table (so animated style parameters follow the frames; a new style is
        built when the table changes, the state still carries over), else ``DEFAULT_STYLE``.
    width, height : int
        Image size in pixels.
    spp : int
        Samples per pixel of the rendered frames (the motion G-buffer is always spp 1).
    depth_rtol : float
        Depth-test tolerance of :func:`refnpr.coherence.motion_field`.
    frames : sequence of int, optional
        Frame numbers of ``scenes`` (for the rows and the plot); default 0, 1, 2, ...
    keep_images : bool
        Keep the rendered frames in ``report.images``.
    strokes : bool
        Also measure the strokes by stroke id (``report.strokes``; a stroke style such as
        TAMISS, or one wrapping it), from runs of its pipeline on a pixel-resolution G-buffer
        in frame order through the style's own state (``run_frame``), as a render does.
    progress : callable(done, total), optional
        Called after each frame.
    previous : Scene, optional
        The still of the frame before ``scenes[0]`` (``anim.at(a - 1)``), given to
        ``style.for_frame`` for the first frame so that a style reading the previous frame
        (X-Toon's optical flow) renders it as in the whole sequence; not rendered or measured.
        None: the first frame has no previous frame, as frame 0 of a sequence.

    Returns
    -------
    CoherenceReport
    """
    scenes = _scenes(scenes)
    if previous is not None and (
        not hasattr(previous, "world_meshes") or not hasattr(previous, "camera")
    ):
        raise TypeError(
            f"previous: expected the still Scene of the frame before scenes[0] (anim.at(a - 1)) "
            f"or None, got {type(previous).__name__}"
        )
    width, height, spp = _check_args(width, height, spp)
    if frames is None:
        frames = list(range(len(scenes)))
    else:
        frames = [check_int(f"frames[{i}]", f) for i, f in enumerate(frames)]
        if len(frames) != len(scenes):
            raise ValueError(
                f"frames: got {len(frames)} frame numbers for {len(scenes)} scenes; give one "
                "per scene"
            )
    if progress is not None and not callable(progress):
        raise TypeError(f"progress: expected a callable(done, total) or None, got {progress!r}")
    own = style is None  # each frame's own style table (animated style parameters follow)
    base = style_from_spec(scenes[0].style or DEFAULT_STYLE if own else style)
    spec = scenes[0].style
    state = base.initial_state()
    if strokes and stroke_style(base) is None:
        raise TypeError(
            f"strokes: style {base.name!r} draws no strokes by id; strokes=True needs a stroke "
            "style (TAMISS, or one wrapping it)"
        )
    rows, images, stroke_rows = [], [], []
    prev_scene = prev_rgba = prev_gb = prev_ends = None
    stroke_state = ctx = None
    for t, scene in enumerate(scenes):
        if own and scene.style != spec:
            spec = scene.style
            base = style_from_spec(spec or DEFAULT_STYLE)
        frame_style = base.for_frame(scene, previous if t == 0 else prev_scene)
        ctx = ctx or RenderContext(scene, frame_style, width, height, spp)
        image, state = ctx.render_frame(scene, frame_style, state, copy=True)
        rgba = image.rgba
        gb = rasterize(scene, None, width, height, MOTION_CHANNELS, 1, dtype=np.float64)
        if prev_scene is not None:
            motion = motion_field(gb, prev_gb, scene, prev_scene, depth_rtol=depth_rtol)
            rows.append(pair_metrics(rgba, prev_rgba, motion, frame=frames[t]))
        if strokes:
            stroker = stroke_style(frame_style)
            if t == 0:
                stroke_state = stroker.initial_state()
            ends, sgb, stroke_state = frame_stroke_ends(stroker, scene, width, height, stroke_state)
            if prev_ends is not None:
                row = stroke_pair_metrics(ends, *prev_ends, scene, prev_scene, frame=frames[t])
                stroke_rows.append(row)
            prev_ends = (ends, sgb)
        if keep_images:
            images.append(rgba)
        prev_scene, prev_rgba, prev_gb = scene, rgba, gb
        if progress is not None:
            progress(t + 1, len(scenes))
    meta = {
        "style": base.name,
        "style_params": {k: repr(v) for k, v in base.params().items()},
        "scene": getattr(scenes[0], "name", ""),
        "size": [width, height],
        "spp": spp,
        "depth_rtol": float(depth_rtol),
        "frames": list(frames),
        "luminance": "Rec. 709 Y of linear RGB",
    }
    return CoherenceReport(tuple(rows), meta, tuple(images), tuple(stroke_rows))
