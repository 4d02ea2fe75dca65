"""The exact motion field of a frame pair: G-buffer world positions re-projected into frame t-1.

Each pixel covered at frame t shows a world point of object ``mesh_id``; the point goes back
through the object's transform at t, out through its transform at t-1 and through frame t-1's
camera (the rasterizer's pixel convention: pixel (i, j) covers [i, i + 1) x [j, j + 1), its
centre at (i + 0.5, j + 0.5); ``w`` is clip w, the eye-space view-axis distance ``depth`` holds).
The valid mask M is ``covered & in_front & inside & visible``, where ``visible`` is a depth test
of every weighted bilinear tap against the point's own triangle plane, so a warped value blends
one surface only (docs/coherence.md, "The motion field"). Coordinates within ``SNAP_PX`` of a
pixel centre are snapped onto it, so a still frame warps onto itself exactly and every number is
exactly 0 for a static scene.
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

#: Default relative depth tolerance: a tap passes when ``|depth_prev - w_plane| <= DEPTH_RTOL *
#: w_plane``. A tap on a neighbouring triangle of a curved mesh departs from the plane by about
#: 2 tan(fov/2) / H * sin(crease) relative (1.4e-3 at fov 45 deg, H = 100, a 10 deg crease);
#: 1e-2 covers that and still catches an occluder 1 % of the depth in front (5 cm at 5 m).
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
    """A GBuffer at spp 1 with the ``needed`` channels, or an error naming ``name``."""
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


def _inside(xy: np.ndarray, width: int, height: int) -> np.ndarray:
    """(K,) bool: which pixel coordinates ``xy`` (K, 2) are finite and inside the image."""
    with np.errstate(invalid="ignore"):
        return np.isfinite(xy).all(1) & (xy >= 0).all(1) & (xy < (width, height)).all(1)


def _eye_rays(x: np.ndarray, y: np.ndarray, proj: np.ndarray, width: int, height: int):
    """(K, 3) eye-space directions through pixel coordinates (x, y), scaled to z = -1."""
    ndc_x, ndc_y = 2.0 * x / width - 1.0, 1.0 - 2.0 * y / height
    return np.stack([ndc_x / proj[0, 0], ndc_y / proj[1, 1], -np.ones(np.shape(x))], axis=-1)


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
    for i, (now, prev) in enumerate(zip(t_now, t_prev, strict=True)):
        # exact for a still object: it maps every point onto itself
        rel[i] = np.eye(4) if np.array_equal(now, prev) else prev @ np.linalg.inv(now)
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
    fx, fy = xy[..., 0] - 0.5, xy[..., 1] - 0.5
    x0, y0 = np.floor(fx), np.floor(fy)
    ax, ay = fx - x0, fy - y0
    x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
    cols = (np.clip(x0, 0, width - 1), np.clip(x0 + 1, 0, width - 1))
    rows = (np.clip(y0, 0, height - 1), np.clip(y0 + 1, 0, height - 1))
    taps = np.stack([r * width + c for r in rows for c in cols])  # TL, TR, BL, BR
    weights = np.stack([(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay])
    return taps, weights


def motion_field(
    gb: Any, prev_gb: Any, scene: Any, prev_scene: Any, *, depth_rtol: float = DEPTH_RTOL
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
    inside_k = _inside(xy_k, width, height)
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
        ray = _eye_rays(col + 0.5, row + 0.5, proj, width, height)  # through the tap centre
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
