"""World points to pixels as the rasterizer projects vertices, for arrays of points (motion,
flow, stroke anchors): ``refnpr.device.projection.project`` at every point."""

from __future__ import annotations

import numpy as np

from refnpr.device.projection import project
from refnpr.formulas._face import Whole, elementwise

__all__ = ["project_points"]


def project_points(
    points: np.ndarray, vp: np.ndarray, width: int, height: int
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates and clip w of world points.

    Parameters
    ----------
    points : (..., 3) float
        World positions.
    vp : (4, 4) float
        ``Camera.view_projection(width, height)``.
    width, height : int
        Image size in pixels (x right, y down, pixel centres at +0.5).

    Returns
    -------
    xy : (..., 2) float64
        Continuous pixel coordinates; NaN where w_clip <= 0 (at or behind the eye).
    w : (...) float64
        Clip w (the view-axis distance for a perspective camera).
    """
    p = np.asarray(points, dtype=np.float64)
    m = np.ascontiguousarray(vp, dtype=np.float64)
    size = (float(width), float(height))
    out = elementwise(project, np.float64, Whole(m), (p[..., 0], p[..., 1], p[..., 2]), size)
    return out[..., :2], out[..., 2]
