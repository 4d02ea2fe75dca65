"""Pinhole camera with the OpenGL view and projection matrices other backends use verbatim."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np

from ..formulas._validate import BEYOND_FLOAT_RANGE, to_float

__all__ = ["Camera"]


def _vec3(name: str, value) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except OverflowError:  # a Python int of about 309 digits or more
        raise ValueError(f"{name}: must be finite, got {BEYOND_FLOAT_RANGE}") from None
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected 3 numbers, got {value!r}") from exc
    if arr.shape != (3,):
        raise ValueError(f"{name}: expected 3 numbers (x, y, z), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: must be finite, got {arr.tolist()}")
    return arr


def _real(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a real number, got {type(value).__name__} {value!r}")
    v = to_float(name, value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    return v


@dataclass(frozen=True)
class Camera:
    """A perspective camera.

    Build it with :meth:`look_at`. ``view_matrix()`` is the OpenGL world->eye matrix (the camera
    looks down -Z of eye space, +Y up); ``projection_matrix(width, height)`` is the OpenGL
    perspective matrix (NDC z in [-1, 1], aspect = width / height). A GLSL/WGSL/CUDA backend that
    uses these two matrices verbatim sees exactly the geometry refnpr rasterizes.

    Attributes
    ----------
    eye, target, up : (3,) float64
    fov_y : float
        Vertical field of view in degrees, in (0, 180).
    near, far : float
        Clip distances along the view axis, 0 < near < far.
    """

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov_y: float
    near: float
    far: float

    @classmethod
    def look_at(
        cls,
        eye,
        target,
        up=(0.0, 1.0, 0.0),
        fov_y: float = 45.0,
        near: float = 0.1,
        far: float = 100.0,
    ) -> Camera:
        """Camera at ``eye`` looking at ``target`` with ``up`` as the approximate up direction.

        Raises
        ------
        ValueError
            If ``near <= 0``, ``far <= near``, ``fov_y`` is outside (0, 180), ``eye == target``
            or ``up`` is parallel to the view direction.
        """
        eye = _vec3("eye", eye)
        target = _vec3("target", target)
        up = _vec3("up", up)
        fov_y = _real("fov_y", fov_y)
        near = _real("near", near)
        far = _real("far", far)
        if not 0.0 < fov_y < 180.0:
            raise ValueError(
                f"fov_y: expected degrees in (0, 180), got {fov_y}; typical values are 30-60"
            )
        if near <= 0.0:
            raise ValueError(f"near: expected a positive clip distance, got {near}; use e.g. 0.1")
        if far <= near:
            raise ValueError(f"far: must be greater than near ({near}), got {far}")
        if not (math.isfinite(2.0 * far * near) and math.isfinite(far + near)):
            most = sys.float_info.max / (2.0 * max(near, 1.0))
            raise ValueError(
                f"far: {far} with near {near} overflows the perspective matrix (2 far near / "
                f"(near - far), projection_matrix); give a far of at most {most:.4g}"
            )
        forward = target - eye
        if np.linalg.norm(forward) == 0.0:
            raise ValueError(
                f"target: equals eye {eye.tolist()}; the camera needs a view direction"
            )
        if np.linalg.norm(np.cross(forward, up)) <= 1e-12 * np.linalg.norm(
            forward
        ) * np.linalg.norm(up):
            raise ValueError(
                f"up: {up.tolist()} is parallel to the view direction {forward.tolist()}; "
                "choose an up vector that is not along the line of sight"
            )
        for a in (eye, target, up):
            a.setflags(write=False)
        return cls(eye, target, up, fov_y, near, far)

    # -- derived frames -------------------------------------------------------------------------
    @property
    def forward(self) -> np.ndarray:
        """Unit view direction (world space)."""
        f = self.target - self.eye
        return f / np.linalg.norm(f)

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Right, up and backward unit vectors (rows of the view rotation)."""
        f = self.forward
        s = np.cross(f, self.up)
        s /= np.linalg.norm(s)
        u = np.cross(s, f)
        return s, u, -f

    def view_matrix(self) -> np.ndarray:
        """(4, 4) float64 OpenGL world->eye matrix (gluLookAt)."""
        s, u, b = self.basis()
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = s, u, b
        m[:3, 3] = -m[:3, :3] @ self.eye
        return m

    def projection_matrix(self, width: int, height: int) -> np.ndarray:
        """(4, 4) float64 OpenGL perspective matrix (gluPerspective) for a ``width`` x ``height`` image."""
        if isinstance(width, bool) or not isinstance(width, (int, np.integer)) or width <= 0:
            raise ValueError(f"width: expected a positive integer, got {width!r}")
        if isinstance(height, bool) or not isinstance(height, (int, np.integer)) or height <= 0:
            raise ValueError(f"height: expected a positive integer, got {height!r}")
        aspect = width / height
        f = 1.0 / math.tan(math.radians(self.fov_y) / 2.0)
        n, fa = self.near, self.far
        p = np.zeros((4, 4))
        p[0, 0] = f / aspect
        p[1, 1] = f
        p[2, 2] = (fa + n) / (n - fa)
        p[2, 3] = 2.0 * fa * n / (n - fa)
        p[3, 2] = -1.0
        return p

    def view_projection(self, width: int, height: int) -> np.ndarray:
        """(4, 4) float64 ``projection_matrix @ view_matrix``."""
        return self.projection_matrix(width, height) @ self.view_matrix()

    def orbit(self, azimuth_deg: float = 0.0, elevation_deg: float = 0.0) -> Camera:
        """A copy rotated about ``target``: azimuth about ``up``, then elevation (degrees)."""

        def rotate(v, axis, a):  # Rodrigues' formula about a unit axis
            return (
                v * math.cos(a)
                + np.cross(axis, v) * math.sin(a)
                + axis * np.dot(axis, v) * (1 - math.cos(a))
            )

        up = self.up / np.linalg.norm(self.up)
        off = rotate(self.eye - self.target, up, math.radians(_real("azimuth_deg", azimuth_deg)))
        right = np.cross(off, up)
        if np.linalg.norm(right) > 0:
            e = math.radians(_real("elevation_deg", elevation_deg))
            off = rotate(off, right / np.linalg.norm(right), e)
        return Camera.look_at(
            self.target + off, self.target, self.up, self.fov_y, self.near, self.far
        )
