"""Deterministic test scenes for the oracle comparisons: (meshes, camera, width, height)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refnpr.raster import Camera, Mesh

from .meshes import cube, icosphere, with_data

#: Every built-in channel name, spelled out here (not taken from the code under test).
BUILTIN_CHANNELS = (
    "depth",
    "ndc_z",
    "tri_id",
    "mesh_id",
    "bary",
    "position",
    "normal",
    "uv",
    "duv_dx",
    "duv_dy",
    "lod",
    "dyadic_scale",
    "coverage",
    "coverage_count",
    "dposition_dx",
    "dposition_dy",
)
#: The scenes' scalar vertex attribute and its derivatives.
HEAT_CHANNELS = ("heat", "dheat_dx", "dheat_dy")


@dataclass(frozen=True)
class Scene:
    name: str
    meshes: list[Mesh]
    camera: Camera
    width: int
    height: int


def _frame_points(camera: Camera, xyw) -> np.ndarray:
    """World points eye + x right + y up + w forward (w = view-axis depth) from rows (x, y, w)."""
    right, up, back = camera.basis()
    xyw = np.asarray(xyw, dtype=np.float64)
    return camera.eye + xyw[:, :1] * right + xyw[:, 1:2] * up - xyw[:, 2:3] * back


def _grid(corner, edge_a, edge_b, n: int) -> tuple[np.ndarray, np.ndarray]:
    """An n x n quad grid spanning corner + [0, 1] edge_a + [0, 1] edge_b (2 n^2 triangles)."""
    s = np.linspace(0.0, 1.0, n + 1)
    a, b = np.meshgrid(s, s, indexing="ij")
    pos = corner + a[..., None] * edge_a + b[..., None] * edge_b
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    v00, v10, v01, v11 = idx[:-1, :-1], idx[1:, :-1], idx[:-1, 1:], idx[1:, 1:]
    faces = np.concatenate(
        [np.stack([v00, v10, v11], -1).reshape(-1, 3), np.stack([v00, v11, v01], -1).reshape(-1, 3)]
    )
    return pos.reshape(-1, 3), faces


def mixed() -> Scene:
    """An icosphere, a cube and interpenetrating random triangles; odd, non-square image."""
    rng = np.random.default_rng(11)
    tris = rng.uniform(-1.6, 1.6, size=(8, 3, 3))
    loose = with_data(tris.reshape(-1, 3), np.arange(24).reshape(8, 3), "loose")
    cam = Camera.look_at((2.2, 1.3, 3.1), (0.1, -0.05, 0.0), (0.0, 1.0, 0.0), 55.0, 0.1, 50.0)
    meshes = [icosphere(1, 0.8, (-0.4, 0.1, 0.2)), cube(0.9, (0.7, -0.3, -0.4)), loose]
    return Scene("mixed", meshes, cam, 37, 29)


def close_sphere() -> Scene:
    """A unit icosphere seen from 1.35 radii with a wide lens: strong perspective."""
    cam = Camera.look_at((0.3, 0.4, 1.25), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 75.0, 0.05, 10.0)
    return Scene("close_sphere", [icosphere(2)], cam, 30, 30)


def grazing() -> Scene:
    """A subdivided floor 5 cm below the eye, reaching from behind the camera to near the far
    plane, and a wall at 0.6 degrees to the line of sight."""
    cam = Camera.look_at((0.0, 0.05, 0.0), (0.0, 0.05, -1.0), (0.0, 1.0, 0.0), 60.0, 0.05, 400.0)
    pos, faces = _grid(
        np.array([-60.0, 0.0, 5.0]), np.array([120.0, 0.0, 0.0]), np.array([0.0, 0.0, -300.0]), 4
    )
    floor = with_data(pos, faces, "floor", normals=np.tile([0.0, 1.0, 0.0], (len(pos), 1)))
    slope = np.tan(np.radians(0.6))
    wpos, wfaces = _grid(
        np.array([0.3, -1.0, -0.5]),
        np.array([300.0 * slope, 0.0, -300.0]),
        np.array([0.0, 3.0, 0.0]),
        3,
    )
    wall = with_data(wpos, wfaces[:, ::-1], "wall")
    return Scene("grazing", [floor, wall], cam, 40, 24)


def near_clip() -> Scene:
    """Triangles crossing the near plane and the eye plane (w = 0), partly or wholly behind the
    camera (rows are (x right, y up, w forward) in the camera frame)."""
    cam = Camera.look_at((0.5, 0.2, 1.0), (0.3, 0.0, -3.0), (0.0, 1.0, 0.0), 65.0, 0.5, 30.0)
    xyw = [
        [(-3.0, -2.0, 4.0), (3.0, -2.5, 6.0), (0.5, 1.0, -2.0)],  # one vertex behind the eye
        [(-1.0, 1.5, 3.0), (2.0, 1.4, 0.0), (0.0, -1.0, 2.5)],  # one vertex on the eye plane
        # in front of the eye but before the near plane
        [(-2.0, -0.5, 0.2), (-0.5, -1.0, 5.0), (-1.5, 1.0, 5.5)],
        [(-1.0, -1.0, -1.0), (1.0, -1.0, -1.5), (0.0, 1.0, -2.0)],  # wholly behind the eye
        [(1.0, 0.5, -1.0), (2.0, -0.5, -0.5), (1.2, 0.2, 3.0)],  # two vertices behind the eye
        [(-0.4, 0.6, 1.0), (0.4, 0.7, 1.0), (0.0, -0.3, -1.0)],  # crosses near and w = 0 on screen
    ]
    pos = _frame_points(cam, np.reshape(xyw, (-1, 3)))
    mesh = with_data(pos, np.arange(len(pos)).reshape(-1, 3), "clipped")
    return Scene("near_clip", [mesh], cam, 36, 27)


SCENES = {f.__name__: f for f in (mixed, close_sphere, grazing, near_clip)}
