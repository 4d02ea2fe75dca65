"""Small scenes for the render-path tests, built from public API only."""

import numpy as np
import pytest

from refnpr.raster import Camera, Mesh
from refnpr.scenes import Light, Material, Scene, SceneObject


def quad(z: float = 0.0, size: float = 1.0) -> Mesh:
    """A square in the plane z facing +z, with uv and normals."""
    p = np.array([[-size, -size, z], [size, -size, z], [size, size, z], [-size, size, z]], float)
    return Mesh(
        p,
        [[0, 1, 2], [0, 2, 3]],
        normals=np.tile([0.0, 0.0, 1.0], (4, 1)),
        uv=p[:, :2] / (2 * size) + 0.5,
        name="quad",
    )


@pytest.fixture
def plane_scene() -> Scene:
    """A camera-facing quad filling the middle of the view, one directional light."""
    cam = Camera.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 0.1, 100.0)
    mat = Material(
        ambient=(0.1, 0.1, 0.1), diffuse=(0.6, 0.5, 0.4), specular=(0.3, 0.3, 0.3), shininess=16.0
    )
    light = Light(kind="directional", direction=(0.3, 0.4, 1.0), color=(1.0, 1.0, 1.0))
    return Scene(
        objects=(SceneObject(quad(), np.eye(4), mat, "quad"),),
        camera=cam,
        lights=(light,),
        ambient=(1.0, 1.0, 1.0),
        background=(0.0, 0.0, 0.0, 1.0),
        name="plane",
    )
