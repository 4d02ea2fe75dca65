"""X-Toon attribute maps -> detail D (Barla et al. 2006, sec. 3.1, 3.2 and 5), evaluated on flat
arrays of samples or of vertices.

Which depth (Fig. 2): by default ``depth`` (levels of abstraction, aerial perspective) uses the
**view-axis distance** (Fig. 2b; the G-buffer ``depth`` channel, w_clip) and ``focus`` (depth of
field) the **Euclidean distance to the eye** (Fig. 2a), with z_c that distance of the focus
point, as the paper prefers; ``distance="axis"`` or ``"eye"`` picks either for either map.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr.formulas import xtoon
from refnpr.formulas._face import elementwise
from refnpr.raster import Camera

from . import _kernels as K
from .geometry import view_axis_depth
from .params import DISTANCES, PARAMS

__all__ = [
    "DISTANCES",
    "TINY",
    "FLOW_BEHIND",
    "DEFAULT_DISTANCE",
    "style_record",
    "texels",
    "detail_values",
    "flow_detail",
    "distances",
]

#: Distances are clamped to at least this before the log of sec. 3.1 (vertices at or behind
#: the eye get D = 1 in the per-vertex mode instead of a NaN).
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
    lo, hi = scene.bounds()
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    z = distances(corners, camera, distance)
    near = max(float(z.min()), camera.near)
    return near, max(float(z.max()), near)


def _resolved(p: Any, scene: Any, camera: Camera) -> tuple[float, float, float]:
    """``(z_min, r, z_c)`` after the defaults that depend on the frame, with the checks that
    need the camera.

    ``depth``: z_min defaults to the nearest depth (``p.distance``) of the scene's bounding box
    corners (at least the near plane) and r to (farthest corner depth) / z_min (at least 1.01).
    ``focus``: z_c is the focus point's depth (``p.distance``), z_min defaults to 0.1 z_c and r
    to 4; the focus point must lie in front of the camera and z_c - r z_min > 0 (footnote 2).
    ``orientation``: r defaults to 1.
    """
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


def texels(texture: np.ndarray) -> np.ndarray:
    """The toon ``texture (rows, cols, 4)``'s float32 values as a flat float64 array (exact:
    the kernel's loads need no conversion)."""
    tex32 = np.asarray(texture, dtype=np.float32)
    return np.ascontiguousarray(tex32, dtype=np.float64).reshape(-1)


def flow_detail(length: np.ndarray, flow_min: float, flow_max: float) -> np.ndarray:
    """D from the optical-flow length in pixels (X-Toon sec. 5): 1 up to ``flow_min``, falling
    linearly to 0 at ``flow_max`` (refnpr's choice; the paper only says the length assigns D)."""
    t = (np.asarray(length, dtype=np.float64) - flow_min) / (flow_max - flow_min)
    return 1.0 - np.clip(np.nan_to_num(t, nan=1.0, posinf=1.0), 0.0, 1.0)


def _rows(a: np.ndarray | None, count: int) -> tuple[np.ndarray, ...]:
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
    p : the style's parameter values; record : its :func:`style_record` for the frame
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
            _rows(positions, k),
            _rows(normals, k),
            _rows(light, k),
            z,
        )
    if kind == "flow":
        return flow_detail(np.linalg.norm(flow, axis=-1), p.flow_min, p.flow_max)  # sec. 5
    if kind == "map":
        return np.asarray(user, dtype=np.float64)
    return np.ones(count)
