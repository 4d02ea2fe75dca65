"""Cameras, sample positions and pixel conventions as kit JSON."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["CONVENTIONS", "camera_entry", "sample_positions"]

#: How a backend maps the matrices to pixels (the rasterizer contract of DESIGN.md).
CONVENTIONS: dict[str, str | float] = {
    "matrices": "row-major nested lists: m[row][col]; clip = projection_matrix @ view_matrix @ "
    "[x, y, z, 1] (column vectors; upload transposed, or with GL_TRUE, to a column-major API)",
    "eye_space": "OpenGL: the camera looks down -Z, +Y up; depth channel = -z_eye = w_clip",
    "ndc_z": "[-1, 1] (OpenGL)",
    "pixel_center": 0.5,
    "row0": "top",
    "ndc_x": "2 (x + 0.5) / W - 1",
    "ndc_y": "1 - 2 (y + 0.5) / H",
    "sample_grid": "spp = n * n samples per pixel render as an n W x n H image with the SAME "
    "projection_matrix (aspect W / H): sample-grid pixel (X, Y) has NDC x = 2 (X + 0.5) / (n W) "
    "- 1, y = 1 - 2 (Y + 0.5) / (n H)",
    "derivatives": "d/dx to the right, d/dy DOWN (growing image rows), per IMAGE pixel of the "
    "W x H image, not per sample-grid pixel: on the n W x n H sample grid a backend multiplies "
    "its per-sample-pixel derivatives (dFdx, dFdy) by n; d/dy = -dFdy when the render target's "
    "y axis points up",
    "fill_rule": "top-left, on vertices snapped to 1/256 of an image pixel (floor(256 x + 0.5), "
    "round half up); attributes interpolated from the unsnapped positions",
    "front_face": "counter-clockwise seen from outside in world space; refnpr draws both faces "
    "(no culling)",
}


def _matrix(m: np.ndarray) -> list[list[float]]:
    return [[float(v) for v in row] for row in np.asarray(m, dtype=np.float64)]


def camera_entry(camera: Any, width: int, height: int) -> dict[str, Any]:
    """A camera as case.json's ``camera`` object.

    Parameters
    ----------
    camera : refnpr.raster.Camera
    width, height : int
        The image size (the projection's aspect is width / height).

    Returns
    -------
    dict
        ``eye``, ``target``, ``up`` (3 floats), ``fov_y`` (degrees, vertical), ``near``, ``far``,
        ``view_matrix`` and ``projection_matrix`` (4x4 row-major, exactly refnpr's float64
        matrices), ``conventions``.
    """
    return {
        "eye": [float(v) for v in camera.eye],
        "target": [float(v) for v in camera.target],
        "up": [float(v) for v in camera.up],
        "fov_y": float(camera.fov_y),
        "near": float(camera.near),
        "far": float(camera.far),
        "view_matrix": _matrix(camera.view_matrix()),
        "projection_matrix": _matrix(camera.projection_matrix(width, height)),
        "conventions": dict(CONVENTIONS),
    }


def sample_positions(spp: int) -> list[list[float]]:
    """The n x n sample offsets inside a pixel, in pixels, in refnpr's order (sy outer, sx
    inner): sample (sx, sy) sits at ((sx + 0.5) / n, (sy + 0.5) / n).

    Raises
    ------
    ValueError
        If ``spp`` is not a positive square number.
    """
    n = math.isqrt(spp) if isinstance(spp, int) and spp > 0 else 0
    if n * n != spp or n == 0:
        raise ValueError(f"spp: expected a positive square number (n * n), got {spp!r}")
    return [[(sx + 0.5) / n, (sy + 0.5) / n] for sy in range(n) for sx in range(n)]
