"""The scene data model: meshes with transforms and materials, a camera, lights.

World space is right-handed with +y up (the built-in meshes stand on y = 0). The renderer
and the CLI read these frozen dataclasses; :mod:`refnpr.scenes.toml_format` builds them from
scene files.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..formulas._validate import BEYOND_FLOAT_RANGE
from ..raster import Camera, Mesh
from ._params import check_real, check_type, check_vec
from .animation import Animation

__all__ = ["Material", "Light", "SceneObject", "Scene", "transform_matrix"]

LIGHT_KINDS = ("directional", "point")


def _set(obj, **values) -> None:
    """Assign fields of a frozen dataclass (in ``__post_init__``)."""
    for name, value in values.items():
        object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class Material:
    """Material terms of Veryovka 2002 eq. 1 plus the texture a style may use.

    Attributes
    ----------
    ambient, diffuse, specular : tuple of 3 float
        m_a, m_d, m_s (>= 0, RGB). A single number stands for a grey.
    shininess : float
        Specular exponent (> 0).
    texture : str or None
        Name of a built-in texture, a file path, or an image held in memory (a
        :class:`refnpr.texture.EmbeddedImage`, a ``str`` that carries a glTF file's embedded
        PNG or JPEG): a threshold texture or screen; styles decide how to use it (through
        :func:`refnpr.texture.load_texture`). Paths in scene files are resolved against the
        file's directory.
    uv_scale : tuple of 2 float
        Multiplies uv before texture lookup (> 0). A single number scales both.
    color_texture : str or None
        The material's colour map (glTF's ``baseColorTexture``): an RGB image (a file path,
        built-in name or :class:`refnpr.texture.EmbeddedImage`) whose values, sRGB-decoded
        and sampled trilinearly at the scaled uv, multiply m_a and m_d per sample in the
        styles that shade with the material's colour (``smooth``, ``toon``:
        :func:`refnpr.styles.albedo.albedo_grid`). None: m_a and m_d alone.
    """

    ambient: tuple[float, float, float] = (0.15, 0.15, 0.15)
    diffuse: tuple[float, float, float] = (0.8, 0.8, 0.8)
    specular: tuple[float, float, float] = (0.3, 0.3, 0.3)
    shininess: float = 32.0
    texture: str | None = None
    uv_scale: tuple[float, float] = (1.0, 1.0)
    color_texture: str | None = None

    def __post_init__(self) -> None:
        colors = {
            k: check_vec(k, getattr(self, k), 3, broadcast_scalar=True, nonnegative=True)
            for k in ("ambient", "diffuse", "specular")
        }
        shininess = check_real("shininess", self.shininess, positive=True)
        textures = {}
        for key in ("texture", "color_texture"):
            value = getattr(self, key)
            value = str(value) if isinstance(value, Path) else value
            if value is not None and (not isinstance(value, str) or not value):
                raise TypeError(
                    f"{key}: expected a texture name or a file path (non-empty str; an "
                    f"EmbeddedImage for an image in memory) or None, got {value!r}"
                )
            textures[key] = value
        uv_scale = check_vec("uv_scale", self.uv_scale, 2, broadcast_scalar=True, positive=True)
        _set(self, **colors, shininess=shininess, **textures, uv_scale=uv_scale)


@dataclass(frozen=True)
class Light:
    """A light source of Veryovka 2002 eq. 1.

    Attributes
    ----------
    kind : {"directional", "point"}
    direction : tuple of 3 float
        Unit vector *towards* the light (directional lights); normalized on construction.
    position : tuple of 3 float or None
        World position (point lights; required for them, must be None for directional ones).
    color : tuple of 3 float
        Light intensity l_i (RGB, >= 0).
    """

    kind: str = "directional"
    direction: tuple[float, float, float] = (1.0, 1.0, 1.0)
    position: tuple[float, float, float] | None = None
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        if self.kind not in LIGHT_KINDS:
            raise ValueError(
                f"kind: unknown light kind {self.kind!r}; expected one of {LIGHT_KINDS}"
            )
        d = check_vec("direction", self.direction, 3)
        big = max(abs(x) for x in d)
        if big == 0.0:
            raise ValueError(
                "direction: must not be the zero vector; give the direction to the light"
            )
        squares = sum(x * x for x in d)
        if not 2.0**-960 < squares < math.inf:  # the squares under- or overflow: scale first
            d = tuple(x / big for x in d)
            squares = sum(x * x for x in d)
        length = math.sqrt(squares)
        position = self.position
        if self.kind == "point":
            if position is None:
                raise ValueError("position: a point light needs a position [x, y, z]")
            position = check_vec("position", position, 3)
        elif position is not None:
            raise ValueError(
                f"position: a directional light has no position (got {position!r}); "
                "use kind='point' or give only a direction"
            )
        color = check_vec("color", self.color, 3, broadcast_scalar=True, nonnegative=True)
        _set(self, direction=tuple(x / length for x in d), position=position, color=color)


def transform_matrix(
    translate=(0.0, 0.0, 0.0), rotate_deg=(0.0, 0.0, 0.0), scale=1.0
) -> np.ndarray:
    """Object-to-world matrix ``T @ Rz @ Ry @ Rx @ S``, (4, 4) float64.

    Parameters
    ----------
    translate : 3 floats
    rotate_deg : 3 floats
        Rotations about x, then y, then z (degrees, counter-clockwise looking down the axis).
    scale : float or 3 floats
        Uniform or per-axis scale (non-zero).
    """
    t = check_vec("translate", translate, 3)
    rx, ry, rz = (math.radians(a) for a in check_vec("rotate_deg", rotate_deg, 3))
    s = check_vec("scale", scale, 3, broadcast_scalar=True)
    if any(x == 0.0 for x in s):
        raise ValueError(f"scale: must be non-zero on every axis, got {list(s)}")
    cx, sx = math.cos(rx), math.sin(rx)
    cy, sy = math.cos(ry), math.sin(ry)
    cz, sz = math.cos(rz), math.sin(rz)
    r_x = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    r_y = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    r_z = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    m = np.eye(4)
    m[:3, :3] = r_z @ r_y @ r_x @ np.diag(s)
    m[:3, 3] = t
    return m


def _as_transform(value) -> np.ndarray:
    try:
        m = np.array(value, dtype=np.float64)
    except OverflowError:  # a Python int of about 309 digits or more
        raise ValueError(
            f"transform: expected a finite (4, 4) matrix, got {BEYOND_FLOAT_RANGE}"
        ) from None
    except (TypeError, ValueError) as exc:
        raise TypeError(f"transform: expected a (4, 4) array of numbers, got {value!r}") from exc
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise ValueError(f"transform: expected a finite (4, 4) matrix, got shape {m.shape}")
    if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"transform: the last row must be (0, 0, 0, 1), got {m[3].tolist()}")
    with np.errstate(over="ignore", under="ignore"):  # a huge scale: its coordinates are checked
        det = np.linalg.det(m[:3, :3])
    if abs(det) < 1e-300:
        raise ValueError("transform: the 3x3 part is singular; use a non-zero scale")
    m.setflags(write=False)
    return m


@dataclass(frozen=True, eq=False)
class SceneObject:
    """A mesh placed in the scene.

    Attributes
    ----------
    mesh : Mesh
        In object space.
    transform : (4, 4) float64
        Object-to-world affine matrix (read-only copy).
    material : Material
    name : str
        Defaults to the mesh's name.
    """

    mesh: Mesh
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    material: Material = field(default_factory=Material)
    name: str = ""

    def __post_init__(self) -> None:
        check_type("mesh", self.mesh, Mesh, "a refnpr Mesh")
        transform = _as_transform(self.transform)
        check_type("material", self.material, Material, "a Material")
        check_type("name", self.name, str, "a str")
        _set(self, transform=transform, name=self.name or self.mesh.name)

    def world_mesh(self) -> Mesh:
        """The mesh in world space (itself for the identity transform), memoized (meshes are immutable)."""
        cached = self.__dict__.get("_world_mesh")
        if cached is None:
            identity = np.array_equal(self.transform, np.eye(4))
            cached = self.mesh if identity else self.mesh.transformed(self.transform)
            object.__setattr__(self, "_world_mesh", cached)
        return cached


@dataclass(frozen=True, eq=False)
class Scene:
    """Objects, a camera and lights: everything a render needs besides the style.

    Attributes
    ----------
    objects : tuple of SceneObject
    camera : Camera
    lights : tuple of Light
    ambient : tuple of 3 float
        Ambient light intensity l_a of Veryovka eq. 1 (>= 0).
    background : tuple of 4 float
        RGBA clear colour in [0, 1].
    name : str
    style : dict
        The scene file's default style, e.g. ``{"name": "toon", "n": 3}`` (empty if none).
    animation : Animation or None
        Tracks over frames, each naming a part of this scene; None for a still. :meth:`at` gives
        the still scene of a frame.
    """

    objects: tuple[SceneObject, ...]
    camera: Camera
    lights: tuple[Light, ...] = (Light(),)
    ambient: tuple[float, float, float] = (1.0, 1.0, 1.0)
    background: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    name: str = "scene"
    style: dict = field(default_factory=dict)
    animation: Animation | None = None

    def __post_init__(self) -> None:
        objects = tuple(self.objects)
        if not objects:
            raise ValueError("objects: a scene needs at least one object")
        for i, obj in enumerate(objects):
            check_type(f"objects[{i}]", obj, SceneObject, "a SceneObject")
        check_type("camera", self.camera, Camera, "a Camera (Camera.look_at(...))")
        lights = tuple(self.lights)
        for i, light in enumerate(lights):
            check_type(f"lights[{i}]", light, Light, "a Light")
        ambient = check_vec("ambient", self.ambient, 3, broadcast_scalar=True, nonnegative=True)
        background = check_vec("background", self.background, 4)
        if not all(0.0 <= c <= 1.0 for c in background):
            raise ValueError(
                f"background: RGBA components must lie in [0, 1], got {list(background)}"
            )
        check_type("name", self.name, str, "a str")
        check_type("style", self.style, dict, "a dict")
        _set(self, objects=objects, lights=lights, ambient=ambient, background=background)
        _set(self, style=dict(self.style))
        if self.animation is not None:
            check_type("animation", self.animation, Animation, "an Animation or None")
            self.animation.check_scene(self)

    @property
    def frames(self) -> int:
        """Number of frames: the animation's, 1 for a still scene (frame 0 of one frame)."""
        return 1 if self.animation is None else self.animation.frames

    def at(self, frame: float) -> Scene:
        """The still scene of ``frame`` in ``[0, frames - 1]`` (fractional frames interpolate; time =
        frame / fps): the same objects and meshes, with the frame's camera, lights, object
        transforms and style table, and ``animation=None``. A still scene is its own frame 0.

        Raises
        ------
        ValueError
            A frame outside the range, or one whose interpolated values are invalid (a camera whose
            eye reaches its target, a zero scale), naming the frame.
        """
        if self.animation is None:
            if isinstance(frame, bool) or not isinstance(frame, (int, float, np.number)):
                raise TypeError(f"frame: expected a number, got {type(frame).__name__} {frame!r}")
            if frame != 0:
                raise ValueError(
                    f"frame: {frame!r} is outside [0, 0]: scene {self.name!r} is a still (no "
                    "[animation] table), which has only frame 0"
                )
            return self
        return self.animation.still(self, frame)

    def world_meshes(self) -> list[Mesh]:
        """Each object's mesh transformed to world space, in object order."""
        return [obj.world_mesh() for obj in self.objects]

    def with_camera(self, camera: Camera) -> Scene:
        """A copy with another camera."""
        return dataclasses.replace(self, camera=camera)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World-space axis-aligned bounding box ``(lo, hi)``, each (3,) float64."""
        meshes = self.world_meshes()
        lo = np.min([m.positions.min(axis=0) for m in meshes], axis=0)
        hi = np.max([m.positions.max(axis=0) for m in meshes], axis=0)
        return lo, hi
