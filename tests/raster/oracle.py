"""Independent float64 ray-cast oracle for the rasterizer tests.

Built only from the camera's two OpenGL matrices (``view_matrix()``, ``projection_matrix()``) and
brute force; it shares no code with ``refnpr.raster`` beyond reading those matrices.

* Rays through arbitrary pixel coordinates (pixel centres, sample centres, offsets for central
  differences): the NDC points at z = -1 and z = 1 are unprojected through inv(P @ V), so the ray
  segment t in [0, 1] spans exactly the part of the view between the near and far planes.
* Ray/triangle intersection in float64 (Moller-Trumbore's edge tests, origin-relative, with t
  from the plane through the nearest vertex), vectorized over rays x triangles, and the nearest
  hit by brute force (smallest t).
* An ambiguity mask: rays whose pixel lies within ``edge_eps`` pixels of the boundary of some
  triangle's visible screen region (its three edges plus the near and far clip lines, computed as
  2D homogeneous lines from the clip-space vertices, so triangles crossing w = 0 are handled) or
  of the line a flat triangle (zero area, or plane through the eye) projects onto; where two
  triangles tie in depth; where a hit lies on the near or far plane (to rounding). There the
  rasterizer's 1/256 px vertex snapping or its rounding may legitimately decide differently;
  everywhere else the triangle id must agree exactly.
* Attribute values at the exact hit, and per-pixel screen derivatives by central differences of
  the exact hit of rays through (x +- h, y) and (x, y +- h) with the plane of the same triangle
  (Richardson-extrapolated: h and h / 2), interpolated with the exact barycentrics.

Pixel coordinates follow the rasterizer contract: pixel (x, y) has its centre at (x + 0.5, y + 0.5),
row 0 is the top row, NDC x = 2 px / W - 1, NDC y = 1 - 2 py / H; d/dy is downward.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Hits",
    "View",
    "cast",
    "derivatives",
    "front_facing",
    "intersect",
    "pixel_centres",
    "region_distance",
    "surface",
]

#: Default half-width (pixels) of the band around triangle boundaries where ids may differ.
EDGE_EPS = 1.0 / 128.0
#: Default relative depth difference under which two triangles count as tied.
DEPTH_RTOL = 1e-8
#: A triangle whose plane passes closer to the eye than this (relative to its distance) is flat.
FLAT_RTOL = 1e-10


@dataclass(frozen=True)
class View:
    """The camera as the oracle sees it: the two OpenGL matrices and the image size.

    Attributes
    ----------
    view, proj : (4, 4) float64
        World -> eye and eye -> clip matrices.
    width, height : int
        Image size in pixels.
    """

    view: np.ndarray
    proj: np.ndarray
    width: int
    height: int

    @classmethod
    def of(cls, camera, width: int, height: int) -> View:
        """Read ``camera.view_matrix()`` and ``camera.projection_matrix(width, height)``."""
        return cls(
            np.asarray(camera.view_matrix(), dtype=np.float64),
            np.asarray(camera.projection_matrix(width, height), dtype=np.float64),
            int(width),
            int(height),
        )

    @property
    def vp(self) -> np.ndarray:
        """(4, 4) float64 ``proj @ view``."""
        return self.proj @ self.view

    @property
    def eye(self) -> np.ndarray:
        """(3,) float64 eye position in world space (inverse view matrix applied to the origin)."""
        return np.linalg.inv(self.view)[:3, 3]

    def clip(self, points: np.ndarray) -> np.ndarray:
        """(..., 4) float64 clip coordinates of world points (..., 3)."""
        vp = self.vp
        return np.asarray(points, dtype=np.float64) @ vp[:, :3].T + vp[:, 3]

    def depth(self, points: np.ndarray) -> np.ndarray:
        """(...,) float64 view-axis distance -z_eye of world points (..., 3)."""
        v = self.view
        return -(points @ v[2, :3] + v[2, 3])

    def rays(self, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World-space rays through pixel coordinates.

        Parameters
        ----------
        px, py : (...,) float64
            Pixel coordinates (x to the right, y downward; pixel centres at k + 0.5).

        Returns
        -------
        origin, direction : (..., 3) float64
            ``origin`` is on the near plane, ``origin + direction`` on the far plane.
        """
        px = np.asarray(px, dtype=np.float64)
        py = np.asarray(py, dtype=np.float64)
        inv = np.linalg.inv(self.vp)
        x = 2.0 * px / self.width - 1.0
        y = 1.0 - 2.0 * py / self.height

        def unproject(z: float) -> np.ndarray:
            h = np.stack([x, y, np.full_like(x, z), np.ones_like(x)], axis=-1) @ inv.T
            return h[..., :3] / h[..., 3:]

        a = unproject(-1.0)
        b = unproject(1.0)
        return a, b - a


def pixel_centres(width: int, height: int, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates of the sample centres of an ``n x n`` grid per pixel.

    Returns ``(px, py)``, each ``(n H, n W)`` float64: sample (sx, sy) is at ((sx+.5)/n, (sy+.5)/n).
    """
    ys, xs = np.mgrid[0 : n * height, 0 : n * width].astype(np.float64)
    return (xs + 0.5) / n, (ys + 0.5) / n


def intersect(origin, direction, v0, v1, v2):
    """Intersection of rays ``origin + t direction`` with the planes of triangles (float64).

    Vertices are taken relative to the ray origin. The barycentrics are the signed volumes
    d . (s_j x s_k) of the direction with the origin-relative vertices s (the edge tests of
    Moller-Trumbore and of watertight ray tracing, normalized by their sum d . n); t comes from
    the plane equation through the vertex nearest the origin, so a hit close to the camera on a
    huge triangle does not lose its digits to the far vertices.

    All arguments broadcast against each other with a trailing axis of 3.

    Returns
    -------
    t : float64 array of the broadcast shape without the last axis
        Ray parameter of the hit with the unbounded plane; NaN/inf where the ray is parallel.
    b : (..., 3) float64
        Barycentrics of v0, v1, v2 (sum 1); inside the triangle where all are >= 0.
    """
    s0, s1, s2 = v0 - origin, v1 - origin, v2 - origin
    u = np.stack(
        [
            np.sum(direction * np.cross(s1, s2), axis=-1),
            np.sum(direction * np.cross(s2, s0), axis=-1),
            np.sum(direction * np.cross(s0, s1), axis=-1),
        ],
        axis=-1,
    )
    den = u.sum(axis=-1)  # = direction . n with n = (v1 - v0) x (v2 - v0)
    n = np.cross(v1 - v0, v2 - v0)
    s = np.stack(np.broadcast_arrays(s0, s1, s2), axis=-2)  # (..., 3 vertices, 3)
    nearest = np.argmin(np.sum(s * s, axis=-1), axis=-1)
    s_ref = np.take_along_axis(s, nearest[..., None, None], axis=-2)[..., 0, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        b = u / den[..., None]
        t = np.sum(n * s_ref, axis=-1) / np.sum(n * direction, axis=-1)
    return t, b


def _flat(view: View, positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(T,) bool: zero-area triangles (collinear or repeated vertices) and triangles whose plane
    passes through the eye (to FLAT_RTOL). Both project to a segment or a point: rays never hit
    them (the rasterizer may cover a snapped sliver within 1/512 px of that set)."""
    v = positions[faces]
    e1 = v[:, 1] - v[:, 0]
    e2 = v[:, 2] - v[:, 0]
    n = np.cross(e1, e2)
    area = np.linalg.norm(n, axis=-1)
    degenerate = ~(area > 1e-12 * np.linalg.norm(e1, axis=-1) * np.linalg.norm(e2, axis=-1))
    rel = v - view.eye
    reach = np.linalg.norm(rel, axis=-1).max(axis=-1)
    through_eye = np.abs(np.sum(n * rel[:, 0], axis=-1)) <= FLAT_RTOL * area * reach
    return degenerate | through_eye


def _pixel_homogeneous(view: View, points: np.ndarray) -> np.ndarray:
    """(..., 3) (px w, py w, w) of world points: px = (X / W + 1) width / 2, py = (1 - Y / W) height / 2."""
    c = view.clip(points)
    X, Y, W = c[..., 0], c[..., 1], c[..., 3]
    return np.stack([0.5 * view.width * (X + W), 0.5 * view.height * (W - Y), W], axis=-1)


def _flat_distance(view: View, positions, faces, px, py) -> np.ndarray:
    """(R, T) unsigned screen distance (pixels) to the line that flat triangles project onto (to
    the point, if all three vertices lie on one ray through the eye; inf if that is at infinity)."""
    h = _pixel_homogeneous(view, positions[faces])  # (T, 3, 3)
    pairs = [(0, 1), (1, 2), (2, 0)]
    lines = np.stack([np.cross(h[:, i], h[:, j]) for i, j in pairs], axis=1)  # (T, 3, 3)
    size = np.stack(
        [np.linalg.norm(h[:, i], axis=-1) * np.linalg.norm(h[:, j], axis=-1) for i, j in pairs], 1
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        strength = np.nan_to_num(np.hypot(lines[..., 0], lines[..., 1]) / size)
    best = np.argmax(strength, axis=1)
    line = lines[np.arange(len(best)), best]  # (T, 3)
    is_line = strength[np.arange(len(best)), best] > 1e-10
    far_vertex = h[np.arange(len(best)), np.argmax(np.abs(h[..., 2]), axis=1)]  # (T, 3)
    px = np.asarray(px, dtype=np.float64).reshape(-1, 1)
    py = np.asarray(py, dtype=np.float64).reshape(-1, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        d_line = np.abs(px * line[:, 0] + py * line[:, 1] + line[:, 2]) / np.hypot(
            line[:, 0], line[:, 1]
        )
        d_point = np.hypot(
            px - far_vertex[:, 0] / far_vertex[:, 2], py - far_vertex[:, 1] / far_vertex[:, 2]
        )
    d = np.where(is_line, d_line, d_point)
    return np.where(np.isnan(d), np.inf, d)


def front_facing(view: View, positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(T,) bool: triangles counter-clockwise as seen from the eye."""
    v = positions[faces]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    return np.sum((view.eye - v[:, 0]) * n, axis=-1) > 0.0


def _region_lines(view: View, positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(T, K + 2, 3) float64 oriented lines a px + b py + c (>= 0 inside) bounding the visible
    screen region of each planar convex polygon faces[t] (K vertices; K = 3 for triangles): K
    edges (for a triangle: lambda'_i >= 0), near (z + w >= 0) and far (w - z >= 0)."""
    c = view.clip(positions)[faces]  # (T, K, 4): X, Y, Z, W
    Z, W = c[..., 2], c[..., 3]
    h = _pixel_homogeneous(view, positions[faces])  # (T, K, 3)
    edges = np.cross(h, np.roll(h, -1, axis=1))  # (T, K, 3): line through vertices k, k + 1
    # the plane from the first three vertices: lambda'_i = l_i . (px, py, 1) / det
    l0 = np.cross(h[:, 1], h[:, 2])
    l1 = np.cross(h[:, 2], h[:, 0])
    l2 = np.cross(h[:, 0], h[:, 1])
    det = np.sum(h[:, 0] * l0, axis=-1)
    sign = np.where(det < 0.0, -1.0, 1.0)[:, None]
    near = l0 * (Z[:, 0] + W[:, 0])[:, None] + l1 * (Z[:, 1] + W[:, 1])[:, None]
    near = near + l2 * (Z[:, 2] + W[:, 2])[:, None]
    far = l0 * (W[:, 0] - Z[:, 0])[:, None] + l1 * (W[:, 1] - Z[:, 1])[:, None]
    far = far + l2 * (W[:, 2] - Z[:, 2])[:, None]
    lines = np.concatenate([edges, near[:, None], far[:, None]], axis=1)
    return lines * sign[:, :, None]


def region_distance(view: View, positions, faces, px, py) -> np.ndarray:
    """Signed screen distance (pixels) of points to each triangle's visible region.

    The region of a triangle is where a ray hits it in front of the eye between the near and far
    planes: the intersection of five half-planes (2D homogeneous rasterization, so vertices
    behind the eye are handled). The value is the minimum of the signed distances to the five
    lines: positive inside; a value <= -eps means at least eps pixels outside; a value >= eps
    means at least eps pixels inside.

    Parameters
    ----------
    px, py : (R,) float64
    positions : (N, 3) float64
    faces : (T, 3) int, or (T, K) for planar convex polygons (vertices in order)

    Returns
    -------
    (R, T) float64
    """
    positions = np.asarray(positions, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    lines = _region_lines(view, positions, faces)  # (T, K + 2, 3)
    norm = np.hypot(lines[..., 0], lines[..., 1])  # (T, K + 2)
    px = np.asarray(px, dtype=np.float64).reshape(-1)
    py = np.asarray(py, dtype=np.float64).reshape(-1)
    value = (
        px[:, None, None] * lines[None, :, :, 0]
        + py[:, None, None] * lines[None, :, :, 1]
        + lines[None, :, :, 2]
    )  # (R, T, K + 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        sd = np.where(norm > 0.0, value / np.where(norm > 0.0, norm, 1.0), np.sign(value) * np.inf)
    sd = np.where(np.isnan(sd), 0.0, sd)  # a constant-zero line: on the boundary everywhere
    return sd.min(axis=-1)


@dataclass(frozen=True)
class Hits:
    """Nearest hits of a set of rays.

    Attributes
    ----------
    tri : (R,) int64
        Index of the nearest triangle hit between the near and far planes; -1 for none.
    t : (R,) float64
        Ray parameter of that hit (0 on the near plane, 1 on the far plane); inf for none.
    ambiguous : (R,) bool
        Within ``edge_eps`` px of some triangle's region boundary (or of the line a flat
        triangle projects onto), a depth tie, a hit within ``depth_rtol`` of the near or far
        plane, or an internal disagreement (below).
    inconsistent : (R,) bool
        The two independent inside tests of the oracle (ray/triangle, region distance)
        disagree by more than ``edge_eps`` for some triangle: a precision limit of the oracle,
        reported so that tests can bound it; such rays are also marked ambiguous.
    """

    tri: np.ndarray
    t: np.ndarray
    ambiguous: np.ndarray
    inconsistent: np.ndarray

    @property
    def clear(self) -> np.ndarray:
        """(R,) bool: rays where the rasterizer must agree with the oracle exactly."""
        return ~self.ambiguous


def cast(
    view: View,
    positions,
    faces,
    px,
    py,
    *,
    cull_backfaces: bool = False,
    edge_eps: float = EDGE_EPS,
    depth_rtol: float = DEPTH_RTOL,
    chunk: int = 256,
) -> Hits:
    """Brute-force nearest hit of the rays through pixel coordinates ``(px, py)``.

    Parameters
    ----------
    view : View
    positions : (N, 3) float64
    faces : (T, 3) int
    px, py : array_like float64, any shape (flattened; results are (R,) with R = px.size)
    cull_backfaces : bool
        Ignore triangles that are clockwise as seen from the eye.
    edge_eps : float
        Ambiguity band around region boundaries, pixels.
    depth_rtol : float
        Two different triangles whose hits differ by less than this relative depth are a tie;
        a hit this close to the near or far plane is ambiguous.
    """
    positions = np.asarray(positions, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    px = np.asarray(px, dtype=np.float64).reshape(-1)
    py = np.asarray(py, dtype=np.float64).reshape(-1)
    n_rays = px.size
    v = positions[faces]  # (T, 3, 3)
    flat = _flat(view, positions, faces)
    solid = np.flatnonzero(~flat)
    usable = np.ones(len(faces), dtype=bool)
    if cull_backfaces:
        usable &= front_facing(view, positions, faces)
    usable &= ~flat
    tri = np.full(n_rays, -1, dtype=np.int64)
    t_best = np.full(n_rays, np.inf)
    ambiguous = np.zeros(n_rays, dtype=bool)
    inconsistent = np.zeros(n_rays, dtype=bool)
    for lo in range(0, n_rays, chunk):
        sl = slice(lo, min(n_rays, lo + chunk))
        o, d = view.rays(px[sl], py[sl])
        t, b = intersect(o[:, None, :], d[:, None, :], v[None, :, 0], v[None, :, 1], v[None, :, 2])
        w_near = view.depth(o)
        w_far = view.depth(o + d)
        # ray parameters within depth_rtol (relative depth) of the near and far planes
        tol_near = (depth_rtol * w_near / (w_far - w_near))[:, None]
        tol_far = (depth_rtol * w_far / (w_far - w_near))[:, None]
        with np.errstate(invalid="ignore"):
            in_triangle = np.isfinite(t) & np.all(b >= 0.0, axis=-1)
            inside = in_triangle & (t >= 0.0) & (t <= 1.0)
            at_clip_plane = in_triangle & ((np.abs(t) <= tol_near) | (np.abs(t - 1.0) <= tol_far))
        hit = inside & usable[None, :]
        tt = np.where(hit, t, np.inf)
        best = np.argmin(tt, axis=1)
        t1 = tt[np.arange(tt.shape[0]), best]
        found = np.isfinite(t1)
        tri[sl] = np.where(found, best, -1)
        t_best[sl] = t1
        # on the near or far plane: the rasterizer's clip test decides by rounding
        amb = np.any(at_clip_plane & ~flat[None, :], axis=1)
        if tt.shape[1] >= 2:
            t2 = np.partition(tt, 1, axis=1)[:, 1]
            with np.errstate(invalid="ignore"):
                gap = (t2 - t1) * (w_far - w_near)
                amb |= found & (gap <= depth_rtol * (w_near + t1 * (w_far - w_near)))
        if solid.size:
            dist = region_distance(view, positions, faces[solid], px[sl], py[sl])
            amb |= np.any(np.abs(dist) < edge_eps, axis=1)
            odd = np.any((dist > 0) != inside[:, solid], axis=1) & ~amb
            inconsistent[sl] = odd
            amb |= odd
        if solid.size < len(faces):
            near_flat = _flat_distance(view, positions, faces[flat], px[sl], py[sl]) < edge_eps
            amb |= np.any(near_flat, axis=1)
        ambiguous[sl] = amb
    return Hits(tri, t_best, ambiguous, inconsistent)


def _plane_hit(view: View, positions, faces, tri, px, py) -> np.ndarray:
    """(R, 3) exact barycentrics of the rays through (px, py) with the planes of triangles tri."""
    o, d = view.rays(px, py)
    v = positions[faces[tri]]  # (R, 3, 3)
    return intersect(o, d, v[:, 0], v[:, 1], v[:, 2])[1]


def _interpolate(bary: np.ndarray, values: np.ndarray, faces, tri) -> np.ndarray:
    """(R, C) barycentric interpolation of per-vertex values (N, C) over triangles tri (R,)."""
    return np.einsum("rk,rkc->rc", bary, values[faces[tri]])


def _as_columns(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    return a[:, None] if a.ndim == 1 else a


def surface(view: View, positions, faces, tri, px, py, attributes=None) -> dict[str, np.ndarray]:
    """Values at the exact hit of each ray with the plane of its triangle.

    Parameters
    ----------
    tri : (R,) int
        Triangle of each ray (all >= 0).
    px, py : (R,) float64
    attributes : dict of str to (N,) or (N, C) float64, optional
        Per-vertex data (e.g. ``uv``, ``normal`` -- renormalized after interpolation -- or any
        named attribute), interpolated with the exact barycentrics.

    Returns
    -------
    dict with ``bary`` (R, 3), ``position`` (R, 3), ``depth`` (R,), ``ndc_z`` (R,) and one
    (R, C) array per attribute (``normal`` unit length).
    """
    positions = np.asarray(positions, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    tri = np.asarray(tri, dtype=np.int64).reshape(-1)
    px = np.asarray(px, dtype=np.float64).reshape(-1)
    py = np.asarray(py, dtype=np.float64).reshape(-1)
    bary = _plane_hit(view, positions, faces, tri, px, py)
    pos = _interpolate(bary, positions, faces, tri)
    clip = view.clip(pos)
    out = {
        "bary": bary,
        "position": pos,
        "depth": view.depth(pos),
        "ndc_z": clip[:, 2] / clip[:, 3],
    }
    for name, values in (attributes or {}).items():
        val = _interpolate(bary, _as_columns(values), faces, tri)
        if name == "normal":
            val = val / np.linalg.norm(val, axis=-1, keepdims=True)
        out[name] = val
    return out


def derivatives(
    view: View, positions, faces, tri, px, py, attributes, h: float = 1e-3
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per-pixel screen derivatives (d/dx right, d/dy down) of interpolated vertex data.

    Central differences of the exact hits of rays through (x +- h, y) and (x, y +- h) with the
    plane of triangle ``tri`` (the plane, not the triangle: offsets may leave it), Richardson-
    extrapolated from steps h and h / 2 (error O(h^4)).

    Parameters
    ----------
    attributes : dict of str to (N,) or (N, C) float64
        Include ``"position": positions`` for d(position)/dx.

    Returns
    -------
    dict name -> (d_dx (R, C), d_dy (R, C)) float64
    """
    positions = np.asarray(positions, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    tri = np.asarray(tri, dtype=np.int64).reshape(-1)
    px = np.asarray(px, dtype=np.float64).reshape(-1)
    py = np.asarray(py, dtype=np.float64).reshape(-1)
    cols = {k: _as_columns(a) for k, a in attributes.items()}

    def values_at(qx, qy):
        bary = _plane_hit(view, positions, faces, tri, qx, qy)
        return {k: _interpolate(bary, a, faces, tri) for k, a in cols.items()}

    def central(step):
        xp, xm = values_at(px + step, py), values_at(px - step, py)
        yp, ym = values_at(px, py + step), values_at(px, py - step)
        return {k: ((xp[k] - xm[k]) / (2.0 * step), (yp[k] - ym[k]) / (2.0 * step)) for k in cols}

    coarse, fine = central(h), central(h / 2.0)
    return {k: tuple((4.0 * fine[k][i] - coarse[k][i]) / 3.0 for i in range(2)) for k in cols}
