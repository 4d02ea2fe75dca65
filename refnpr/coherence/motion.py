"""The exact motion field of a frame pair: G-buffer world positions re-projected into frame t-1.

DESIGN.md ("Frames, state and speed"): temporal coherence is measured with the exact motion
field, never with estimated optical flow. For every pixel covered at frame t the G-buffer holds
the world position of the surface point it shows and the object (``mesh_id``) it belongs to;
the point is carried back to object space through the inverse of the object's transform at t,
out to world space through the object's transform at t-1, and projected through the camera of
frame t-1.

Conventions (the rasterizer's, DESIGN.md "The rasterizer contract")
--------------------------------------------------------------------
* Pixel coordinates are continuous, x to the right, y downward, origin at the top-left corner
  of the image: pixel ``(i, j)`` (column i, row j) covers ``[i, i + 1) x [j, j + 1)`` and has
  its centre at ``(i + 0.5, j + 0.5)``. A point of NDC ``(x_ndc, y_ndc)`` lies at
  ``x = (x_ndc + 1) W / 2``, ``y = (1 - y_ndc) H / 2``.
* ``w`` is the clip-space w of the previous camera, which for the OpenGL perspective matrix is
  the eye-space distance along the view axis: the quantity the G-buffer's ``depth`` holds.

The valid mask M
----------------
A pixel is valid when all of these hold:

1. ``covered``: ``mesh_id >= 0`` at frame t;
2. ``in_front``: the point is inside the previous camera's depth range, ``near <= w <= far``;
3. ``inside``: its re-projection lands inside frame t-1, ``0 <= x < W`` and ``0 <= y < H``;
4. ``visible``: a depth test against frame t-1's own G-buffer on the bilinear taps. The warp
   (:mod:`refnpr.coherence.resample`) reads the 2 x 2 pixel centres around the landing point; every
   tap with a non-zero bilinear weight must show the same object (``mesh_id``) and a depth
   within ``depth_rtol`` of the depth the point's own surface has *at that tap*. That expected
   depth comes from the triangle plane through the point (tangents ``dposition_dx`` and
   ``dposition_dy`` of frame t, carried to frame t-1 by the same object transforms), cut by the
   previous camera's ray through the tap's centre, so slanted and grazing surfaces pass while
   an occluder in front of the point (or a surface behind it that was visible because the point
   was hidden, i.e. disocclusion) fails. Requiring *all* weighted taps makes the warped value a
   blend of the same surface only: the pixels whose footprint straddles a silhouette in frame
   t-1 are left out, so M is at most one pixel narrower than the exactly visible region.

Re-projected coordinates within ``SNAP_PX`` of a pixel centre are snapped to it: float rounding
of the re-projection (about 1e-12 px with a float64 G-buffer, 1e-5 px with float32) is far below
any meaningful motion, and snapping makes a still frame warp onto itself exactly (one tap,
weight 1), so that every number is exactly 0 for a static scene.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.raster.projection import project_points

__all__ = [
    "MOTION_CHANNELS",
    "DEPTH_RTOL",
    "SNAP_PX",
    "MotionField",
    "bilinear_taps",
    "motion_field",
]

#: G-buffer channels ``motion_field`` reads (frame t: all but ``depth``; frame t-1: ``depth``,
#: ``mesh_id``). The driver rasterizes exactly these, at spp 1, in float64.
MOTION_CHANNELS = ("depth", "dposition_dx", "dposition_dy", "mesh_id", "position")

#: Default relative depth tolerance of the depth test. A tap passes when
#: ``|depth_prev - w_plane| <= DEPTH_RTOL * w_plane``. Within one triangle the plane is exact
#: (float64 rounding, ~1e-12); a tap up to one pixel away may lie on a neighbouring triangle of
#: a curved mesh, which departs from the plane by about (pixel footprint) * sin(dihedral
#: angle), i.e. a relative 2 tan(fov/2) / H * sin(phi) -- 1.4e-3 for fov 45 deg, H = 100 and a
#: 10 deg crease. 1e-2 accepts that with margin while any occluder more than 1 % of the depth in
#: front (5 cm at 5 m) is caught; creases sharper than that lose their one-pixel band, which is
#: the conservative side.
DEPTH_RTOL = 1e-2
#: Re-projected coordinates this close (pixels) to a pixel centre are snapped onto it.
SNAP_PX = 1e-6


@dataclass(frozen=True, eq=False)
class MotionField:
    """Where each pixel of frame t was in frame t-1, and whether it can be compared.

    Attributes
    ----------
    xy : (H, W, 2) float64
        Continuous pixel coordinates (x, y) in frame t-1 of the surface point each pixel of
        frame t shows (pixel centre convention of the module docstring; snapped to a pixel
        centre within ``SNAP_PX``); NaN where not covered.
    w : (H, W) float64
        Clip w (eye-space view-axis distance) of the point in the previous camera; NaN where not
        covered.
    valid : (H, W) bool
        The mask M: ``covered & in_front & inside & visible``.
    covered, in_front, inside, visible : (H, W) bool
        The four conditions of M separately (``visible`` is only meaningful where the first
        three hold, and False elsewhere).
    taps : (4, H, W) int64
        Flat indices (``row * W + col``) into frame t-1 of the bilinear taps (top-left,
        top-right, bottom-left, bottom-right), clamped to the image; 0 where not valid.
    weights : (4, H, W) float64
        Their bilinear weights (summing to 1); 0 where not valid.
    depth_rtol : float
        The tolerance the depth test used.
    """

    xy: np.ndarray
    w: np.ndarray
    valid: np.ndarray
    covered: np.ndarray
    in_front: np.ndarray
    inside: np.ndarray
    visible: np.ndarray
    taps: np.ndarray
    weights: np.ndarray
    depth_rtol: float

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W)."""
        return self.valid.shape

    def flow(self) -> np.ndarray:
        """(H, W, 2) float64 backward motion in pixels: ``xy - pixel centre`` (where the point
        was in frame t-1 minus where it is in frame t); NaN where not covered."""
        h, w = self.shape
        ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
        centre = np.stack([xs + 0.5, ys + 0.5], axis=-1)
        return self.xy - centre


def _check_gbuffer(name: str, gb: Any, needed: Sequence[str]) -> None:
    for attr in ("channels", "width", "height", "spp", "camera", "view_projection"):
        if not hasattr(gb, attr):
            raise TypeError(
                f"{name}: expected a refnpr.raster.GBuffer (rasterize(...)), "
                f"got {type(gb).__name__}"
            )
    if gb.spp != 1:
        raise ValueError(
            f"{name}: expected a pixel-resolution G-buffer (spp 1), got spp {gb.spp}; "
            f"rasterize it with spp=1"
        )
    missing = [c for c in needed if c not in gb.channels]
    if missing:
        raise ValueError(
            f"{name}: lacks channels {missing} (has {sorted(gb.channels)}); rasterize it with "
            f"channels={MOTION_CHANNELS}"
        )


def _transforms(name: str, scene: Any) -> np.ndarray:
    objects = getattr(scene, "objects", None)
    if objects is None:
        raise TypeError(f"{name}: expected a refnpr.scenes.Scene, got {type(scene).__name__}")
    return np.array([np.asarray(o.transform, dtype=np.float64) for o in objects])


def _relative_transforms(scene: Any, prev_scene: Any) -> np.ndarray:
    """(n, 4, 4) float64: object i's ``T_prev @ inv(T_t)`` (world at t -> world at t-1)."""
    t_now = _transforms("scene", scene)
    t_prev = _transforms("prev_scene", prev_scene)
    if t_now.shape[0] != t_prev.shape[0]:
        raise ValueError(
            f"prev_scene: has {t_prev.shape[0]} objects, scene has {t_now.shape[0]}; the frames "
            "of a sequence keep the same objects (only transforms, camera, lights and style "
            "parameters change)"
        )
    for i, (a, b) in enumerate(zip(scene.objects, prev_scene.objects, strict=True)):
        ma, mb = a.mesh, b.mesh
        if ma is not mb and (
            ma.positions.shape != mb.positions.shape or ma.faces.shape != mb.faces.shape
        ):
            raise ValueError(
                f"prev_scene: object {i} ({b.name!r}) has a different mesh than in scene "
                f"({ma.positions.shape[0]} vs {mb.positions.shape[0]} vertices); the frames of a "
                "sequence keep their meshes"
            )
    rel = np.empty_like(t_now)
    for i in range(t_now.shape[0]):
        if np.array_equal(t_now[i], t_prev[i]):
            rel[i] = np.eye(4)  # exact: a still object maps every point onto itself
        else:
            rel[i] = t_prev[i] @ np.linalg.inv(t_now[i])
    return rel


def bilinear_taps(xy: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The 2 x 2 bilinear taps of continuous pixel coordinates, clamped to the image.

    A pixel centre is at ``(i + 0.5, j + 0.5)``, so the sample position in pixel-index space is
    ``(x - 0.5, y - 0.5)``; its integer part and fraction give the taps and weights. Taps that
    fall outside the image are clamped to the nearest edge pixel (OpenGL CLAMP_TO_EDGE).

    Parameters
    ----------
    xy : (..., 2) float64
        Finite coordinates.
    width, height : int

    Returns
    -------
    taps : (4, ...) int64
        Flat indices ``row * width + col``: top-left, top-right, bottom-left, bottom-right.
    weights : (4, ...) float64
        Bilinear weights, summing to 1.
    """
    fx = xy[..., 0] - 0.5
    fy = xy[..., 1] - 0.5
    x0 = np.floor(fx)
    y0 = np.floor(fy)
    ax = fx - x0
    ay = fy - y0
    x0 = x0.astype(np.int64)
    y0 = y0.astype(np.int64)
    cols = (np.clip(x0, 0, width - 1), np.clip(x0 + 1, 0, width - 1))
    rows = (np.clip(y0, 0, height - 1), np.clip(y0 + 1, 0, height - 1))
    taps = np.stack(
        [
            rows[0] * width + cols[0],
            rows[0] * width + cols[1],
            rows[1] * width + cols[0],
            rows[1] * width + cols[1],
        ]
    )
    weights = np.stack([(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay])
    return taps, weights


def motion_field(
    gb: Any,
    prev_gb: Any,
    scene: Any,
    prev_scene: Any,
    *,
    depth_rtol: float = DEPTH_RTOL,
) -> MotionField:
    """The exact motion field of frame t with respect to frame t-1, and the valid mask M.

    Parameters
    ----------
    gb : GBuffer
        Frame t at spp 1, with ``position``, ``mesh_id``, ``dposition_dx``, ``dposition_dy``
        (``MOTION_CHANNELS``). Rasterize it in float64: float32 positions re-project with
        ~1e-5 px of rounding, more than ``SNAP_PX``, so a still frame no longer warps onto
        itself exactly.
    prev_gb : GBuffer
        Frame t-1 at spp 1 and the same size, with ``depth`` and ``mesh_id``. Its ``camera`` is
        the previous camera.
    scene, prev_scene : Scene
        The still scenes of frames t and t-1 (same objects and meshes; the transforms may
        differ).
    depth_rtol : float
        Relative depth tolerance of the depth test (``DEPTH_RTOL``; see the module docstring).

    Returns
    -------
    MotionField

    Raises
    ------
    TypeError, ValueError
        A G-buffer that is not spp 1, lacks a channel, or differs in size; scenes with different
        object counts or meshes; a bad ``depth_rtol``.
    """
    _check_gbuffer("gb", gb, ("position", "mesh_id", "dposition_dx", "dposition_dy"))
    _check_gbuffer("prev_gb", prev_gb, ("depth", "mesh_id"))
    if (gb.width, gb.height) != (prev_gb.width, prev_gb.height):
        raise ValueError(
            f"prev_gb: is {prev_gb.width} x {prev_gb.height}, gb is {gb.width} x {gb.height}; "
            "both frames must be rasterized at the same size"
        )
    if isinstance(depth_rtol, bool) or not isinstance(depth_rtol, (int, float, np.floating)):
        raise TypeError(f"depth_rtol: expected a real number, got {depth_rtol!r}")
    depth_rtol = float(depth_rtol)
    if not 0.0 < depth_rtol < 1.0:
        raise ValueError(f"depth_rtol: expected a tolerance in (0, 1), got {depth_rtol}")
    rel = _relative_transforms(scene, prev_scene)
    width, height = gb.width, gb.height
    mesh_id = np.asarray(gb["mesh_id"])
    if mesh_id.max(initial=-1) >= rel.shape[0]:
        raise ValueError(
            f"gb: mesh_id {int(mesh_id.max())} is out of range for a scene of {rel.shape[0]} "
            "objects; rasterize gb from this scene"
        )
    covered = mesh_id >= 0
    ids = mesh_id[covered]
    p = np.asarray(gb["position"], dtype=np.float64)[covered]  # (K, 3) world at t
    m = rel[ids]  # (K, 4, 4)
    lin = m[:, :3, :3]
    p_prev = np.einsum("kij,kj->ki", lin, p) + m[:, :3, 3]  # world at t-1
    cam = prev_gb.camera
    view = cam.view_matrix()
    proj = cam.projection_matrix(width, height)
    q = p_prev @ view[:3, :3].T + view[:3, 3]  # eye space of the previous camera
    # pixel and clip w as the rasterizer projects a vertex (w = -z_eye: OpenGL perspective)
    xy_k, w = project_points(p_prev, cam.view_projection(width, height), width, height)
    nearest = np.floor(xy_k) + 0.5
    snap = np.abs(xy_k - nearest) < SNAP_PX
    xy_k = np.where(snap, nearest, xy_k)
    in_front_k = (w >= cam.near) & (w <= cam.far)
    inside_k = (
        np.isfinite(xy_k).all(axis=1)
        & (xy_k[:, 0] >= 0)
        & (xy_k[:, 0] < width)
        & (xy_k[:, 1] >= 0)
        & (xy_k[:, 1] < height)
    )
    reach = inside_k & in_front_k
    taps_k, weights_k = bilinear_taps(np.where(reach[:, None], xy_k, 0.5), width, height)
    # depth the point's own surface has at each tap: the triangle plane (tangents of frame t
    # carried to t-1 and into the previous eye space) cut by the previous camera's tap ray
    rot = view[:3, :3]
    a = np.einsum("ij,kjl,kl->ki", rot, lin, np.asarray(gb["dposition_dx"], np.float64)[covered])
    b = np.einsum("ij,kjl,kl->ki", rot, lin, np.asarray(gb["dposition_dy"], np.float64)[covered])
    normal = np.cross(a, b)
    flat = ~np.any(normal != 0.0, axis=1)  # degenerate tangents: fall back to constant depth
    n_dot_q = np.einsum("ki,ki->k", normal, q)
    depth_prev = np.asarray(prev_gb["depth"], dtype=np.float64).reshape(-1)
    mesh_prev = np.asarray(prev_gb["mesh_id"]).reshape(-1)
    visible_k = reach.copy()
    for k in range(4):
        t = taps_k[k]
        col, row = t % width, t // width
        ray = np.stack(  # eye-space direction through the tap centre, scaled to z = -1
            [
                (2.0 * (col + 0.5) / width - 1.0) / proj[0, 0],
                (1.0 - 2.0 * (row + 0.5) / height) / proj[1, 1],
                -np.ones(t.shape),
            ],
            axis=-1,
        )
        with np.errstate(divide="ignore", invalid="ignore"):
            w_plane = np.where(flat, w, n_dot_q / np.einsum("ki,ki->k", normal, ray))
            ok = (mesh_prev[t] == ids) & (np.abs(depth_prev[t] - w_plane) <= depth_rtol * w_plane)
        visible_k &= ok | (weights_k[k] == 0.0)
    valid_k = visible_k  # implies covered, in_front, inside

    def full(values, fill, dtype=None):
        out = np.full((height, width) + values.shape[1:], fill, dtype=dtype or values.dtype)
        out[covered] = values
        return out

    def full_taps(values, fill):
        out = np.full((4, height, width), fill, dtype=values.dtype)
        out[:, covered] = np.where(valid_k[None], values, fill)
        return out

    return MotionField(
        xy=full(xy_k, np.nan),
        w=full(w, np.nan),
        valid=full(valid_k, False),
        covered=covered,
        in_front=full(in_front_k, False),
        inside=full(inside_k, False),
        visible=full(visible_k, False),
        taps=full_taps(taps_k, 0),
        weights=full_taps(weights_k, 0.0),
        depth_rtol=depth_rtol,
    )
