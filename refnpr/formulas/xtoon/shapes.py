"""Abstracted normal fields of a mesh for X-Toon shape detail (Barla et al. 2006, sec. 4, Fig. 5).

Four abstracted shapes: the mesh with smoothed normals, and an enclosing ellipsoid, cylinder and
sphere. The paper only says the ellipse's "dimensions come from a bounding box" and that the
mapping is "straightforward analytic"; refnpr's reading:

- The box is the bounding box of the vertices in a frame (``frame="pca"``: the principal axes of
  the surface's area-weighted second moments, so the shapes follow the "principal direction of
  elongation" of Fig. 5c/d whatever the mesh's orientation; ``frame="aabb"``: the world axes).
  Its centre c is the box centre; its half extents are the ellipsoid's semi-axes.
- A vertex p maps radially from c onto the shape, whose normal there is returned: the ellipsoid
  normal is normalize(R diag(1/a^2) R^T (p - c)), the sphere normal normalize(p - c), the
  (infinite, uncapped) cylinder normal the part of p - c perpendicular to the principal axis (the
  box axis with the largest extent).
- Where that is undefined (p at the centre or on the axis) the vertex keeps its own normal.

All functions take plain arrays, ``positions (N, 3)``, ``faces (M, 3)`` int and ``normals (N, 3)``,
and return ``(N, 3)`` unit float64 normals (float32 if positions and normals are float32).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float, check_int, check_scalar, describe, result_dtype

__all__ = [
    "shape_frame",
    "smoothed_normals",
    "ellipsoid_normals",
    "cylinder_normals",
    "sphere_normals",
]


def _mesh(positions, faces, normals=None):
    p = as_float("positions", positions, finite=True)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 1:
        raise ValueError(
            f"positions: expected shape (N, 3) with N >= 1, got {describe(p)}; one row per vertex"
        )
    f = np.asarray(faces)
    if f.dtype.kind not in "iu" or f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(
            f"faces: expected an integer array of shape (M, 3), got {describe(f)}; "
            "one row of three vertex indices per triangle"
        )
    if f.size and (f.min() < 0 or f.max() >= p.shape[0]):
        raise ValueError(
            f"faces: indices must lie in [0, {p.shape[0] - 1}], got min {f.min()}, max {f.max()}; "
            "use zero-based indices into positions"
        )
    if normals is None:
        return p, f.astype(np.intp), None
    n = as_float("normals", normals, finite=True)
    if n.shape != p.shape:
        raise ValueError(
            f"normals: expected shape {p.shape} (one per vertex), got {describe(n)}; "
            "compute vertex normals first"
        )
    return p, f.astype(np.intp), n


def _normalize(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    ok = norm > 1e-12 * max(float(np.max(norm, initial=0.0)), 1e-300)
    safe = np.where(ok, norm, 1.0)
    fb_norm = np.linalg.norm(fallback, axis=-1, keepdims=True)
    fb = fallback / np.where(fb_norm > 0, fb_norm, 1.0)
    return np.where(ok, v / safe, fb)


def _out(v: np.ndarray, p: np.ndarray, n: np.ndarray) -> np.ndarray:
    return v.astype(result_dtype(p, n), copy=False)


def shape_frame(positions, faces, *, frame: str = "pca"):
    """The box an abstracted shape is built from.

    Parameters
    ----------
    positions : (N, 3) float
    faces : (M, 3) int
    frame : {"pca", "aabb"}
        ``"pca"``: axes are the eigenvectors of the surface's area-weighted second moments about
        its area centroid (vertex moments if the mesh has no area); ``"aabb"``: world axes.

    Returns
    -------
    center : (3,) float64, the box centre
    axes : (3, 3) float64, rows are unit axes, sorted by decreasing half extent
    half_extents : (3,) float64, non-increasing
    """
    p, f, _ = _mesh(positions, faces)
    p = p.astype(np.float64)
    if frame == "aabb":
        axes = np.eye(3)
    elif frame == "pca":
        axes = _pca_axes(p, f)
    else:
        raise ValueError(f"frame: expected 'pca' or 'aabb', got {frame!r}")
    q = p @ axes.T
    lo, hi = q.min(axis=0), q.max(axis=0)
    half = (hi - lo) / 2
    order = np.argsort(-half, kind="stable")
    center = ((lo + hi) / 2) @ axes
    return center, axes[order], half[order]


def _pca_axes(p: np.ndarray, f: np.ndarray) -> np.ndarray:
    if f.size:
        v0, v1, v2 = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
        area = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
    else:
        area = np.zeros(0)
    if area.sum() > 0:
        total = area.sum()
        s = v0 + v1 + v2
        mean = (area[:, None] * s).sum(axis=0) / (3 * total)
        # exact surface moment of a triangle: A/12 (sum v_i v_i^T + s s^T)
        second = sum(np.einsum("m,mi,mj->ij", area, v, v) for v in (v0, v1, v2))
        second = (second + np.einsum("m,mi,mj->ij", area, s, s)) / (12 * total)
        cov = second - np.outer(mean, mean)
    else:
        cov = np.cov(p.T, bias=True) if p.shape[0] > 1 else np.zeros((3, 3))
    _, vecs = np.linalg.eigh(np.atleast_2d(cov))
    return vecs[:, ::-1].T  # rows, decreasing variance


def smoothed_normals(
    positions,
    faces,
    normals,
    *,
    iterations: int = 10,
    weighting: str = "uniform",
    weld_tol: float | None = 0.0,
) -> np.ndarray:
    """Smoothed normals by iterated neighbour averaging (Fig. 5b).

    Each iteration replaces a vertex normal by the normalized sum of itself and its edge
    neighbours' normals (``weighting="inverse_length"`` weights neighbours by 1 / edge length).

    Parameters
    ----------
    positions : (N, 3) float
    faces : (M, 3) int
    normals : (N, 3) float
    iterations : int >= 0
    weighting : {"uniform", "inverse_length"}
    weld_tol : float >= 0 or None
        Vertices whose positions agree (exactly for 0, after rounding to a grid of this size
        otherwise) are merged for the averaging, so smoothing crosses seams of duplicated
        vertices; ``None`` uses the face connectivity only.

    Returns
    -------
    (N, 3) unit normals
    """
    p, f, n = _mesh(positions, faces, normals)
    iterations = check_int("iterations", iterations, lo=0)
    if weighting not in ("uniform", "inverse_length"):
        raise ValueError(f"weighting: expected 'uniform' or 'inverse_length', got {weighting!r}")
    pf = p.astype(np.float64)
    if weld_tol is None:
        inv = np.arange(p.shape[0])
    else:
        tol = check_scalar("weld_tol", weld_tol, lo=0.0)
        key = pf if tol == 0 else np.round(pf / tol)
        _, inv = np.unique(key, axis=0, return_inverse=True)
        inv = inv.ravel()
    nw = int(inv.max()) + 1
    nf = _normalize(n.astype(np.float64), n.astype(np.float64))
    cur = np.stack([np.bincount(inv, nf[:, k], minlength=nw) for k in range(3)], axis=1)
    first = np.zeros(nw, dtype=np.intp)
    first[inv[::-1]] = np.arange(p.shape[0])[::-1]  # a representative vertex per welded vertex
    cur = _normalize(cur, nf[first])
    e = inv[f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)]
    e = np.unique(np.sort(e, axis=1), axis=0)
    e = e[e[:, 0] != e[:, 1]]
    if weighting == "uniform":
        w = np.ones(len(e))
    else:
        length = np.linalg.norm(pf[first[e[:, 0]]] - pf[first[e[:, 1]]], axis=1)
        w = 1.0 / np.maximum(length, 1e-300)
    for _ in range(iterations):
        acc = cur.copy()
        for k in range(3):
            acc[:, k] += np.bincount(e[:, 0], w * cur[e[:, 1], k], minlength=nw)
            acc[:, k] += np.bincount(e[:, 1], w * cur[e[:, 0], k], minlength=nw)
        cur = _normalize(acc, cur)  # neighbour average, renormalized
    return _out(cur[inv], p, n)


def ellipsoid_normals(positions, faces, normals, *, frame: str = "pca") -> np.ndarray:
    """Normals of the bounding-box ellipsoid (Fig. 5c), by radial projection from its centre.

    Parameters
    ----------
    positions : (N, 3) float
    faces : (M, 3) int
    normals : (N, 3) float (used where the projection is undefined)
    frame : {"pca", "aabb"}, see :func:`shape_frame`

    Returns
    -------
    (N, 3) unit normals
    """
    p, f, n = _mesh(positions, faces, normals)
    c, axes, half = shape_frame(p, f, frame=frame)
    a = np.maximum(half, 1e-9 * max(half[0], 1e-300))  # flat boxes: avoid 1/0
    q = (p.astype(np.float64) - c) @ axes.T  # box frame
    grad = (q / a**2) @ axes  # gradient of sum (q_k / a_k)^2
    return _out(_normalize(grad, n.astype(np.float64)), p, n)


def cylinder_normals(positions, faces, normals, *, frame: str = "pca") -> np.ndarray:
    """Normals of an infinite circular cylinder along the principal axis (Fig. 5d).

    The axis passes through the box centre along the box axis of largest extent. Parameters
    and result as :func:`ellipsoid_normals`.
    """
    p, f, n = _mesh(positions, faces, normals)
    c, axes, _ = shape_frame(p, f, frame=frame)
    d = p.astype(np.float64) - c
    a = axes[0]
    radial = d - (d @ a)[:, None] * a  # component perpendicular to the axis
    return _out(_normalize(radial, n.astype(np.float64)), p, n)


def sphere_normals(positions, faces, normals, *, frame: str = "pca") -> np.ndarray:
    """Normals of a sphere centred on the bounding box (Fig. 5e): normalize(p - c).

    Parameters and result as :func:`ellipsoid_normals` (``frame`` moves only the centre;
    ``normals`` serve at the centre).
    """
    p, f, n = _mesh(positions, faces, normals)
    c, _, _ = shape_frame(p, f, frame=frame)
    return _out(_normalize(p.astype(np.float64) - c, n.astype(np.float64)), p, n)
