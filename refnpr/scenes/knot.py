"""Torus knot tube with rotation-minimising frames (Wang, Juettler, Zheng, Liu 2008)."""

from __future__ import annotations

import math

import numpy as np

from ..raster import Mesh
from ._params import check_grid, check_int, positives
from ._topology import grid_faces

__all__ = ["torus_knot", "torus_knot_curve", "rotation_minimising_frames"]


def torus_knot_curve(
    t: np.ndarray, p: int, q: int, R: float, r: float
) -> tuple[np.ndarray, np.ndarray]:
    """Points and unit tangents of the (p, q) torus knot.

    ``c(t) = ((R + r cos(q t)) cos(p t), (R + r cos(q t)) sin(p t), r sin(q t))``, t in [0, 2 pi]:
    it winds p times about the z axis and q times around the core circle of radius R.

    Parameters
    ----------
    t : (N,) float64

    Returns
    -------
    points, tangents : (N, 3) float64
    """
    ring = R + r * np.cos(q * t)
    points = np.stack([ring * np.cos(p * t), ring * np.sin(p * t), r * np.sin(q * t)], axis=1)
    d_ring = -q * r * np.sin(q * t)
    d = np.stack(
        [
            d_ring * np.cos(p * t) - p * ring * np.sin(p * t),
            d_ring * np.sin(p * t) + p * ring * np.cos(p * t),
            q * r * np.cos(q * t),
        ],
        axis=1,
    )
    return points, d / np.linalg.norm(d, axis=1, keepdims=True)


def rotation_minimising_frames(
    points: np.ndarray, tangents: np.ndarray, *, closed: bool = True
) -> np.ndarray:
    """Reference vectors of a rotation-minimising frame by the double-reflection method.

    Parameters
    ----------
    points, tangents : (N, 3) float64
        Samples of the curve and their unit tangents. With ``closed=True`` the curve continues
        from the last sample back to the first (which must not be repeated at the end).
    closed : bool
        Spread the holonomy (the angle by which the propagated frame fails to return to itself
        after one loop) evenly along the curve, so the frame is periodic.

    Returns
    -------
    normals : (N, 3) float64
        Unit reference vectors orthogonal to the tangents; the binormal is ``tangent x normal``.
    """
    n = points.shape[0]
    t0 = tangents[0]
    helper = np.eye(3)[np.argmin(np.abs(t0))]
    r0 = np.cross(t0, helper)
    r0 /= np.linalg.norm(r0)
    steps = n if closed else n - 1
    rs = np.empty((steps + 1, 3))
    rs[0] = r0
    for i in range(steps):  # double reflection, Wang et al. 2008, algorithm 1
        j = (i + 1) % n
        v1 = points[j] - points[i]
        c1 = v1 @ v1
        r_l = rs[i] - (2.0 / c1) * (v1 @ rs[i]) * v1
        t_l = tangents[i] - (2.0 / c1) * (v1 @ tangents[i]) * v1
        v2 = tangents[j] - t_l
        c2 = v2 @ v2
        rs[i + 1] = r_l if c2 == 0.0 else r_l - (2.0 / c2) * (v2 @ r_l) * v2
    if closed:
        r_end = rs[n]  # the frame carried once around, back at sample 0
        angle = math.atan2(np.cross(r_end, r0) @ t0, r_end @ r0)
        rs = rs[:n]
        theta = angle * np.arange(n) / n
        b = np.cross(tangents, rs)
        rs = np.cos(theta)[:, None] * rs + np.sin(theta)[:, None] * b
    rs -= np.einsum("ij,ij->i", rs, tangents)[:, None] * tangents
    return rs / np.linalg.norm(rs, axis=1, keepdims=True)


def torus_knot(
    p: int = 2,
    q: int = 3,
    R: float = 1.0,
    r: float = 0.4,
    tube_radius: float = 0.15,
    n_u: int = 256,
    n_v: int = 16,
) -> Mesh:
    """A closed tube of radius ``tube_radius`` around the (p, q) torus knot
    (:func:`torus_knot_curve`), lying across the xy plane (the knot's axis is z).

    Parameters
    ----------
    p, q : int
        Coprime positive winding numbers.
    R, r : float
        Radius of the core circle and of the torus the knot lies on, ``0 < r < R``.
    tube_radius : float
        Radius of the tube (> 0); a tube that would intersect itself is rejected.
    n_u, n_v : int
        Segments along the knot (>= 8) and around the tube (>= 3).

    Returns
    -------
    Mesh
        ``2 * n_u * n_v`` triangles; uv: u along the knot, v around the tube, both in [0, 1].
        Cross sections follow a rotation-minimising frame closed up by spreading its holonomy
        evenly, so the v = const lines do not twist needlessly.
    """
    p, q = check_int("p", p, minimum=1), check_int("q", q, minimum=1)
    if math.gcd(p, q) != 1:
        raise ValueError(
            f"p, q: must be coprime to trace a single knot, got p={p}, q={q} "
            f"(common factor {math.gcd(p, q)}); e.g. (2, 3), (3, 5), (2, 7)"
        )
    R, r, tube_radius = positives(R=R, r=r, tube_radius=tube_radius)
    if r >= R:
        raise ValueError(f"r: must be smaller than R ({R}), got {r}")
    n_u, n_v = check_int("n_u", n_u, minimum=8), check_int("n_v", n_v, minimum=3)
    check_grid((n_u + 1) * (n_v + 1), {"n_u": n_u, "n_v": n_v})
    clearance = _clearance(p, q, R, r)
    if tube_radius >= 0.5 * clearance:
        raise ValueError(
            f"tube_radius: {tube_radius} makes the tube intersect itself; the strands of the "
            f"({p}, {q}) knot come {clearance:.4g} close, so use tube_radius < {0.5 * clearance:.4g}"
        )
    t = 2.0 * np.pi * np.arange(n_u) / n_u
    c, tan = torus_knot_curve(t, p, q, R, r)
    nrm = rotation_minimising_frames(c, tan, closed=True)
    bin_ = np.cross(tan, nrm)
    phi = 2.0 * np.pi * np.arange(n_v + 1) / n_v
    cphi, sphi = np.cos(phi), np.sin(phi)
    cphi[-1], sphi[-1] = cphi[0], sphi[0]
    normals = cphi[None, :, None] * nrm[:, None, :] + sphi[None, :, None] * bin_[:, None, :]
    positions = c[:, None, :] + tube_radius * normals
    # close the knot: ring n_u repeats ring 0 bitwise
    positions = np.concatenate([positions, positions[:1]]).reshape(-1, 3)
    normals = np.concatenate([normals, normals[:1]]).reshape(-1, 3)
    uu, vv = np.meshgrid(np.arange(n_u + 1) / n_u, np.arange(n_v + 1) / n_v, indexing="ij")
    uv = np.stack([uu.ravel(), vv.ravel()], axis=1)
    faces = grid_faces(n_u, n_v)  # normal along d/dv x d/du = outward for (T, N, B) right-handed
    return Mesh(positions, faces, normals, uv, name="torus_knot")


def _clearance(p: int, q: int, R: float, r: float, samples: int = 720) -> float:
    """Smallest distance between two points of the knot more than a quarter strand apart."""
    t = 2.0 * np.pi * np.arange(samples) / samples
    pts, _ = torus_knot_curve(t, p, q, R, r)
    d = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1)
    i = np.arange(samples)
    gap = np.abs(i[:, None] - i[None, :])
    gap = np.minimum(gap, samples - gap)
    # arc length of a gap ~ gap * (2 pi / samples) * speed; exclude near neighbours along the curve
    speed = np.hypot(p * (R + r), q * r)
    near = gap * (2.0 * np.pi / samples) * speed < np.pi * r
    return float(d[~near].min())
