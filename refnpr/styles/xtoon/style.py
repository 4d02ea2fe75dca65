"""The ``xtoon`` style class (Barla et al. 2006): parameters, channels and per-sample shading; the
package docstring (:mod:`refnpr.styles.xtoon`) describes the technique.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import numpy as np

from .._declare import check_number
from ..base import ShadeContext, Style, register
from .detail import DEFAULT_DISTANCE
from .evaluation import Config, evaluate, plan, vertex_values
from .geometry import VertexGeometry
from .params import PARAMS, SHOWS
from .shading import shade_rgba
from .texture import resolve_texture

__all__ = ["XToonStyle", "SHOWS"]

_R_HINT = "r is the ratio z_max / z_min of X-Toon sec. 3.1 (coarsest detail at z_max = r z_min)"


def _checked(p: Any) -> Any:
    """The checks between parameters; returns ``p`` with the paper's distance filled in."""
    if p.detail in DEFAULT_DISTANCE and p.distance is None:
        p = p.replace(distance=DEFAULT_DISTANCE[p.detail])
    if p.r is not None and p.detail in ("depth", "focus"):
        check_number("r", p.r, lo=1.0, lo_open=True, hint=_R_HINT + "; use r > 1, e.g. 4")
    elif p.r is not None:
        check_number("r", p.r, lo=0.0, hint="the near-silhouette exponent of |n.v|^r is >= 0")
    if p.detail == "focus" and p.focus_point is None:
        raise ValueError("focus_point: detail='focus' needs the focus point [x, y, z]")
    hint = f"D reaches 0 at flow_max pixels; it must exceed flow_min = {p.flow_min:g}"
    check_number("flow_max", p.flow_max, lo=p.flow_min, lo_open=True, hint=hint)
    if p.detail == "map":
        if p.detail_map is None:
            raise ValueError("detail_map: detail='map' needs a 2D array (or grey image) of D")
        if p.detail_mode == "vertex":
            raise ValueError(
                "detail_mode: a user-supplied detail_map is per pixel; use detail_mode='pixel'"
            )
    weight = p.shape_weight
    if p.shape is not None and p.shape_blend == "vertex":
        if weight.kind in ("texture", "map"):
            raise ValueError(
                "shape_blend: a weight texture or array varies per pixel, so the normals must be "
                "blended per pixel; use shape_blend='pixel'"
            )
        if weight.kind == "detail" and p.detail in ("map", "none"):
            raise ValueError(
                f"shape_weight: 'detail' with shape_blend='vertex' needs D per vertex, which "
                f"detail={p.detail!r} does not give; use shape_blend='pixel' or another detail "
                "map"
            )
    return p


@register
class XToonStyle(Style):
    """X-Toon shading (Barla et al. 2006); see the package docstring and ``docs/xtoon.md``.
    Parameters: :data:`refnpr.styles.xtoon.params.PARAMS` (``refnpr styles xtoon``)."""

    name = "xtoon"
    description = (
        "X-Toon: 2D toon texture by tone and detail (depth, focus, orientation, highlight, flow) "
        "with shape abstraction (Barla et al. 2006)"
    )
    PARAMS = PARAMS
    INTERMEDIATES = {
        "tone": "the tone n.l (or half-Lambert) of the lookup's first axis (sec. 3)",
        "detail": "the detail D of the lookup's second axis (secs. 3.1, 3.2)",
    }

    def __init__(self, **params: Any) -> None:
        p = _checked(PARAMS.validate(params))
        tex = resolve_texture(p.texture)
        pyramid = None
        if p.shape_weight.kind == "texture":
            from refnpr.texture import build_pyramid

            pyramid = build_pyramid(p.shape_weight.texture.astype(np.float32))
        self._cfg = Config(p=p, texture=tex, weight_pyramid=pyramid)
        self._params = p.as_dict()
        #: The flow inputs given explicitly (the others come from the previous frame).
        self._explicit = frozenset(
            k for k in ("prev_camera", "prev_transforms") if p[k] is not None
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
        p = self._cfg.p
        if p.detail != "flow" or len(self._explicit) == 2:
            return self
        if prev_scene is not None and len(prev_scene.objects) != len(scene.objects):
            raise ValueError(
                f"prev_scene: has {len(prev_scene.objects)} objects but the frame's scene has "
                f"{len(scene.objects)}; the frames of a sequence must show the same objects"
            )
        camera = p.prev_camera
        if "prev_camera" not in self._explicit:
            camera = scene.camera if prev_scene is None else prev_scene.camera
        transforms = p.prev_transforms
        if "prev_transforms" not in self._explicit:
            transforms = None
            if prev_scene is not None:
                transforms = np.stack([np.asarray(o.transform, float) for o in prev_scene.objects])
        out = copy.copy(self)
        q = p.replace(prev_camera=camera, prev_transforms=transforms)
        out._cfg = dataclasses.replace(self._cfg, p=q)
        out._params = q.as_dict()
        return out

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
        parts = {name: geom.split(v) for name, v in vals.items()}
        return [{name: split[i] for name, split in parts.items()} for i in range(len(geom.meshes))]

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
        ev = evaluate(self._cfg, ctx)
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
        return shade_rgba(self._cfg, ctx)
