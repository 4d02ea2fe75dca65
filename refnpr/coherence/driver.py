"""``measure``: render a sequence of still scenes in order and measure each consecutive pair."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..raster import rasterize
from ..render import DEFAULT_STYLE, composite_resolve
from ..scenes._params import check_int
from ..styles import ShadeContext, Style, style_from_spec
from .metrics import pair_metrics
from .motion import DEPTH_RTOL, MOTION_CHANNELS, motion_field
from .report import CoherenceReport
from .strokes import frame_stroke_ends_from, stroke_pair_metrics, stroke_style

__all__ = ["measure", "render_frame"]


def _scenes(scenes: Any) -> list[Any]:
    if isinstance(scenes, (str, bytes)) or not isinstance(scenes, Sequence):
        raise TypeError(
            f"scenes: expected a sequence of still Scenes (e.g. [anim.at(f) for f in "
            f"range(n)]), got {type(scenes).__name__}"
        )
    scenes = list(scenes)
    if len(scenes) < 2:
        raise ValueError(f"scenes: need at least two frames to measure a pair, got {len(scenes)}")
    for i, s in enumerate(scenes):
        if not hasattr(s, "world_meshes") or not hasattr(s, "camera"):
            raise TypeError(f"scenes[{i}]: expected a refnpr.scenes.Scene, got {type(s).__name__}")
    return scenes


def render_frame(
    style: Style, scene: Any, width: int, height: int, spp: int, state: Any
) -> tuple[np.ndarray, Any]:
    """One frame of a sequence through the style protocol (``refnpr.styles.base.Style``).

    Rasterizes exactly ``style.requires(scene)`` with ``style.raster_options(scene)``, shades
    with ``style.shade_frame`` from ``state`` and composites and resolves as
    :func:`refnpr.render.render` does (bit-identical to it for a stateless style).

    Returns
    -------
    rgba : (H, W, 4) float32
        Linear straight-alpha pixels over ``scene.background``.
    state
        The style's state for the next frame.
    """
    channels = sorted(style.requires(scene))
    gb = rasterize(scene, None, width, height, channels, spp, **style.raster_options(scene))
    rgba, state = style.shade_frame(ShadeContext(gb, scene), state)
    rgba = np.asarray(rgba, dtype=np.float32)
    if rgba.shape != gb.sample_shape + (4,):
        raise ValueError(
            f"style {style.name!r} returned shape {rgba.shape}; expected {gb.sample_shape + (4,)}"
        )
    return composite_resolve(rgba, gb.n, scene.background, style_name=style.name), state


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

    Frame t is shaded through the sequence protocol: ``style.for_frame(scenes[t],
    scenes[t-1])`` (None for t = 0), then ``shade_frame`` with the state the previous frame
    returned (``style.initial_state()`` for the first), so stateful styles see their frames in
    order. Each frame is rendered at ``spp``; its exact motion field comes from a separate
    pixel-resolution G-buffer (spp 1, float64, ``MOTION_CHANNELS``).

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
        TAMISS, or one wrapping it): each frame's strokes come from a run of the style's
        pipeline on a pixel-resolution G-buffer (``strokes.frame_stroke_ends_from``), in frame
        order through the style's own state across frames (``run_frame``: aggregate history,
        smoothed fits, hash tables), as the sequence's render does.
    progress : callable(done, total), optional
        Called after each frame.
    previous : Scene, optional
        The still of the frame before ``scenes[0]`` (``anim.at(a - 1)`` when measuring frames
        ``a, a + 1, ...`` with a > 0): given to ``style.for_frame`` for the first frame, so
        that a style that reads the previous frame (X-Toon's optical-flow detail) renders it
        as in the whole sequence. It is not rendered or measured. None (default): the first
        frame has no previous frame, as frame 0 of a sequence.

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
    width = check_int("width", width, minimum=1)
    height = check_int("height", height, minimum=1)
    spp = check_int("spp", spp, minimum=1)
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
    stroke_state = None
    for t, scene in enumerate(scenes):
        if own and scene.style != spec:
            spec = scene.style
            base = style_from_spec(spec or DEFAULT_STYLE)
        frame_style = base.for_frame(scene, previous if t == 0 else prev_scene)
        rgba, state = render_frame(frame_style, scene, width, height, spp, state)
        gb = rasterize(scene, None, width, height, MOTION_CHANNELS, 1, dtype=np.float64)
        if prev_scene is not None:
            motion = motion_field(gb, prev_gb, scene, prev_scene, depth_rtol=depth_rtol)
            rows.append(pair_metrics(rgba, prev_rgba, motion, frame=frames[t]))
        if strokes:
            stroker = stroke_style(frame_style)
            if t == 0:
                stroke_state = stroker.initial_state()
            ends, sgb, stroke_state = frame_stroke_ends_from(
                stroker, scene, width, height, stroke_state
            )
            if prev_ends is not None:
                stroke_rows.append(
                    stroke_pair_metrics(
                        ends, prev_ends[0], prev_ends[1], scene, prev_scene, frame=frames[t]
                    )  # fmt: skip
                )
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
