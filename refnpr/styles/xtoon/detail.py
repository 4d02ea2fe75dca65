"""X-Toon attribute maps -> detail D (Barla et al. 2006, sec. 3.1, 3.2 and 5), evaluated on flat
arrays of samples or of vertices, and the style record of a frame."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from refnpr.formulas import xtoon
from refnpr.formulas._face import elementwise
from refnpr.raster import Camera

from . import _kernels as K
from .geometry import view_axis_depth
from .params import PARAMS

__all__ = ["TINY", "FLOW_BEHIND", "DEFAULT_DISTANCE", "style_record", "detail_values", "distances"]

TINY = xtoon.TINY
#: Flow length given to vertices behind the previous or current camera (no screen position).
FLOW_BEHIND = 1e6
#: The paper's choice per map (sec. 3.1): focal axis for LOA and aerial perspective, eye for focus.
DEFAULT_DISTANCE = {"depth": "axis", "focus": "eye"}


def distances(points: np.ndarray, camera: Camera, distance: str) -> np.ndarray:
    """(N,) float64 depth of world ``points (N, 3)`` seen from ``camera`` (X-Toon Fig. 2):
    ``"axis"``, the distance along the view axis (2b); ``"eye"``, the distance to the eye (2a)."""
    if distance == "axis":
        return view_axis_depth(points, camera)  # Fig. 2b
    return np.linalg.norm(np.asarray(points, dtype=np.float64) - camera.eye, axis=-1)  # Fig. 2a


def _box_depths(scene: Any, camera: Camera, distance: str) -> tuple[float, float]:
    corners = np.array(list(itertools.product(*zip(*scene.bounds(), strict=True))))
    z = distances(corners, camera, distance)
    near = max(float(z.min()), camera.near)
    return near, max(float(z.max()), near)


def _resolved(p: Any, scene: Any, camera: Camera) -> tuple[float, float, float]:
    """``(z_min, r, z_c)`` with the frame's defaults (see ``params.PARAMS``) and the checks
    that need the camera (the focus point ahead, z_c - r z_min > 0: footnote 2)."""
    if p.detail == "depth":
        near, far = _box_depths(scene, camera, p.distance)
        z_min = near if p.z_min is None else p.z_min
        r = max(far / z_min, 1.01) if p.r is None else p.r
        return z_min, r, 0.0
    if p.detail == "focus":
        c = np.asarray(p.focus_point, dtype=np.float64)
        ahead = float(np.dot(c - camera.eye, camera.forward))
        if ahead <= 0.0:
            raise ValueError(
                f"focus_point: {list(p.focus_point)} is behind the camera (distance {ahead:.4g} "
                f"along the view axis from eye {camera.eye.tolist()}); place the focus point in "
                "front of the camera"
            )
        z_c = float(distances(c[None], camera, p.distance)[0])
        z_min = 0.1 * z_c if p.z_min is None else p.z_min
        r = 4.0 if p.r is None else p.r
        if not z_c - r * z_min > 0.0:
            raise ValueError(
                f"z_min: with r = {r:g} the blur reaches the eye: z_c - r*z_min = {z_c:.4g} - "
                f"{r:g}*{z_min:g} <= 0 (X-Toon footnote 2 needs 0 < z_c - r z_min, z_c = "
                f"{p.distance} distance of focus_point); reduce z_min or r, or move the focus "
                "point away"
            )
        return z_min, r, z_c
    if p.detail == "orientation":
        return 1.0, 1.0 if p.r is None else p.r, 0.0
    return 1.0, 2.0, 0.0


def style_record(p: Any, texture: np.ndarray, scene: Any, camera: Camera) -> Any:
    """The style record of one frame (``PARAMS.Record``): the parameters ``p`` with z_min and
    r resolved for the frame (:func:`_resolved`), log r, the focus map's constants
    (``formulas.xtoon.focus_constants``) and the toon ``texture``'s rows and columns."""
    z_min, r, z_c = _resolved(p, scene, camera)
    focus = xtoon.focus_constants(z_c, z_min, r) if p.detail == "focus" else (0.0,) * 5
    rows, cols = np.shape(texture)[:2]
    return PARAMS.record(
        p,
        z_min=z_min,
        r=r,
        log_r=float(np.log(r)) if r > 0 else 0.0,
        focus=focus,
        rows=int(rows),
        cols=int(cols),
    )


def columns(a: np.ndarray | None, count: int = 0) -> tuple[np.ndarray, ...]:
    """The three columns of ``a (K, 3)`` float64, a ``(3,)`` vector repeated ``count`` times, or
    zeros (``a`` None): a vector argument of ``elementwise``."""
    if a is None:
        z = np.zeros(count)
        return z, z, z
    a = np.asarray(a, dtype=np.float64)
    a = np.broadcast_to(a, (count, 3)) if a.ndim == 1 else a
    return a[:, 0], a[:, 1], a[:, 2]


def detail_values(
    p: Any,
    record: Any,
    camera: Camera,
    *,
    positions: np.ndarray | None = None,
    depth: np.ndarray | None = None,
    normals: np.ndarray | None = None,
    light: np.ndarray | None = None,
    flow: np.ndarray | None = None,
    user: np.ndarray | None = None,
    count: int = 0,
) -> np.ndarray:
    """D in [0, 1] for K samples or vertices (float64 ``(K,)``), by the kernels' own
    :func:`._kernels.detail_at` for the maps of a point's geometry.

    Parameters
    ----------
    p, record : the style's parameter values and its :func:`style_record` for the frame
    positions : (K, 3) world positions (focus, orientation, highlight; depth if ``depth`` is None)
    depth : (K,) view-axis distances (depth and focus with ``distance="axis"``), optional
    normals : (K, 3) unit shading normals (orientation, highlight)
    light : (K, 3) or (3,) unit direction towards the light (highlight)
    flow : (K, 2) screen displacement in pixels (flow)
    user : (K,) D values (map)
    count : K, for ``none``
    """
    kind = p.detail
    if kind in ("depth", "focus", "orientation", "highlight"):
        k = len(positions) if positions is not None else len(depth)
        if depth is None and kind in ("depth", "focus") and p.distance == "axis":
            depth = view_axis_depth(positions, camera)  # Fig. 2b
        z = np.zeros(k) if depth is None else np.asarray(depth, dtype=np.float64)
        eye = tuple(float(c) for c in camera.eye)
        return elementwise(
            K.detail_at,
            np.float64,
            record,
            eye,
            columns(positions, k),
            columns(normals, k),
            columns(light, k),
            z,
        )
    if kind == "flow":
        # sec. 5: D = 1 up to flow_min, falling linearly to 0 at flow_max (refnpr's choice; the
        # paper only says that the flow's length assigns D)
        t = (np.linalg.norm(flow, axis=-1) - p.flow_min) / (p.flow_max - p.flow_min)
        return 1.0 - np.clip(np.nan_to_num(t, nan=1.0, posinf=1.0), 0.0, 1.0)
    if kind == "map":
        return np.asarray(user, dtype=np.float64)
    return np.ones(count)
