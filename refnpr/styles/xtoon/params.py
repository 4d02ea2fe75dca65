"""Validation of the X-Toon style's parameters (clear errors naming the parameter and the fix)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.raster import Camera
from refnpr.styles._common import check_uv_scale
from refnpr.styles._declare import NOT_NONE, Param, Params, check_number, short_repr

from .shape import SHAPES, AbstractedNormals

__all__ = [
    "DETAILS",
    "vec3",
    "camera_spec",
    "transforms_spec",
    "unit_map",
    "WeightSpec",
    "weight_spec",
]

#: Attribute maps (X-Toon sec. 3 and sec. 5) and what each needs.
DETAILS = ("depth", "focus", "orientation", "highlight", "flow", "map", "none")

_CAMERA_KEYS = ("eye", "target", "up", "fov_y", "near", "far")


def vec3(name: str, value: Any) -> tuple[float, float, float]:
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected 3 finite numbers [x, y, z], got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def camera_spec(name: str, value: Any) -> Camera:
    """A Camera from a Camera or a table ``{eye, target, up?, fov_y?, near?, far?}``."""
    if isinstance(value, Camera):
        return value
    if not isinstance(value, Mapping):
        raise TypeError(
            f"{name}: expected a refnpr Camera or a table {{eye = [...], target = [...], "
            f"up = [...], fov_y = ...}}, got {type(value).__name__} {value!r}"
        )
    extra = set(value) - set(_CAMERA_KEYS)
    missing = {"eye", "target"} - set(value)
    if extra or missing:
        raise ValueError(
            f"{name}: camera table keys must be among {list(_CAMERA_KEYS)} and include eye and "
            f"target; got {sorted(value)}"
        )
    try:
        return Camera.look_at(**dict(value))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: {exc}") from None


def transforms_spec(name: str, value: Any) -> np.ndarray:
    """Object transforms ``(M, 4, 4)`` float64 from a sequence of M 4x4 matrices (one per scene
    object, in scene order), each finite with last row (0, 0, 0, 1) and an invertible 3x3 part."""
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        a = None
    if a is None or isinstance(value, (str, bytes)) or a.ndim != 3 or a.shape[1:] != (4, 4):
        raise ValueError(
            f"{name}: expected one 4x4 matrix per scene object (a list of (4, 4) arrays, e.g. "
            f"[o.transform for o in prev_scene.objects]), got {short_repr(value)}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: the matrices must be finite, got {short_repr(value)}")
    for i, m in enumerate(a):
        if not np.array_equal(m[3], (0.0, 0.0, 0.0, 1.0)):
            raise ValueError(
                f"{name}[{i}]: the last row must be (0, 0, 0, 1) (an affine transform), got "
                f"{m[3].tolist()}"
            )
        if np.linalg.det(m[:3, :3]) == 0.0:
            raise ValueError(f"{name}[{i}]: the 3x3 part is singular; use a non-zero scale")
    return a


def unit_map(name: str, value: Any) -> np.ndarray:
    """A per-pixel map in [0, 1]: a 2D array or an image path (read as grey, no sRGB decoding)."""
    if isinstance(value, str) or hasattr(value, "__fspath__"):
        from refnpr.texture import load_texture

        value = load_texture(value, gray=True, param=name)
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected a 2D array of values in [0, 1], got {value!r}") from exc
    if a.ndim != 2:
        raise ValueError(
            f"{name}: expected a 2D per-pixel map (H, W) or per-sample map (n H, n W), got shape "
            f"{a.shape}"
        )
    if not np.all(np.isfinite(a)) or a.min() < 0.0 or a.max() > 1.0:
        raise ValueError(
            f"{name}: values must be finite and lie in [0, 1], got range [{np.nanmin(a)}, "
            f"{np.nanmax(a)}]; rescale the map"
        )
    return a


@dataclass(frozen=True, eq=False)
class WeightSpec:
    """The shape-abstraction weight: ``kind`` is "global", "detail", "texture" or "map"."""

    kind: str
    value: float = 1.0
    texture: np.ndarray | None = None
    uv_scale: tuple[float, float] = (1.0, 1.0)
    summary: Any = None


def weight_spec(name: str, value: Any) -> WeightSpec:
    """Parse ``shape_weight``: a number in [0, 1], "detail", {"texture": ..., "uv_scale": ...} or
    a 2D array in [0, 1]."""
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        hint = "0 keeps the mesh normals, 1 uses the abstracted shape's normals (X-Toon sec. 4)"
        w = check_number(name, value, lo=0.0, hi=1.0, hint=hint)
        return WeightSpec("global", w, summary=w)
    if isinstance(value, str):
        if value == "detail":
            return WeightSpec("detail", summary="detail")
        raise ValueError(
            f"{name}: the only string accepted is 'detail' (w = 1 - D of the detail map), got "
            f"{value!r}"
        )
    if isinstance(value, Mapping):
        extra = set(value) - {"texture", "uv_scale"}
        if "texture" not in value or extra:
            raise ValueError(
                f"{name}: a weight texture table is {{texture = <built-in name or image path>, "
                f"uv_scale = 1.0}}, got keys {sorted(value)}"
            )
        tex = unit_map(f"{name}['texture']", value["texture"])
        scale = check_uv_scale(f"{name}['uv_scale']", value.get("uv_scale", 1.0)) or (1.0, 1.0)
        return WeightSpec("texture", texture=tex, uv_scale=scale, summary=dict(value))
    if isinstance(value, (np.ndarray, Sequence)):
        arr = unit_map(name, value)
        return WeightSpec("map", texture=arr, summary=f"array{arr.shape}")
    raise TypeError(
        f"{name}: expected a number in [0, 1], 'detail' (w = 1 - D), a table {{texture = ...}} or "
        f"a 2D array in [0, 1], got {value!r}"
    )


# ---------------------------------------------------------------------- the declaration

#: What ``show`` draws: the toon texture, or an attribute as a grey image whose displayed
#: (sRGB) value is D ("detail", Fig. 4's convention: dark = low detail), 1 - D ("inverse_detail",
#: Fig. 3's: near or in focus = dark) or the tone.
SHOWS = ("color", "detail", "inverse_detail", "tone")
#: The two depths of a point of X-Toon Fig. 2: along the view (focal) axis, or to the eye.
DISTANCES = ("axis", "eye")
_FLOW = {"detail": ("flow",)}


def _object_names(name: str, value: Any) -> tuple[str, ...]:
    """``shape_objects`` as a tuple of object names (a list of str)."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise TypeError(
            f"{name}: expected a list of object names, got {type(value).__name__} {value!r}"
        )
    if not all(isinstance(o, str) for o in value):
        raise TypeError(f"{name}: expected a list of object names (str), got {value!r}")
    return tuple(value)


def _shape(name: str, value: Any) -> Any:
    if (
        (isinstance(value, str) and value in SHAPES)
        or isinstance(value, AbstractedNormals)
        or (callable(value) and not isinstance(value, str))
    ):
        return value
    raise ValueError(
        f"{name}: expected None, one of {sorted(SHAPES)}, an AbstractedNormals "
        f"(abstract_normals(scene, ...)) or a callable mesh -> (N, 3) normals, got {value!r}"
    )


def _shape_label(shape: Any) -> str | None:
    if shape is None or isinstance(shape, str):
        return shape
    if isinstance(shape, AbstractedNormals):
        return f"AbstractedNormals({shape.shape})"
    return getattr(shape, "__name__", "callable")


def camera_table(cam: Camera) -> dict[str, Any]:
    """A camera as the table ``prev_camera`` accepts."""
    return {k: np.asarray(getattr(cam, k)).tolist() for k in _CAMERA_KEYS}


def _texture_label(spec: Any) -> Any:
    if isinstance(spec, (str, dict)):
        return spec
    if hasattr(spec, "__fspath__"):
        return str(spec)
    return f"array{np.shape(spec)[:2] + (4,)}"  # the resolved RGBA texture's shape


_SHAPED = {"shape": NOT_NONE}

PARAMS = Params(
    "xtoon",
    Param(
        "texture",
        "loa_blur",
        "2D toon texture, rows growing with D and columns with tone: a "
        "preset name, an image path, {preset}, {image, flip, srgb}, {recipe, ramp, ...}, or an "
        "array (rows, cols[, C]) of linear values in [0, 1] (C = 1 grey, 2 grey + alpha, 3 RGB, "
        "4 RGBA)",
        kind="any",
        summary=_texture_label,
        accepts="str, table or array",
    ),
    Param(
        "detail",
        "depth",
        "the attribute map giving D: depth, focus (sec. 3.1), "
        "orientation, highlight (sec. 3.2), flow (sec. 5), a user map, or none (D = 1)",
        kind="choice",
        choices=DETAILS,
    ),
    Param(
        "detail_mode",
        "pixel",
        "pixel: D evaluated per sample from interpolated quantities "
        "(exact); vertex: per vertex and interpolated perspective-correctly (the paper's "
        "vertex shader; for flow the displacement vector)",
        kind="choice",
        choices=("pixel", "vertex"),
    ),
    Param(
        "distance",
        None,
        "the depth of the depth and focus maps: axis, the view-axis "
        "distance (Fig. 2b), or eye, the distance to the eye (Fig. 2a); none: the paper's "
        "(axis for depth, eye for focus)",
        kind="choice",
        choices=DISTANCES,
        optional=True,
        used_when={"detail": ("depth", "focus")},
    ),
    Param(
        "show",
        "color",
        "color: the toon texture; detail, inverse_detail, tone: D, 1 - D "
        "or the tone as opaque grey whose displayed (sRGB) value is that quantity (the "
        "attribute maps of Figs. 3, 4)",
        kind="choice",
        choices=SHOWS,
    ),
    Param(
        "tone",
        "clamped",
        "the tone coordinate: clip(n.l, 0, 1) (sec. 3) or half_lambert (n.l + 1) / 2",
        kind="choice",
        choices=("clamped", "half_lambert"),
    ),
    Param(
        "light",
        0,
        "index of the scene light giving l",
        kind="int",
        lo=0,
        hint="it indexes the scene's lights",
    ),
    Param(
        "z_min",
        None,
        "depth: where D starts to fall (none: the nearest depth of the "
        "scene's bounding box, at least near); focus: half-width of the sharp region (none: "
        "0.1 z_c)",
        lo=0.0,
        lo_open=True,
        unit="world units",
        optional=True,
        used_when={"detail": ("depth", "focus")},
        hint="z_min is a distance (X-Toon sec. 3.1); give a positive value",
    ),
    Param(
        "r",
        None,
        "depth, focus: z_max / z_min > 1, coarsest detail at r z_min (none: the "
        "scene box's far / near depth for depth, 4 for focus); orientation: the exponent of "
        "|n.v|^r, >= 0 (none: 1)",
        optional=True,
        used_when={"detail": ("depth", "focus", "orientation")},
    ),
    Param(
        "focus_point",
        None,
        "world position [x, y, z] of the focus point c (focus), in front "
        "of the camera with z_c - r z_min > 0",
        kind="any",
        parse=vec3,
        unit="world units",
        accepts="3 floats",
        used_when={"detail": ("focus",)},
    ),
    Param(
        "s",
        16.0,
        "shininess of the highlight map |v.r|^s (sec. 3.2)",
        lo=1.0,
        used_when={"detail": ("highlight",)},
        hint="X-Toon sec. 3.2 takes a shininess s >= 1",
    ),
    Param(
        "one_sided",
        False,
        "highlight with max(v.r, 0)^s instead of the paper's |v.r|^s, "
        "which also lights v.r near -1",
        kind="bool",
    ),
    Param(
        "prev_camera",
        None,
        "the previous frame's camera (flow): a Camera or {eye, target, "
        "up, fov_y, near, far}; none: the current camera (a still is frame 0), or in a "
        "sequence the previous frame's",
        kind="any",
        parse=camera_spec,
        accepts="Camera or table",
        summary=camera_table,
        used_when=_FLOW,
    ),
    Param(
        "prev_transforms",
        None,
        "the previous frame's object-to-world matrices, one 4x4 per "
        "scene object (flow with moving objects); in a sequence the previous frame's",
        kind="any",
        parse=transforms_spec,
        accepts="(M, 4, 4) floats",
        summary=lambda a: a.tolist(),
        used_when=_FLOW,
    ),
    Param(
        "flow_min",
        0.0,
        "flow length where D starts to fall (sec. 5)",
        lo=0.0,
        unit="px",
        hint="a flow length in pixels",
        used_when=_FLOW,
    ),
    Param(
        "flow_max",
        16.0,
        "flow length where D reaches 0 (sec. 5), > flow_min",
        unit="px",
        used_when=_FLOW,
    ),
    Param(
        "detail_map",
        None,
        "D per pixel (H, W), repeated over the samples, or per sample "
        "(nH, nW), values in [0, 1], or a grey image path (map)",
        kind="any",
        parse=unit_map,
        summary=lambda a: f"array{a.shape}",
        accepts="array or path",
        used_when={"detail": ("map",)},
    ),
    Param(
        "shape",
        None,
        "the abstracted shape of sec. 4: smoothed, ellipsoid, cylinder, "
        "sphere, an AbstractedNormals (precomputed) or a callable mesh -> (N, 3) normals",
        kind="any",
        parse=_shape,
        summary=_shape_label,
        accepts="str, object or callable",
    ),
    Param(
        "shape_weight",
        1.0,
        "weight of the abstracted normals: a number in [0, 1]; detail "
        "(w = 1 - D of the same map, with the mesh normals); {texture, uv_scale} (a grey "
        "texture at uv, per pixel); or an (H, W) array",
        kind="any",
        parse=weight_spec,
        summary=lambda w: w.summary,
        accepts="float, str, table or array",
        used_when=_SHAPED,
    ),
    Param(
        "shape_blend",
        "vertex",
        "vertex: (1 - w) n + w n_abstract per vertex, interpolated, "
        "renormalized per pixel (the paper's); pixel: both normals interpolated and "
        "renormalized, then blended (blend_normals)",
        kind="choice",
        choices=("vertex", "pixel"),
        used_when=_SHAPED,
    ),
    Param(
        "shape_frame",
        "pca",
        "box frame of the ellipsoid, cylinder and sphere shapes",
        kind="choice",
        choices=("pca", "aabb"),
        used_when=_SHAPED,
    ),
    Param(
        "shape_iterations",
        10,
        "neighbour-averaging iterations of the smoothed shape",
        kind="int",
        lo=0,
        hi=10_000,
        hint="a few tens of iterations already give a smooth field",
        used_when=_SHAPED,
    ),
    Param(
        "shape_objects",
        None,
        "names of the objects to abstract (none: all)",
        kind="any",
        parse=_object_names,
        used_when=_SHAPED,
        accepts="list of str",
    ),
    Param(
        "modulate",
        False,
        "multiply the texture colour by each object's diffuse colour",
        kind="bool",
    ),
    frame=("log_r", "focus", "rows", "cols"),
    module=__name__,
)
