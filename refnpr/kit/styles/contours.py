"""Kit export of the contour layer (refnpr/styles/contours.py; Veryovka 2002 sec. 5), called by
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

#: Length of the pieces an edge is drawn in, in samples (refnpr draw_edges' ``step``).
PIECE_SAMPLES = 0.5

DERIVED = {
    "contour_edges": (
        "Per object (its own .glb), weld vertices by exact position (np.unique over POSITION "
        "rows, each welded vertex represented by its first index) and collect the unique "
        "undirected edges of the triangles (degenerate edges dropped), each with its first two "
        "faces in face order (one face: a boundary edge; more than two: the first two). "
        "Dihedral angle = degrees(arccos(clip(n0.n1, -1, 1))) of the unit geometric face "
        "normals cross(p1 - p0, p2 - p0) (0 on boundaries). Per frame a face is front-facing "
        "when n.(eye - centroid) > 0 (centroid = mean of its 3 vertices). Selected edges: "
        "silhouettes (two faces, front != back) if params.contours.silhouettes, boundaries if "
        "params.contours.boundaries, creases (two faces, dihedral > crease_angle) if "
        "crease_angle is not null (refnpr/styles/contours.py: edge_table, selected_edges)."
    ),
    "contour_drawing": (
        "On the sample grid (n W x n H, n = sqrt(spp)), per selected edge: clip = VP p of its "
        "two vertices (VP = projection_matrix @ view_matrix); clip to the near plane "
        "(d = z + w >= 0; an edge with both d < 0 is dropped, else the outside end moves to "
        "t = d_a / (d_a - d_b)); drop it if a w <= 0; sample coordinates x = (x/w + 1) nW / 2, "
        "y = (1 - y/w) nH / 2 (sample s has its centre at s + 0.5); split into k = max(1, "
        "ceil(length / piece_samples)) pieces (at most 4 (nW + nH)); a piece is visible when "
        "at its midpoint (eye depth w from 1/w interpolated linearly along the segment) w <= "
        "(1 + depth_tolerance) * the largest depth-channel value of the 3 x 3 samples around "
        "(floor(x), floor(y)) (inside the grid; none inside: hidden). Visible pieces are drawn "
        "as capsules: coverage(sample) = max over pieces of min(radius_samples + 0.5 - "
        "distance(sample centre, piece), 1), clamped below at 0. The layer is composited per "
        "sample over the style's straight-alpha RGBA: a = c + A (1 - c), rgb = (ink c + rgb A "
        "(1 - c)) / a where a > 0 (refnpr/styles/_kernels.py draw_edges, contours.py "
        "Contoured.shade), before the background composite and resolve."
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
