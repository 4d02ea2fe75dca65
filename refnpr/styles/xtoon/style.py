"""The ``xtoon`` style class (Barla et al. 2006): parameters, channels and per-sample shading; the
package docstring (:mod:`refnpr.styles.xtoon`) describes the technique.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from .._common import check_choice, warn_unused
from ..base import ShadeContext, Style, register
from .detail import DEFAULT_DISTANCE, DISTANCES, DetailParams
from .evaluation import Config, evaluate, plan, vertex_values
from .geometry import VertexGeometry
from .params import DETAILS, camera_spec, number, transforms_spec, unit_map, vec3, weight_spec
from .shading import shade_rgba
from .shape import SHAPES, AbstractedNormals
from .texture import resolve_texture

__all__ = ["XToonStyle"]

#: What ``shade`` draws: the toon texture, or an attribute as a grey image whose displayed
#: (sRGB) value is D ("detail", Fig. 4's convention: dark = low detail), 1 - D ("inverse_detail",
#: Fig. 3's: near or in focus = dark) or the tone.
SHOWS = ("color", "detail", "inverse_detail", "tone")

_R_HINT = "r is the ratio z_max / z_min of X-Toon sec. 3.1 (coarsest detail at z_max = r z_min)"


def _bool(name: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected a bool, got {value!r}")
    return bool(value)


@register
class XToonStyle(Style):
    """X-Toon shading (Barla et al. 2006); see the module docstring and ``docs/xtoon.md``.

    Parameters
    ----------
    texture : str, table or array
        2D toon texture: a preset name (``PRESETS``), an image path, ``{"image": path, "flip":
        bool, "srgb": bool}``, ``{"recipe": ..., "ramp": [...], ...}`` or an array
        ``(rows, cols[, C])`` with rows growing with D.
    detail : {"depth", "focus", "orientation", "highlight", "flow", "map", "none"}
    detail_mode : {"pixel", "vertex"}
    distance : {"axis", "eye"}, optional
        The depth of depth and focus maps (Fig. 2): along the view axis or to the eye (default:
        the paper's, "axis" for depth and "eye" for focus).
    show : {"color", "detail", "inverse_detail", "tone"}
        "color" (default) draws the toon texture; the others draw D, 1 - D or the tone as opaque
        grey (displayed sRGB value = the quantity), the attribute-map images of Figs. 3 and 4.
    tone : {"clamped", "half_lambert"}
    light : int
        Index of the scene light giving l.
    z_min : float > 0, optional
        depth: distance where detail starts to fall (default: nearest depth of the scene box);
        focus: half-width of the sharp region around the focus (default 0.1 z_c).
    r : float, optional
        depth/focus: > 1 (default: depth range of the scene box / focus 4); orientation: the
        exponent, >= 0 (default 1).
    focus_point : 3 floats
        World position of the focus point c (``focus``); must be in front of the camera.
    s : float >= 1
        Shininess of the highlight map.
    one_sided : bool
        Highlight with max(v . r, 0) instead of the paper's |v . r|.
    prev_camera : Camera or table {eye, target, up, fov_y, near, far}, optional
        The previous frame's camera (``flow``). Without it a still has no motion (zero flow,
        full detail: a still is frame 0 of a sequence), and in a sequence :meth:`for_frame`
        takes the previous frame's camera.
    prev_transforms : list of 4x4 matrices, optional
        The previous frame's object transforms (``flow``), one per scene object in scene order:
        each object-space vertex goes through them and ``prev_camera`` for its previous screen
        position (default: the current transforms, still objects). :meth:`for_frame` takes
        them from the previous frame.
    flow_min, flow_max : float
        Flow lengths in pixels where D starts to fall and reaches 0.
    detail_map : (H, W) or (n H, n W) array in [0, 1], or a grey image path (``map``).
    shape : None, {"smoothed", "ellipsoid", "cylinder", "sphere"}, AbstractedNormals or callable
    shape_weight : float in [0, 1], "detail", {"texture": name_or_path, "uv_scale": s} or array
    shape_blend : {"vertex", "pixel"}
    shape_frame : {"pca", "aabb"}
    shape_iterations : int in [0, 10000]
        Smoothing iterations of the "smoothed" shape.
    shape_objects : list of str, optional
        Objects to abstract (default: all).
    modulate : bool
        Multiply the texture colour by each object's diffuse material colour.
    """

    name = "xtoon"
    description = (
        "X-Toon: 2D toon texture by tone and detail (depth, focus, orientation, highlight, flow) "
        "with shape abstraction (Barla et al. 2006)"
    )

    def __init__(
        self,
        *,
        texture: Any = "loa_blur",
        detail: str = "depth",
        detail_mode: str = "pixel",
        distance: str | None = None,
        show: str = "color",
        tone: str = "clamped",
        light: int = 0,
        z_min: float | None = None,
        r: float | None = None,
        focus_point: Any = None,
        s: float = 16.0,
        one_sided: bool = False,
        prev_camera: Any = None,
        prev_transforms: Any = None,
        flow_min: float = 0.0,
        flow_max: float = 16.0,
        detail_map: Any = None,
        shape: Any = None,
        shape_weight: Any = 1.0,
        shape_blend: str = "vertex",
        shape_frame: str = "pca",
        shape_iterations: int = 10,
        shape_objects: Any = None,
        modulate: bool = False,
    ) -> None:
        check_choice("detail", detail, DETAILS)
        check_choice("detail_mode", detail_mode, ("pixel", "vertex"))
        check_choice("show", show, SHOWS)
        check_choice("tone", tone, ("clamped", "half_lambert"))
        if isinstance(light, bool) or not isinstance(light, (int, np.integer)) or light < 0:
            raise ValueError(f"light: expected a light index >= 0, got {light!r}")
        tex = resolve_texture(texture)
        (distance, z_min, r, focus_point, prev_camera, prev_transforms, detail_map) = (
            _without_unused_detail_params(
                detail,
                distance=distance,
                z_min=z_min,
                r=r,
                focus_point=focus_point,
                prev_camera=prev_camera,
                prev_transforms=prev_transforms,
                detail_map=detail_map,
            )
        )
        if distance is not None:
            check_choice("distance", distance, DISTANCES)
        elif detail in DEFAULT_DISTANCE:
            distance = DEFAULT_DISTANCE[detail]
        if z_min is not None:
            z_min = number(
                "z_min",
                z_min,
                lo=0.0,
                lo_open=True,
                hint="z_min is a distance (X-Toon sec. 3.1); give a positive value",
            )
        if r is not None:
            if detail in ("depth", "focus"):
                r = number("r", r, lo=1.0, lo_open=True, hint=_R_HINT + "; use r > 1, e.g. 4")
            else:
                r = number("r", r, lo=0.0, hint="the near-silhouette exponent of |n.v|^r is >= 0")
        if detail == "focus":
            if focus_point is None:
                raise ValueError("focus_point: detail='focus' needs the focus point [x, y, z]")
            focus_point = vec3("focus_point", focus_point)
        s = number("s", s, lo=1.0, hint="X-Toon sec. 3.2 takes a shininess s >= 1")
        one_sided = _bool("one_sided", one_sided)
        prev = None if prev_camera is None else camera_spec("prev_camera", prev_camera)
        prev_tf = None
        if prev_transforms is not None:
            prev_tf = transforms_spec("prev_transforms", prev_transforms)
        flow_min = number("flow_min", flow_min, lo=0.0, hint="a flow length in pixels")
        flow_max = number(
            "flow_max",
            flow_max,
            lo=flow_min,
            lo_open=True,
            hint=f"D reaches 0 at flow_max pixels; it must exceed flow_min = {flow_min:g}",
        )
        user = None
        if detail == "map":
            if detail_map is None:
                raise ValueError("detail_map: detail='map' needs a 2D array (or grey image) of D")
            if detail_mode == "vertex":
                raise ValueError(
                    "detail_mode: a user-supplied detail_map is per pixel; use detail_mode='pixel'"
                )
            user = unit_map("detail_map", detail_map)
        if not (
            shape is None
            or (isinstance(shape, str) and shape in SHAPES)
            or isinstance(shape, AbstractedNormals)
            or (callable(shape) and not isinstance(shape, str))
        ):
            raise ValueError(
                f"shape: expected None, one of {sorted(SHAPES)}, an AbstractedNormals "
                f"(abstract_normals(scene, ...)) or a callable mesh -> (N, 3) normals, got {shape!r}"
            )
        weight = weight_spec(shape_weight)
        check_choice("shape_blend", shape_blend, ("vertex", "pixel"))
        if shape is not None and shape_blend == "vertex" and weight.kind in ("texture", "map"):
            raise ValueError(
                "shape_blend: a weight texture or array varies per pixel, so the normals must be "
                "blended per pixel; use shape_blend='pixel'"
            )
        if (
            shape is not None
            and shape_blend == "vertex"
            and weight.kind == "detail"
            and detail in ("map", "none")
        ):
            raise ValueError(
                f"shape_weight: 'detail' with shape_blend='vertex' needs D per vertex, which "
                f"detail={detail!r} does not give; use shape_blend='pixel' or another detail map"
            )
        check_choice("shape_frame", shape_frame, ("pca", "aabb"))
        if (
            isinstance(shape_iterations, bool)
            or not isinstance(shape_iterations, (int, np.integer))
            or not 0 <= shape_iterations <= 10_000
        ):
            raise ValueError(
                f"shape_iterations: expected an integer in [0, 10000], got {shape_iterations!r}; "
                "a few tens of iterations already give a smooth field"
            )
        if shape_objects is not None:
            shape_objects = _object_names(shape_objects)
            if shape is None:
                warn_unused(
                    "shape_objects",
                    list(shape_objects),
                    "shape=None (no shape abstraction)",
                    "choose a shape (e.g. shape='smoothed') or remove shape_objects",
                )
        modulate = _bool("modulate", modulate)
        pyramid = None
        if weight.kind == "texture":
            from refnpr.texture import build_pyramid

            pyramid = build_pyramid(weight.texture.astype(np.float32))
        self._cfg = Config(
            texture=tex,
            detail=DetailParams(
                detail,
                z_min,
                r,
                focus_point,
                s,
                one_sided,
                prev,
                flow_min,
                flow_max,
                user,
                distance,
                prev_tf,
            ),
            detail_mode=detail_mode,
            tone=tone,
            light=int(light),
            shape=shape,
            weight=weight,
            shape_blend=shape_blend,
            shape_frame=shape_frame,
            shape_iterations=int(shape_iterations),
            shape_objects=shape_objects,
            modulate=modulate,
            weight_pyramid=pyramid,
        )
        self._show = show
        self._explicit_camera = prev is not None
        self._explicit_transforms = prev_tf is not None
        self._params = self._summary(
            texture=(
                texture
                if isinstance(texture, (str, dict))
                else str(texture)
                if hasattr(texture, "__fspath__")
                else f"array{tex.shape}"
            ),
            detail=detail,
            detail_mode=detail_mode,
            distance=distance,
            show=show,
            tone=tone,
            light=int(light),
            z_min=z_min,
            r=r,
            focus_point=list(focus_point) if focus_point is not None else None,
            s=s,
            one_sided=one_sided,
            prev_camera=_camera_table(prev) if prev is not None else None,
            prev_transforms=prev_tf.tolist() if prev_tf is not None else None,
            flow_min=flow_min,
            flow_max=flow_max,
            detail_map=f"array{user.shape}" if user is not None else None,
            shape=_shape_label(shape),
            shape_weight=weight.summary,
            shape_blend=shape_blend,
            shape_frame=shape_frame,
            shape_iterations=int(shape_iterations),
            shape_objects=list(shape_objects) if shape_objects is not None else None,
            modulate=modulate,
        )

    def for_frame(self, scene: Any, prev_scene: Any | None) -> XToonStyle:
        """This style for one frame of a sequence (``Style.for_frame``).

        With ``detail="flow"``, what the style was not given explicitly comes from the previous
        frame: ``prev_camera`` is ``prev_scene.camera`` and ``prev_transforms`` are
        ``prev_scene.objects[i].transform``, so each object-space vertex goes through the
        previous transform and camera versus the current ones (the exact per-vertex screen
        motion of sec. 5). On the first frame (``prev_scene`` None) both are the current
        frame's: zero flow. Other detail maps, and a flow style given both, return ``self``.
        """
        p = self._cfg.detail
        if p.kind != "flow" or (self._explicit_camera and self._explicit_transforms):
            return self
        if prev_scene is not None and len(prev_scene.objects) != len(scene.objects):
            raise ValueError(
                f"prev_scene: has {len(prev_scene.objects)} objects but the frame's scene has "
                f"{len(scene.objects)}; the frames of a sequence must show the same objects"
            )
        camera = p.prev_camera
        if not self._explicit_camera:
            camera = scene.camera if prev_scene is None else prev_scene.camera
        transforms = p.prev_transforms
        if not self._explicit_transforms:
            transforms = None
            if prev_scene is not None:
                transforms = np.stack([np.asarray(o.transform, float) for o in prev_scene.objects])
        out = copy.copy(self)
        out._cfg = dataclasses.replace(
            self._cfg,
            detail=dataclasses.replace(p, prev_camera=camera, prev_transforms=transforms),
        )
        out._params = self._summary(
            **{
                **self._params,
                "prev_camera": _camera_table(camera),
                "prev_transforms": None if transforms is None else transforms.tolist(),
            }
        )
        return out

    @staticmethod
    def _summary(**kv: Any) -> dict[str, Any]:
        return {k: v for k, v in kv.items() if v is not None}

    @property
    def texture(self) -> np.ndarray:
        """The resolved 2D toon texture, ``(rows, cols, 4)`` float32 RGBA, rows growing with D."""
        return self._cfg.texture

    def requires(self, scene: Any) -> frozenset[str]:
        return plan(self._cfg, scene).channels

    def vertex_attributes(
        self, scene: Any, *, width: int, height: int, camera: Any = None
    ) -> list[dict[str, np.ndarray]]:
        """Per-mesh vertex attributes this style interpolates (``xtoon_d``, ``xtoon_flow``,
        ``xtoon_normal``; empty in the pure per-pixel modes), for the scene's world meshes.

        ``width`` and ``height`` matter for ``xtoon_flow`` (pixels) only.
        """
        sc = scene if camera is None else scene.with_camera(camera)
        geom = VertexGeometry.of(sc.world_meshes())
        vals = vertex_values(self._cfg, sc, width, height, geom)
        per_mesh = [dict() for _ in geom.meshes]
        for name, v in vals.items():
            for d, part in zip(per_mesh, geom.split(v), strict=True):
                d[name] = part
        return per_mesh

    def prepare_scene(self, scene: Any, *, width: int, height: int, camera: Any = None) -> Any:
        """A copy of ``scene`` whose world meshes carry :meth:`vertex_attributes`, so that the
        rasterizer interpolates them (the paper's vertex-shader outputs) instead of the style.

        Objects get their world meshes with an identity transform. The style checks when
        shading that the carried values match the frame; rebuild after a camera change.
        """
        from refnpr.scenes import SceneObject

        attrs = self.vertex_attributes(scene, width=width, height=height, camera=camera)
        objects = tuple(
            SceneObject(
                obj.world_mesh().with_(attributes={**obj.world_mesh().attributes, **extra}),
                np.eye(4),
                obj.material,
                obj.name,
            )
            for obj, extra in zip(scene.objects, attrs, strict=True)
        )
        return dataclasses.replace(scene, objects=objects)

    def fields(self, ctx: ShadeContext) -> dict[str, np.ndarray]:
        """Per-sample ``tone`` and ``detail`` (nH, nW), ``normal`` (nH, nW, 3) and, where the
        shape weight varies, ``weight``: float32, NaN where no surface is seen."""
        ev = evaluate(self._cfg, ctx, lookup=False)
        out = {}
        for key in ("tone", "detail", "normal", "weight"):
            v = getattr(ev, key)
            if v is None:
                continue
            full = np.full(ev.mask.shape + v.shape[1:], np.nan, dtype=np.float32)
            full[ev.mask] = v
            out[key] = full
        return out

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        # sec. 3: tone, detail and the 2D toon texture lookup in one numba pass over the samples
        return shade_rgba(self._cfg, ctx, self._show)


#: Detail maps that read each optional parameter (the others ignore it).
_USED_BY = {
    "distance": ("depth", "focus"),
    "z_min": ("depth", "focus"),
    "r": ("depth", "focus", "orientation"),
    "focus_point": ("focus",),
    "prev_camera": ("flow",),
    "prev_transforms": ("flow",),
    "detail_map": ("map",),
}


def _without_unused_detail_params(detail: str, **given: Any) -> tuple[Any, ...]:
    """The optional parameters in order, None where the detail map ignores them; each ignored
    one gives a warning (at the caller), as the threshold and halftone styles do, so a sweep over
    detail maps with one shared parameter table keeps working."""
    out = []
    for name, value in given.items():
        users = _USED_BY[name]
        if value is not None and detail not in users:
            want = " or ".join(repr(d) for d in users)
            warn_unused(name, value, f"detail={detail!r}", f"remove {name} or use detail={want}")
            value = None
        out.append(value)
    return tuple(out)


def _object_names(value: Any) -> tuple[str, ...]:
    """``shape_objects`` as a tuple of object names (a list of str)."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise TypeError(
            f"shape_objects: expected a list of object names, got {type(value).__name__} {value!r}"
        )
    if not all(isinstance(o, str) for o in value):
        raise TypeError(f"shape_objects: expected a list of object names (str), got {value!r}")
    return tuple(value)


def _camera_table(cam: Any) -> dict[str, Any]:
    return {
        "eye": cam.eye.tolist(),
        "target": cam.target.tolist(),
        "up": cam.up.tolist(),
        "fov_y": cam.fov_y,
        "near": cam.near,
        "far": cam.far,
    }


def _shape_label(shape: Any) -> str | None:
    if shape is None or isinstance(shape, str):
        return shape
    if isinstance(shape, AbstractedNormals):
        return f"AbstractedNormals({shape.shape})"
    return getattr(shape, "__name__", "callable") if isinstance(shape, Callable) else None
