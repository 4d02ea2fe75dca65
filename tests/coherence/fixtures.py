"""Test scenes, a smooth texture style and a hand-written float64 pinhole projection.

The projection here is written from the OpenGL formulas (gluLookAt, gluPerspective, the
rasterizer's pixel-centre convention), not taken from refnpr, so the motion field is checked
against an independent oracle.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr.raster import Camera, Mesh
from refnpr.scenes import Scene, SceneObject, plane, transform_matrix
from refnpr.styles import Style

EYE = np.array([0.0, 0.0, 5.0])
FOV = 45.0
W, H = 80, 60
#: Amplitude and texture period (uv units) of the Sine style.
AMP = 0.4


class SineStyle(Style):
    """Grey 0.5 + AMP sin(2 pi u) cos(2 pi v): a smooth texture fixed on the surface."""

    name = "test_coherence_sine"

    def requires(self, scene):
        return frozenset({"uv", "mesh_id"})

    def shade(self, ctx):
        uv = ctx.gb["uv"].astype(np.float64)
        v = 0.5 + AMP * np.sin(2 * np.pi * uv[..., 0]) * np.cos(2 * np.pi * uv[..., 1])
        out = np.zeros(uv.shape[:2] + (4,), np.float32)
        m = ctx.mask
        out[m, :3] = v[m][:, None]
        out[m, 3] = 1.0
        return out


def camera(yaw_deg: float = 0.0, eye=EYE) -> Camera:
    """Camera at ``eye`` looking along (sin yaw, 0, -cos yaw)."""
    a = math.radians(yaw_deg)
    eye = np.asarray(eye, dtype=np.float64)
    return Camera.look_at(eye, eye + np.array([math.sin(a), 0.0, -math.cos(a)]), (0, 1, 0), FOV)


def wall(tx=0.0, ty=0.0, tz=0.0, rot=(90.0, 0.0, 0.0), size=20.0, tile=0.5) -> SceneObject:
    """A plane facing +z (rot = 90 deg about x) through (tx, ty, tz)."""
    return SceneObject(
        plane(size, size, tile=tile), transform_matrix((tx, ty, tz), rot), name="wall"
    )


def scene(objects, cam=None) -> Scene:
    return Scene(tuple(objects), cam if cam is not None else camera())


# -- the hand projection --------------------------------------------------------------------
def basis(yaw_deg: float):
    """Right, up, forward of ``camera(yaw_deg)``, written out by hand."""
    a = math.radians(yaw_deg)
    fwd = np.array([math.sin(a), 0.0, -math.cos(a)])
    right = np.array([math.cos(a), 0.0, math.sin(a)])  # fwd x up
    return right, np.array([0.0, 1.0, 0.0]), fwd


def project(points, yaw_deg=0.0, eye=EYE, width=W, height=H):
    """World points (K, 3) -> pixel (x, y) (K, 2) and clip w (K,), float64."""
    right, up, fwd = basis(yaw_deg)
    d = np.asarray(points, np.float64) - np.asarray(eye, np.float64)
    xe, ye, w = d @ right, d @ up, d @ fwd  # w = -z_eye
    f = 1.0 / math.tan(math.radians(FOV) / 2)
    aspect = width / height
    x_ndc = f / aspect * xe / w
    y_ndc = f * ye / w
    return np.stack([(x_ndc + 1) * width / 2, (1 - y_ndc) * height / 2], -1), w


def pixel_rays(yaw_deg=0.0, width=W, height=H):
    """World directions (H, W, 3) through every pixel centre (unit view-axis component)."""
    right, up, fwd = basis(yaw_deg)
    f = 1.0 / math.tan(math.radians(FOV) / 2)
    aspect = width / height
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    x_ndc = 2 * (xs + 0.5) / width - 1
    y_ndc = 1 - 2 * (ys + 0.5) / height
    return (
        (x_ndc * aspect / f)[..., None] * right
        + (y_ndc / f)[..., None] * up
        + np.ones_like(xs)[..., None] * fwd
    )


def hit_plane(point, normal, yaw_deg=0.0, eye=EYE):
    """(H, W, 3) world points where the pixel rays of ``camera(yaw_deg)`` meet a plane."""
    rays = pixel_rays(yaw_deg)
    lam = ((np.asarray(point) - eye) @ normal) / (rays @ normal)
    return eye + lam[..., None] * rays


def pixel_size(w: float, height=H) -> float:
    """World size of one pixel at view distance w."""
    return 2 * w * math.tan(math.radians(FOV) / 2) / height


def quad(x0, x1, y0, y1, z, dx=0.0) -> SceneObject:
    """An axis-aligned rectangle facing +z at height z, translated by ``dx`` along x."""
    pos = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)
    mesh = Mesh(pos, faces, normals, uv, name="quad")
    return SceneObject(mesh, transform_matrix((dx, 0.0, 0.0)), name="quad")
