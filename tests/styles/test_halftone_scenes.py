"""Small scenes for the halftone style tests (public API only; no tests in this module)."""

from __future__ import annotations

import numpy as np

from refnpr.raster import Camera
from refnpr.scenes import Light, Material, Scene, SceneObject, plane, transform_matrix


def wall(
    intensity: float = 0.5,
    *,
    light=(0.0, 0.0, 1.0),
    size: float = 2.0,
    distance: float = 5.0,
    fov: float = 30.0,
    ambient: float = 0.0,
    texture: str | None = None,
) -> Scene:
    """A square ``size`` x ``size`` facing the camera (normal +z, u along +x, v along +y, uv in
    [0, 1]^2), fully in view, lit by one directional light: with the default light along the
    normal and no ambient, the target intensity is ``intensity`` everywhere."""
    mesh = plane(size, size, tile=size)
    obj = SceneObject(
        mesh,
        transform_matrix(rotate_deg=(90.0, 0.0, 0.0)),
        Material(ambient=ambient, diffuse=intensity, specular=0.0, texture=texture),
        name="wall",
    )
    cam = Camera.look_at((0.0, 0.0, distance), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), fov, 0.1, 50.0)
    return Scene((obj,), cam, (Light(direction=tuple(np.asarray(light, float))),))
