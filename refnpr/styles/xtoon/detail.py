"""X-Toon attribute maps -> detail D (Barla et al. 2006, sec. 3.1, 3.2 and 5), evaluated on flat
arrays of samples or of vertices.

Which depth (Fig. 2): by default ``depth`` (levels of abstraction, aerial perspective) uses the
**view-axis distance** (Fig. 2b; the G-buffer ``depth`` channel, w_clip) and ``focus`` (depth of
field) the **Euclidean distance to the eye** (Fig. 2a), with z_c that distance of the focus
point, as the paper prefers; ``distance="axis"`` or ``"eye"`` picks either for either map.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.formulas import xtoon
from refnpr.raster import Camera

from .geometry import view_axis_depth

__all__ = [
    "DISTANCES",
    "DetailParams",
    "FrameDetail",
    "resolve_frame",
    "detail_values",
    "flow_detail",
    "distances",
]

#: Distances are clamped to at least this before the log of sec. 3.1 (vertices at or behind
#: the eye get D = 1 in the per-vertex mode instead of a NaN).
TINY = 1e-9
#: Flow length given to vertices behind the previous or current camera (no screen position).
FLOW_BEHIND = 1e6
#: The two depths of a point of X-Toon Fig. 2: along the view (focal) axis, or to the eye.
DISTANCES = ("axis", "eye")
#: The paper's choice per map (sec. 3.1): focal axis for LOA and aerial perspective, eye for focus.
DEFAULT_DISTANCE = {"depth": "axis", "focus": "eye"}


@dataclass(frozen=True, eq=False)
class DetailParams:
    """The style's validated detail-map parameters (see ``XToonStyle``)."""

    kind: str
    z_min: float | None = None
    r: float | None = None
    focus_point: tuple[float, float, float] | None = None
    s: float = 16.0
    one_sided: bool = False
    prev_camera: Camera | None = None
    flow_min: float = 0.0
    flow_max: float = 16.0
    user_map: np.ndarray | None = None
    distance: str | None = None  # "axis" or "eye" for depth and focus (Fig. 2), else None
    prev_transforms: np.ndarray | None = None  # (M, 4, 4) previous object transforms (flow)


@dataclass(frozen=True)
class FrameDetail:
    """Per-frame constants: z_min and r after defaults, z_c for ``focus``."""

    z_min: float = 1.0
    r: float = 2.0
    z_focus: float = 0.0


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


def resolve_frame(p: DetailParams, scene: Any, camera: Camera) -> FrameDetail:
    """Defaults that depend on the frame, and the checks that need the camera.

    ``depth``: z_min defaults to the nearest depth (``p.distance``) of the scene's bounding box
    corners (at least the near plane) and r to (farthest corner depth) / z_min (at least 1.01).
    ``focus``: z_c is the focus point's depth (``p.distance``), z_min defaults to 0.1 z_c and r
    to 4; the focus point must lie in front of the camera and z_c - r z_min > 0 (footnote 2).
    ``orientation``: r defaults to 1.
    """
    if p.kind == "depth":
        near, far = _box_depths(scene, camera, p.distance)
        z_min = near if p.z_min is None else p.z_min
        r = max(far / z_min, 1.01) if p.r is None else p.r
        return FrameDetail(z_min, r)
    if p.kind == "focus":
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
        return FrameDetail(z_min, r, z_c)
    if p.kind == "orientation":
        return FrameDetail(r=1.0 if p.r is None else p.r)
    return FrameDetail()


def flow_detail(length: np.ndarray, flow_min: float, flow_max: float) -> np.ndarray:
    """D from the optical-flow length in pixels (X-Toon sec. 5): 1 up to ``flow_min``, falling
    linearly to 0 at ``flow_max`` (refnpr's choice; the paper only says the length assigns D)."""
    t = (np.asarray(length, dtype=np.float64) - flow_min) / (flow_max - flow_min)
    return 1.0 - np.clip(np.nan_to_num(t, nan=1.0, posinf=1.0), 0.0, 1.0)


def detail_values(
    p: DetailParams,
    f: FrameDetail,
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
    """D in [0, 1] for K samples or vertices (float64 ``(K,)``).

    Parameters
    ----------
    positions : (K, 3) world positions (focus, orientation, highlight; depth if ``depth`` is None)
    depth : (K,) view-axis distances (depth and focus with ``distance="axis"``), optional
    normals : (K, 3) unit shading normals (orientation, highlight)
    light : (K, 3) or (3,) unit direction towards the light (highlight)
    flow : (K, 2) screen displacement in pixels (flow)
    user : (K,) D values (map)
    count : K, for ``none``
    """
    kind = p.kind
    if kind in ("depth", "focus"):
        if depth is not None and p.distance == "axis":
            z = np.asarray(depth, dtype=np.float64)  # the G-buffer depth: Fig. 2b
        else:
            z = distances(positions, camera, p.distance)  # Fig. 2a or 2b
        z = np.maximum(z, TINY)
        if kind == "depth":
            return xtoon.detail_depth(z, f.z_min, f.r)  # sec. 3.1: D = 1 - log_r(z / z_min)
        return xtoon.detail_focus(z, f.z_focus, f.z_min, f.r)  # sec. 3.1, depth of field
    if kind in ("orientation", "highlight"):
        v = camera.eye - positions
        v = v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), TINY)
        if kind == "orientation":
            n_dot_v = np.einsum("kc,kc->k", normals, v)
            return xtoon.detail_orientation(np.clip(n_dot_v, -1.0, 1.0), f.r)  # sec. 3.2
        n_dot_l = np.sum(normals * light, axis=-1, keepdims=True)
        refl = 2.0 * n_dot_l * normals - light  # reflection of the light vector about n
        v_dot_r = np.einsum("kc,kc->k", v, refl)
        return xtoon.detail_highlight(np.clip(v_dot_r, -1.0, 1.0), p.s, one_sided=p.one_sided)
    if kind == "flow":
        return flow_detail(np.linalg.norm(flow, axis=-1), p.flow_min, p.flow_max)  # sec. 5
    if kind == "map":
        return np.asarray(user, dtype=np.float64)
    return np.ones(count)
