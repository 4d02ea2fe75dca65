"""Stroke coherence by stroke id (TAMISS): endpoint jitter after removing the true motion,
strokes appearing and vanishing (docs/coherence.md, "Strokes by id").

Works on the public outputs of the TAMISS pipeline (``PipelineResult``), reduced to plain arrays
by :func:`stroke_ends`, so any stroke renderer that can say where its strokes' drawn ends are can
be measured the same way. The jitter of an end drawn at e in frame t-1 and at e_t in frame t is
``|e_t - P_t|``, with P_t the surface point under e at t-1 (the previous camera's ray through e
cut with the triangle plane of its pixel) carried by its object's transforms and projected
through frame t's camera; an end whose 2 x 2 neighbourhood at t-1 is not all one object is not
measured. The reference is the surface the end is drawn on, what a viewer sees it slide on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.raster.projection import project_points

from ..raster import rasterize
from ..styles import ShadeContext, style_from_spec
from ..styles.tamiss.strokes import centreline
from .metrics import _Row
from .motion import _check_gbuffer, _eye_rays, _inside, _relative_transforms

__all__ = [
    "STROKE_CHANNELS",
    "StrokeEnds",
    "StrokePairMetrics",
    "frame_stroke_ends",
    "measure_strokes",
    "stroke_ends",
    "stroke_pair_metrics",
    "stroke_style",
]

#: G-buffer channels :func:`stroke_pair_metrics` reads from the previous frame.
STROKE_CHANNELS = ("dposition_dx", "dposition_dy", "mesh_id", "position")


def _scenes(scenes: Any) -> list[Any]:
    """``scenes`` checked: a sequence of at least two still Scenes."""
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


@dataclass(frozen=True, eq=False)
class StrokeEnds:
    """The drawn strokes of one frame and where their ends are.

    Attributes
    ----------
    ids : (N,) int64
        Stroke ids, sorted, unique.
    start, end : (N, 2) float64
        Pixel coordinates (x, y) of the start of the first drawn interval and the end of the
        last one.
    """

    ids: np.ndarray
    start: np.ndarray
    end: np.ndarray

    def __post_init__(self) -> None:
        ids = np.asarray(self.ids, dtype=np.int64)
        if ids.ndim != 1 or np.any(np.diff(ids) <= 0):
            raise ValueError("ids: expected a sorted 1-D array of unique stroke ids")
        for name in ("start", "end"):
            a = np.asarray(getattr(self, name), dtype=np.float64)
            if a.shape != (ids.size, 2):
                raise ValueError(f"{name}: expected shape ({ids.size}, 2), got {a.shape}")
            object.__setattr__(self, name, a)
        object.__setattr__(self, "ids", ids)


def stroke_ends(result: Any) -> StrokeEnds:
    """The drawn strokes of a TAMISS frame (``run_pipeline`` / ``TamissStyle.run``).

    A stroke is drawn when it has at least one drawn interval (``n_segments > 0``); its start is
    the drawn curve (``refnpr.styles.tamiss.strokes.centreline``: the fit, extended along its
    end tangents beyond [t_min, t_max]) at the first interval's lower t, its end at the last
    interval's upper t.
    """
    for attr in ("stroke_ids", "fit", "segments", "n_segments"):
        if not hasattr(result, attr):
            raise TypeError(
                f"result: expected a TAMISS PipelineResult (run_pipeline(...)), got "
                f"{type(result).__name__}"
            )
    ids = np.asarray(result.stroke_ids, dtype=np.int64)
    seg = np.asarray(result.segments, dtype=np.float64)  # (S, K, 2) t intervals, NaN: none
    drawn = np.asarray(result.n_segments) > 0
    with np.errstate(invalid="ignore"):
        t0 = np.where(drawn, np.nanmin(np.where(drawn[:, None], seg[..., 0], 0.0), axis=1), 0.0)
        t1 = np.where(drawn, np.nanmax(np.where(drawn[:, None], seg[..., 1], 0.0), axis=1), 0.0)
    # the drawn curve: r(t) on [t_min, t_max], its tangent extension beyond (extent "overdraw"
    # draws past the fitted range), exactly as the stroke raster places it
    x0, y0 = (v[:, 0] for v in centreline(result.fit, t0[:, None])[:2])
    x1, y1 = (v[:, 0] for v in centreline(result.fit, t1[:, None])[:2])
    order = np.argsort(ids[drawn], kind="stable")
    pick = np.flatnonzero(drawn)[order]
    return StrokeEnds(
        ids[pick], np.stack([x0[pick], y0[pick]], -1), np.stack([x1[pick], y1[pick]], -1)
    )


@dataclass(frozen=True)
class StrokePairMetrics(_Row):
    """Stroke numbers of one frame pair (t-1, t).

    Attributes
    ----------
    frame : int
    n_strokes : int
        Strokes drawn at t.
    appeared, vanished : int
        Drawn at t and not at t-1 / drawn at t-1 and not at t.
    n_ends : int
        Ends measured (two per stroke drawn in both frames, less those not measurable).
    jitter_mean, jitter_p95, jitter_max : float
        Endpoint jitter in pixels after removing the true motion (NaN when ``n_ends`` is 0).
    """

    frame: int
    n_strokes: int
    appeared: int
    vanished: int
    n_ends: int
    jitter_mean: float
    jitter_p95: float
    jitter_max: float


def _surface_points(prev_gb: Any, xy: np.ndarray):
    """World points under pixel coordinates ``xy`` (K, 2) in frame t-1, their object ids, and
    which could be measured (a one-object 2 x 2 neighbourhood inside the frame)."""
    width, height = prev_gb.width, prev_gb.height
    mesh = np.asarray(prev_gb["mesh_id"])
    ok = _inside(xy, width, height)
    xs = np.where(ok, xy[:, 0], 0.5)
    ys = np.where(ok, xy[:, 1], 0.5)
    col = np.clip(np.floor(xs).astype(np.int64), 0, width - 1)
    row = np.clip(np.floor(ys).astype(np.int64), 0, height - 1)
    ids = mesh[row, col]
    ok &= ids >= 0
    c0 = np.clip(np.floor(xs - 0.5).astype(np.int64), 0, width - 1)
    r0 = np.clip(np.floor(ys - 0.5).astype(np.int64), 0, height - 1)
    for dr in (0, 1):
        for dc in (0, 1):
            ok &= mesh[np.minimum(r0 + dr, height - 1), np.minimum(c0 + dc, width - 1)] == ids
    p0 = np.asarray(prev_gb["position"], np.float64)[row, col]
    n = np.cross(
        np.asarray(prev_gb["dposition_dx"], np.float64)[row, col],
        np.asarray(prev_gb["dposition_dy"], np.float64)[row, col],
    )
    cam = prev_gb.camera
    view = cam.view_matrix()
    proj = cam.projection_matrix(width, height)
    d = _eye_rays(xs, ys, proj, width, height) @ view[:3, :3]  # eye -> world (rotation rows)
    eye = np.asarray(cam.eye, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.einsum("ki,ki->k", n, p0 - eye) / np.einsum("ki,ki->k", n, d)
    ok &= np.isfinite(lam) & (lam > 0)
    return eye + np.where(ok, lam, 0.0)[:, None] * d, np.where(ok, ids, 0), ok


def carried_points(
    prev_gb: Any, xy: np.ndarray, scene: Any, prev_scene: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates ``xy`` (K, 2) of frame t-1 carried to frame t by the true motion.

    The surface point under each (:func:`_surface_points`) goes through its object's transforms
    (``T_i(t) T_i(t-1)^-1``) and frame t's camera. Returns the points at t (K, 2) and which
    could be carried (on a one-object neighbourhood at t-1, inside frame t's depth range); the
    others hold meaningless finite values.
    """
    p, ids, ok = _surface_points(prev_gb, xy)
    rel = np.linalg.inv(_relative_transforms(scene, prev_scene))  # world at t-1 -> world at t
    m = rel[ids]
    p_now = np.einsum("kij,kj->ki", m[:, :3, :3], p) + m[:, :3, 3]
    cam = scene.camera
    width, height = prev_gb.width, prev_gb.height
    now, w = project_points(p_now, cam.view_projection(width, height), width, height)
    ok &= (w >= cam.near) & (w <= cam.far)
    return np.where(ok[:, None], now, 0.0), ok


def stroke_pair_metrics(
    ends: StrokeEnds,
    prev_ends: StrokeEnds,
    prev_gb: Any,
    scene: Any,
    prev_scene: Any,
    *,
    frame: int = 1,
) -> StrokePairMetrics:
    """Endpoint jitter and strokes appearing / vanishing between frames t-1 and t.

    Parameters
    ----------
    ends, prev_ends : StrokeEnds
        Frames t and t-1 (:func:`stroke_ends`).
    prev_gb : GBuffer
        Frame t-1 at spp 1 with ``position``, ``dposition_dx``, ``dposition_dy``, ``mesh_id``
        (float64 recommended); its ``camera`` is the previous camera.
    scene, prev_scene : Scene
        The still scenes of t and t-1; frame t's camera is ``scene.camera``.
    frame : int
        t, recorded in the result.

    Returns
    -------
    StrokePairMetrics
    """
    for name, e in (("ends", ends), ("prev_ends", prev_ends)):
        if not isinstance(e, StrokeEnds):
            raise TypeError(
                f"{name}: expected StrokeEnds (stroke_ends(...)), got {type(e).__name__}"
            )
    _check_gbuffer("prev_gb", prev_gb, STROKE_CHANNELS)
    common, i_now, i_prev = np.intersect1d(ends.ids, prev_ends.ids, return_indices=True)
    appeared = int(ends.ids.size - common.size)
    vanished = int(prev_ends.ids.size - common.size)
    e_prev = np.concatenate([prev_ends.start[i_prev], prev_ends.end[i_prev]])
    e_now = np.concatenate([ends.start[i_now], ends.end[i_now]])
    true_now, ok = carried_points(prev_gb, e_prev, scene, prev_scene)
    jitter = np.hypot(*(e_now - true_now)[ok].T) if ok.any() else np.zeros(0)
    nan = float("nan")
    return StrokePairMetrics(
        frame=int(frame),
        n_strokes=int(ends.ids.size),
        appeared=appeared,
        vanished=vanished,
        n_ends=int(jitter.size),
        jitter_mean=float(jitter.mean()) if jitter.size else nan,
        jitter_p95=float(np.percentile(jitter, 95)) if jitter.size else nan,
        jitter_max=float(jitter.max()) if jitter.size else nan,
    )


def stroke_style(style: Any) -> Any | None:
    """The TAMISS style that draws the strokes of ``style``: the style itself when it has
    ``run(ctx) -> PipelineResult``, the style it wraps (``contoured``'s ``base``), else None."""
    for s in (style, getattr(style, "base", None)):
        if s is not None and callable(getattr(s, "run", None)):
            return s
    return None


def frame_stroke_ends(
    style: Any,
    scene: Any,
    width: int,
    height: int,
    state: Any = None,
    run_kwargs: dict | None = None,
) -> tuple[StrokeEnds, Any, Any]:
    """Rasterize one frame for a stroke style: its drawn stroke ends, G-buffer and next state.

    The G-buffer is at spp 1 (float64 unless the style's ``raster_options`` name a dtype) with
    the style's channels plus ``STROKE_CHANNELS``. The strokes come from
    ``style.run_frame(ctx, state)`` (the style's state across frames: hash tables, aggregate
    history, smoothed fits), or from ``style.run(ctx, **run_kwargs)`` when ``run_kwargs`` is
    given or the style has no ``run_frame`` (the state passes through).
    """
    channels = sorted(set(style.requires(scene)) | set(STROKE_CHANNELS))
    options = {"dtype": np.float64, **style.raster_options(scene)}  # the style's dtype wins
    gb = rasterize(scene, None, width, height, channels, 1, **options)
    ctx = ShadeContext(gb, scene)
    if run_kwargs is not None or not hasattr(style, "run_frame"):
        return stroke_ends(style.run(ctx, **(run_kwargs or {}))), gb, state
    result, state = style.run_frame(ctx, state)
    return stroke_ends(result), gb, state


def measure_strokes(
    scenes: Sequence[Any],
    style: Any,
    width: int,
    height: int,
    *,
    frames: Sequence[int] | None = None,
    run_kwargs: dict | None = None,
) -> list[StrokePairMetrics]:
    """Run a stroke style on consecutive still scenes and measure every pair's strokes.

    Parameters
    ----------
    scenes : sequence of Scene
        At least two consecutive still scenes.
    style : Style, str or dict
        A TAMISS style, or a style wrapping one (``contoured``); see :func:`stroke_style`.
    width, height : int
    frames : sequence of int, optional
        Frame numbers of ``scenes`` (default 0, 1, ...).
    run_kwargs : dict, optional
        Passed to ``style.run`` every frame, e.g. ``{"history": AggregateHistory(3)}`` (the
        same object for every frame, in order). Without it the frames run in order through
        the style's own sequence state (``run_frame``: its ``average_frames``, ``smooth``,
        hashed aggregation), as in a render of the sequence.

    Returns
    -------
    list of StrokePairMetrics
        One per consecutive pair.
    """
    base = style_from_spec(style)
    strokes = stroke_style(base)
    if strokes is None:
        raise TypeError(
            f"style: expected a stroke style (TAMISS, with run(ctx) -> PipelineResult, or a "
            f"style wrapping one), got {base.name!r}"
        )
    scenes = _scenes(scenes)
    frames = list(range(len(scenes))) if frames is None else list(frames)
    rows, prev = [], None
    state = strokes.initial_state() if run_kwargs is None else None
    for t, sc in enumerate(scenes):
        ends, gb, state = frame_stroke_ends(strokes, sc, width, height, state, run_kwargs)
        if prev is not None:
            rows.append(stroke_pair_metrics(ends, prev[0], prev[1], sc, prev[2], frame=frames[t]))
        prev = (ends, gb, sc)
    return rows
