"""Test geometry for the rasterizer tests: closed meshes, screen-placed points, random cameras."""

from __future__ import annotations

import numpy as np
import trimesh

from refnpr.raster import Camera, Mesh

from .oracle import View


def with_data(positions, faces, name: str = "mesh", normals=None) -> Mesh:
    """A Mesh with normals (given, or the positions' directions from the origin jittered), a uv
    that is a smooth non-affine function of position, and a 2-column attribute ``heat``."""
    p = np.asarray(positions, dtype=np.float64)
    if normals is None:
        normals = p + np.array([0.1, -0.2, 0.3])
    uv = np.stack([0.5 * p[:, 0] + 0.25 * p[:, 2] + 0.3, 0.4 * p[:, 1] - 0.35 * p[:, 2] + 0.1], -1)
    heat = np.stack([p[:, 0] * p[:, 1] + 2.0, np.sin(p[:, 2]) - p[:, 0]], -1)
    return Mesh(p, faces, normals=normals, uv=uv, attributes={"heat": heat}, name=name)


def icosphere(subdivisions: int = 2, radius: float = 1.0, center=(0.0, 0.0, 0.0)) -> Mesh:
    """trimesh's icosphere (closed, counter-clockwise outward) with data (see :func:`with_data`)."""
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return with_data(s.vertices + np.asarray(center), s.faces, "icosphere", s.vertex_normals)


def cube(size: float = 1.5, center=(0.0, 0.0, 0.0)) -> Mesh:
    """trimesh's box (12 triangles, closed, counter-clockwise outward) with data."""
    b = trimesh.creation.box(extents=(size, size, size))
    return with_data(b.vertices + np.asarray(center), b.faces, "cube")


def torus(major: float = 1.0, minor: float = 0.4, n_major: int = 24, n_minor: int = 12) -> Mesh:
    """A closed torus around the z axis built by hand, counter-clockwise seen from outside."""
    a = 2.0 * np.pi * np.arange(n_major) / n_major
    b = 2.0 * np.pi * np.arange(n_minor) / n_minor
    A, B = np.meshgrid(a, b, indexing="ij")
    ring = major + minor * np.cos(B)
    pos = np.stack([ring * np.cos(A), ring * np.sin(A), minor * np.sin(B)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    i1, j1 = (i + 1) % n_major, (j + 1) % n_minor
    v00, v10 = i * n_minor + j, i1 * n_minor + j
    v01, v11 = i * n_minor + j1, i1 * n_minor + j1
    faces = np.concatenate(
        [np.stack([v00, v10, v11], -1).reshape(-1, 3), np.stack([v00, v11, v01], -1).reshape(-1, 3)]
    )
    return with_data(pos, faces, "torus")


def concat(meshes: list[Mesh]) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Concatenated positions, faces (global ids, as rasterize numbers them) and vertex data."""
    pos = np.concatenate([m.positions for m in meshes])
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes])[:-1]
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets, strict=True)])
    data: dict[str, np.ndarray] = {}
    if all(m.uv is not None for m in meshes):
        data["uv"] = np.concatenate([m.uv for m in meshes])
    if all(m.normals is not None for m in meshes):
        data["normal"] = np.concatenate([m.normals for m in meshes])
    for name in set.intersection(*(set(m.attributes) for m in meshes)):
        data[name] = np.concatenate([m.attributes[name] for m in meshes])
    return pos, faces, data


def at_pixels(view: View, px, py, depth) -> np.ndarray:
    """(R, 3) world points that project to pixel coordinates (px, py) at view-axis ``depth``."""
    o, d = view.rays(np.atleast_1d(px), np.atleast_1d(py))
    w0, w1 = view.depth(o), view.depth(o + d)
    t = (np.broadcast_to(depth, w0.shape) - w0) / (w1 - w0)
    return o + t[:, None] * d


def random_outside_camera(rng: np.random.Generator, radius: float, fov: float = 50.0) -> Camera:
    """A camera on a random direction, 2.5 to 4 radii from the origin, looking near the origin."""
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    eye = direction * radius * rng.uniform(2.5, 4.0)
    target = rng.normal(scale=0.15 * radius, size=3)
    up = rng.normal(size=3)
    return Camera.look_at(eye, target, up, fov, 0.05 * radius, 20.0 * radius)
