"""Aggregates carried along the exact surface motion (refnpr's motion-compensated averaging).

The paper averages aggregates over frames against jitter (sec. 4.1); averaged as they are, the
sums of earlier frames hold the stroke where it *was*, so the average lags the surface by about
(k - 1) / 2 frames, a pixel or more as soon as the surface moves a pixel a frame.
With ``average_motion="exact"`` each earlier frame's sums are first moved to where the surface
is now, so averaging keeps only the fits' noise reduction:

* :func:`stroke_anchors`, at the frame the sums were made: per stroke the surface points under
  the centroid c of its fragments (``origin + sum (x - o) / N``) and under c +- h e_x,
  c +- h e_y (h = :data:`RING_PX`): the camera rays through them cut with the plane of the
  triangle under c (the gather G-buffer's ``position`` and ``dposition_dx`` x ``dposition_dy``
  at the sample holding c; ``mesh_id`` names the object), with the objects' transforms;
* :func:`transport`, at a later frame: the five points go through their object's relative
  transform ``T_now inv(T_then)`` and the current camera; the centre lands at c', and central
  differences of the ring give the 2 x 2 screen Jacobian A of the motion at c (exactly the
  identity where nothing moved). A fragment at x goes to c' + A (x - c). That map is affine, so
  the sums transform exactly: with the new
  origin o' = c' + A (o - c), ``sum s^k (x' - o') = A sum s^k (x - o)`` for k = 0..3 (the x and y
  sums mix through A), the powers of s unchanged (s is a texture-space stroke parameter, which
  the motion does not change).

Exact for motions that are affine over a stroke (a stroke is a few pixels long); a stroke whose
centroid is not on its object in the sums' frame, or whose point is behind the camera now, is not
carried (it drops out of the average, never lags).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from refnpr.raster.projection import project_points

if TYPE_CHECKING:
    from .aggregate import Aggregates

__all__ = ["MOTION_CHANNELS", "RING_PX", "StrokeAnchors", "stroke_anchors", "transport"]

#: G-buffer channels the anchors are read from
MOTION_CHANNELS = frozenset({"position", "dposition_dx", "dposition_dy", "mesh_id"})

#: half the step, in pixels, of the central differences that give the motion's Jacobian
RING_PX = 1.0

# the ring's offsets from c: +x, -x, +y, -y
_RING = np.array([[RING_PX, 0.0], [-RING_PX, 0.0], [0.0, RING_PX], [0.0, -RING_PX]])


@dataclass(frozen=True, eq=False)
class StrokeAnchors:
    """Where each stroke of one frame's aggregates lies on the surface (float64).

    Attributes
    ----------
    stroke_ids : (S,) int64, the aggregates' ids (sorted)
    valid : (S,) bool, the centroid lies on an object and its rays meet the triangle's plane
    centroid : (S, 2) pixels, c
    point : (S, 3) world point under c
    ring : (S, 4, 3) world points under c + (h, 0), c - (h, 0), c + (0, h), c - (0, h)
    object : (S,) int64, object index (0 where not valid)
    transforms : (O, 4, 4) the objects' world transforms in that frame
    """

    stroke_ids: np.ndarray
    valid: np.ndarray
    centroid: np.ndarray
    point: np.ndarray
    ring: np.ndarray
    object: np.ndarray
    transforms: np.ndarray

    def __len__(self) -> int:
        return int(self.stroke_ids.shape[0])


def _transforms(scene: Any) -> np.ndarray:
    return np.array([np.asarray(o.transform, dtype=np.float64) for o in scene.objects]).reshape(
        -1, 4, 4
    )


def _rays_on_planes(camera, width, height, xy, p0, normal):
    """World points where the camera rays through pixel coordinates ``xy`` (S, K, 2) meet the
    planes through ``p0`` (S, 3) with ``normal`` (S, 3): (S, K, 3) and (S, K) bool (met)."""
    inv = np.linalg.inv(np.asarray(camera.view_projection(width, height), dtype=np.float64))
    ndc = np.stack([2.0 * xy[..., 0] / width - 1.0, 1.0 - 2.0 * xy[..., 1] / height], -1)

    def unproject(z):
        h = ndc @ inv[:, :2].T + z * inv[:, 2] + inv[:, 3]  # (S, K, 4)
        return h[..., :3] / h[..., 3:]

    near, far = unproject(-1.0), unproject(1.0)
    d = far - near
    den = np.einsum("sk,sk->s", normal, p0)[:, None] - np.einsum("ski,si->sk", near, normal)
    dot = np.einsum("ski,si->sk", d, normal)
    ok = np.abs(dot) > 1e-300
    lam = den / np.where(ok, dot, 1.0)
    ok &= np.isfinite(lam)
    return near + np.where(ok, lam, 0.0)[..., None] * d, ok


def stroke_anchors(agg: Aggregates, gb: Any, scene: Any) -> StrokeAnchors:
    """The surface anchor of each stroke of ``agg`` (see the module docstring).

    Parameters
    ----------
    agg : Aggregates of one frame (fragments in pixels of ``gb``)
    gb : GBuffer the fragments were gathered from, with :data:`MOTION_CHANNELS`
    scene : Scene of that frame (its objects' transforms; the camera is ``gb.camera``)

    Returns
    -------
    StrokeAnchors
    """
    missing = sorted(name for name in MOTION_CHANNELS if name not in gb)
    if missing:
        raise ValueError(
            f"gb: motion-compensated averaging reads channels {missing}, which this G-buffer "
            "lacks; rasterize them (TamissStyle.requires adds them for average_frames > 1)"
        )
    m = np.asarray(agg.moments, dtype=np.float64)
    count = np.maximum(m[:, 0], 1.0)  # sum s^0 = N
    origin = np.asarray(agg.origin, dtype=np.float64).reshape(-1, 2)
    c = origin + np.stack([m[:, 7], m[:, 11]], -1) / count[:, None]  # fragment centroid
    n = gb.n
    nh, nw = gb.sample_shape
    valid = np.all(np.isfinite(c), axis=1)
    cs = np.where(valid[:, None], c, 0.5)
    valid &= (cs[:, 0] >= 0) & (cs[:, 0] < gb.width) & (cs[:, 1] >= 0) & (cs[:, 1] < gb.height)
    col = np.clip(np.floor(cs[:, 0] * n).astype(np.int64), 0, nw - 1)
    row = np.clip(np.floor(cs[:, 1] * n).astype(np.int64), 0, nh - 1)
    obj = np.asarray(gb["mesh_id"])[row, col].astype(np.int64)
    transforms = _transforms(scene)
    valid &= (obj >= 0) & (obj < transforms.shape[0])
    p0 = np.asarray(gb["position"], dtype=np.float64)[row, col]
    normal = np.cross(
        np.asarray(gb["dposition_dx"], dtype=np.float64)[row, col],
        np.asarray(gb["dposition_dy"], dtype=np.float64)[row, col],
    )
    xy = cs[:, None, :] + np.concatenate([np.zeros((1, 2)), _RING])[None]  # (S, 5, 2)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        pts, met = _rays_on_planes(gb.camera, gb.width, gb.height, xy, p0, normal)
    valid &= np.all(met, axis=1) & np.all(np.isfinite(pts.reshape(-1, 15)), axis=1)
    pts = np.where(valid[:, None, None], pts, 0.0)
    return StrokeAnchors(
        stroke_ids=np.asarray(agg.stroke_ids, dtype=np.int64).copy(),
        valid=valid,
        centroid=cs,
        point=pts[:, 0],
        ring=pts[:, 1:],
        object=np.where(valid, obj, 0),
        transforms=transforms,
    )


def transport(
    agg: Aggregates, anchors: StrokeAnchors, scene: Any, width: int, height: int
) -> tuple[Aggregates, np.ndarray]:
    """``agg`` (float64, made in the anchors' frame) moved to the pixels of ``scene``'s frame.

    Parameters
    ----------
    agg : Aggregates, float64, the strokes of ``anchors`` in the same order
    anchors : StrokeAnchors of the frame ``agg`` was made in
    scene : Scene of the current frame (camera, objects' transforms)
    width, height : image size in pixels

    Returns
    -------
    (Aggregates, (S,) bool)
        The moved sums (t ranges and powers of s unchanged, origin and x / y sums moved) and
        which strokes could be moved (the rest are returned as they were and must not be used).
    """
    if not np.array_equal(anchors.stroke_ids, agg.stroke_ids):
        raise ValueError("anchors: stroke ids differ from the aggregates'; make them together")
    now = _transforms(scene)
    if now.shape[0] != anchors.transforms.shape[0]:
        raise ValueError(
            f"scene: has {now.shape[0]} objects, the anchors' frame had "
            f"{anchors.transforms.shape[0]}; the frames of a sequence keep the same objects"
        )
    rel = np.empty_like(now)
    for i in range(now.shape[0]):
        if np.array_equal(now[i], anchors.transforms[i]):
            rel[i] = np.eye(4)  # exact for still objects
        else:
            rel[i] = now[i] @ np.linalg.inv(anchors.transforms[i])
    r = rel[anchors.object]  # (S, 4, 4)
    pts = np.concatenate([anchors.point[:, None], anchors.ring], 1)  # (S, 5, 3)
    moved_pts = np.einsum("sij,skj->ski", r[:, :3, :3], pts) + r[:, None, :3, 3]
    cam = scene.camera
    vp = np.asarray(cam.view_projection(width, height), dtype=np.float64)
    xy, w = project_points(moved_pts, vp, width, height)  # (S, 5, 2), (S, 5); NaN behind
    ok = anchors.valid & np.all((w >= cam.near) & (w <= cam.far), axis=1)
    c_new = xy[:, 0]
    a = np.stack([xy[:, 1] - xy[:, 2], xy[:, 3] - xy[:, 4]], -1) / (2.0 * RING_PX)  # (S, 2, 2)
    ok &= np.all(np.isfinite(a.reshape(-1, 4)), axis=1) & np.all(np.isfinite(c_new), axis=1)
    a = np.where(ok[:, None, None], a, np.eye(2))
    c_new = np.where(ok[:, None], c_new, anchors.centroid)
    origin = np.asarray(agg.origin, dtype=np.float64)
    o_new = c_new + np.einsum("kij,kj->ki", a, origin - anchors.centroid)
    m = np.asarray(agg.moments, dtype=np.float64).copy()
    sx, sy = m[:, 7:11].copy(), m[:, 11:15].copy()
    m[:, 7:11] = a[:, 0, 0, None] * sx + a[:, 0, 1, None] * sy
    m[:, 11:15] = a[:, 1, 0, None] * sx + a[:, 1, 1, None] * sy
    moved = replace(agg, origin=np.where(ok[:, None], o_new, origin), moments=m)
    return moved, ok
