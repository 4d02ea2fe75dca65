"""Kit export of the contour layer (Veryovka 2002 sec. 5), called by
``refnpr.kit.styles.export_style`` for any style wrapped with ``contours = {...}``; its params
go to ``params["contours"]``.

Every ``ContourLayer`` field is exported as used (``width``, ``ink``, ``silhouettes``,
``boundaries``, ``crease_angle`` (null: no creases), ``depth_tolerance``), plus the two numbers
the drawing derives from them on the case's sample grid: ``radius_samples`` (= width n / 2) and
``piece_samples`` (0.5: edges are drawn in pieces of at most half a sample). The edges
themselves are derived by the backend from the meshes (``derived["contour_edges"]``).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from refnpr.styles.contours import CONTOURS

from .._json import jsonable
from ._export import StyleExport

__all__ = ["export_contours", "unresolved", "DERIVED", "PIECE_SAMPLES"]

#: Length of the pieces an edge is drawn in, in samples (the contour layer's piece length).
PIECE_SAMPLES = 0.5

DERIVED = {
    "contour_edges": (
        "Per object (its own .glb), from its POSITION in float64: vertices with bitwise-equal "
        "POSITION rows are welded (a welded vertex is represented by its lowest index); each "
        "triangle f, in index-buffer order, has the welded edges (v0, v1), (v1, v2), (v2, v0); "
        "edges whose two welded ends coincide are dropped; an undirected edge's faces are the "
        "triangles containing it in increasing index, the first two kept (one face: a boundary "
        "edge; more than two: the first two). Face normal n_f = normalize(cross(p1 - p0, p2 - "
        "p0)) of the triangle's own vertices (0 where the cross product is 0); dihedral angle = "
        "degrees(arccos(clip(n_f0 . n_f1, -1, 1))) (0 on boundaries). Per frame a face is "
        "front-facing when n_f . (camera.eye - c_f) > 0, c_f = (p0 + p1 + p2) / 3. Selected "
        "edges: silhouettes (two faces, exactly one of them front-facing) if "
        "params.contours.silhouettes, boundaries if params.contours.boundaries, creases (two "
        "faces, dihedral > params.contours.crease_angle) if crease_angle is not null."
    ),
    "contour_drawing": (
        "On the sample grid (n W x n H, n = sqrt(spp)), coverage c starts at 0 per sample; per "
        "selected edge (a, b) in float64: clip = VP (p, 1) of both ends (VP = projection_matrix @ "
        "view_matrix, rows summed as the vertex stage does), d = z + w per end; both d < 0: "
        "dropped; else t0 = d_a / (d_a - d_b) if d_a < 0 (else 0) and t1 = d_a / (d_a - d_b) if "
        "d_b < 0 (else 1), the clipped ends a + t0 (b - a) and a + t1 (b - a) in clip space; "
        "dropped if either clipped w <= 0. Sample-grid coordinates of the clipped ends A and B "
        "(eye depths w_a, w_b: their clip w): x = (x_c / w + 1) n W / 2, y = (1 - y_c / w) n H / "
        "2 (sample s has its centre at s + 0.5); length = |B - A|; k = max(1, ceil(length / "
        "params.contours.piece_samples)), at most 4 (n W + n H). Piece j in 0 .. k - 1 spans s0 = "
        "j / k .. s1 = (j + 1) / k of the projected segment; at its midpoint s_m = (s0 + s1) / 2, "
        "(x_m, y_m) = A + s_m (B - A) and the eye depth w_m = 1 / (1 / w_a + s_m (1 / w_b - 1 / "
        "w_a)) (1/w is affine on screen). The piece is visible when w_m <= (1 + "
        "params.contours.depth_tolerance) * F, F the largest depth-channel value (float64 of the "
        "stored value; +inf where empty) of the 3 x 3 samples (floor(x_m) - 1 .. floor(x_m) + 1, "
        "floor(y_m) - 1 .. floor(y_m) + 1) that lie inside the grid (none inside: hidden). A "
        "visible piece sets, for every sample (i, j), c = max(c, min(r + 0.5 - D, 1)), r = "
        "params.contours.radius_samples (= width n / 2), D the distance from the sample centre p "
        "= (i + 0.5, j + 0.5) to the piece's segment P0 = A + s0 (B - A) .. P1 = A + s1 (B - A) "
        "(the nearest point at parameter clip(((p - P0) . (P1 - P0)) / |P1 - P0|^2, 0, 1), 0 for "
        "a zero-length piece). The lines are then composited per sample over the style's "
        "straight-alpha RGBA (rgb, A) (as float32, then float64): a = c + A (1 - c), rgb' = "
        "(params.contours.ink c + rgb A (1 - c)) / a where a > 0 (else 0), alpha a; then the "
        "background composite and resolve."
    ),
}


def export_contours(
    layer: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Every field of a ``ContourLayer`` as used, plus ``radius_samples`` (width * n / 2 for
    spp = n * n) and ``piece_samples``; no textures."""
    params = CONTOURS.resolved(layer.p)
    params["radius_samples"] = 0.5 * float(layer.width) * math.isqrt(int(spp))
    params["piece_samples"] = PIECE_SAMPLES
    return StyleExport(params=jsonable(params, where="contours params"), derived=dict(DERIVED))


def unresolved(params: dict[str, Any]) -> list[str]:
    """Declared layer parameters missing from ``params`` (the contour layer's own dict)."""
    return [k for k in CONTOURS.names if k not in params]
