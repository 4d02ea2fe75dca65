"""``halftone`` shading of a whole frame: one numba pass per object in view
(``_kernels.shade_object_for``), after one pass over the empty samples (``_kernels.prepare``).

The kernels read the frame record (:func:`refnpr.styles._frame.frame_record`), the style record
(:func:`style_record`, from the declaration :data:`refnpr.styles.halftone.params.PARAMS`) and each object's
:class:`~._kernels.Tables` (:func:`object_tables`: its screen, normal map, tone LUTs, indication
map and numbers).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from refnpr._jit import frozen
from refnpr.image import srgb_to_linear

from .._common import needs_position, rgba_from, rgba_out
from .._declare import warn_unused
from .._frame import frame_record
from . import _kernels as K
from .params import PARAMS

__all__ = ["style_record", "object_tables", "channels", "shade_rgba"]

_NO_LUTS = (np.zeros((1, 2)), np.linspace(0.0, 1.0, 2))
_NO_MAP = np.zeros((1, 1))
#: A one-texel normal map (the flat normal), where a screen has none (never sampled).
_NO_NORMALS = (np.full((1, 3), 0.5, np.float32), np.zeros(1, np.int64), np.ones((1, 2), np.int64))


def style_record(p: Any, n_axis: int) -> Any:
    """The style record of a frame with ``n_axis`` x ``n_axis`` samples per pixel: the
    declared values ``p`` and the frame's ``slope`` (c; 4 where c is "auto"), ``fwidth`` (c is
    "auto": the slope per sample), ``lod_offset`` (lod_bias, minus log2 n with sample_lod),
    ``step`` (one sample step, 1 / n pixel) and the ink and paper colours."""
    auto = p.c == "auto"
    return PARAMS.record(
        p,
        slope=4.0 if auto else float(p.c),
        fwidth=auto and p.threshold == "smooth",
        lod_offset=p.lod_bias - (math.log2(n_axis) if p.sample_lod else 0.0),
        step=1.0 / n_axis,
        ink_rgb=tuple(p.ink),
        paper_rgb=tuple(p.paper),
    )


def object_tables(style: Any, index: int, obj: Any, screen: Any) -> K.Tables:
    """The :class:`~._kernels.Tables` of scene object ``obj`` (its ``index``) with its built
    ``screen``, for the ``HalftoneStyle`` ``style``."""
    p = style.p
    settings = style.objects.get(obj.name, {})
    scale = settings.get("uv_scale") or style.uv_scale or obj.material.uv_scale
    equalize = p.tone_correct and screen.kind != "strokes"
    luts, lut_x = _NO_LUTS
    if equalize:
        luts = np.ascontiguousarray(style._luts(screen), dtype=np.float64)
        lut_x = np.linspace(0.0, 1.0, luts.shape[1])
    normals = _NO_NORMALS if screen.normals is None else screen.normals.packed()
    imap = settings.get("indication", style.indication)
    direction = screen.direction
    values = K.ObjectValues(
        index=int(index),
        scale=(float(scale[0]), float(scale[1])),
        engraving=direction is not None,
        direction=(0.0, 0.0) if direction is None else (float(direction[0]), float(direction[1])),
        anisotropy=int(p.anisotropy if direction is None else 1),  # engraving: a 1D ramp
        indicated=imap is not None,
        indication_scale=tuple(float(s) for s in settings.get("indication_scale") or (1.0, 1.0)),
        per_level=bool(p.mip == "per_level" or equalize),
        equalize=bool(equalize),
    )
    imap = _NO_MAP if imap is None else np.ascontiguousarray(imap, dtype=np.float64)
    return frozen(K.Tables(screen.pyramid.packed(), normals, luts, lut_x, imap, values))


def channels(style: Any, scene: Any) -> tuple[str, ...]:
    """The G-buffer grids the kernels read for ``scene``."""
    names = ("normal", "uv", "duv_dx", "duv_dy")
    if needs_position(scene, style.p.specular):
        names += ("position",)
    if style.uses_normal_maps(scene):
        names += ("dposition_dx", "dposition_dy")
    return names


def shade_rgba(style: Any, ctx: Any) -> np.ndarray:
    """Per-sample straight-alpha RGBA ``(nH, nW, 4)`` float32 of the ``HalftoneStyle``
    ``style`` for one frame (``ctx``: ``ShadeContext``)."""
    scene = ctx.scene
    p = style.p
    specs = style.object_specs(scene)
    frame = frame_record(ctx, channels(style, scene))
    shape = frame.mesh_id.shape
    record = style_record(p, int(ctx.gb.n))
    out = rgba_out(ctx, shape)  # written in full: prepare, then every object in view
    color = p.show == "color"
    keep = getattr(ctx, "wants_intermediates", False)
    # a (0, 0, 3) stand-in: the kernel writes raw where its rows are the grid's (even one row)
    raw = np.zeros((0, 0, 3)) if color and not keep else np.ones(shape + (3,))
    one = p.paper if color else (1.0, 1.0, 1.0)  # the value 1 off objects
    rows = np.empty((shape[0], max(len(scene.objects), 1)), dtype=np.int64)
    K.prepare(frame, np.asarray(one, dtype=np.float64), rows, out)
    present = rows.sum(axis=0)[: len(scene.objects)] > 0
    # each object in view: its screen and tables, built once for every pass below
    screens = [
        (i, obj, style.screen_for(specs[i], obj.material.texture))
        for i, obj in enumerate(scene.objects)
        if present[i]
    ]
    objects = [(sc, object_tables(style, i, obj, sc)) for i, obj, sc in screens]
    _warn_unread(style, [tables.values for _, tables in objects])
    _shade_objects(objects, frame, record, p.show, out, raw)
    if keep:  # the raw views, as show draws them (the color pass kept them in raw)
        covered = frame.cover >= 0
        for ch, (name, show) in enumerate((("intensity", "intensity"), ("threshold", "screen"))):
            if color:
                values = raw[..., ch]
            else:
                values = np.ones(shape + (3,))
                none = np.empty((0, 0, 4), np.float32)
                _shade_objects(objects, frame, record, show, none, values)
                values = values[..., 0]
            ctx.keep(name, np.where(covered, values, 0.0))
    if not color:  # an 8-bit file of the image stores the raw values
        return rgba_from(srgb_to_linear(raw), frame.cover >= 0)
    return out


def _warn_unread(style: Any, values: list) -> None:
    """Warn (once per style) where no object in view reads ``tone_correct`` or ``anisotropy``
    (``values``: their :class:`~._kernels.ObjectValues`, as :func:`object_tables` resolved them:
    stroke maps are not equalized, engraving ramps are isotropic): the parameter changes
    nothing."""
    p = style.p
    if not values or getattr(style, "_warned_unread", False):
        return
    if p.tone_correct and not any(v.equalize for v in values):
        warn_unused("tone_correct", True, "stroke-map screens only in view",
                    "remove tone_correct, or give an engraving or dither screen")  # fmt: skip
        style._warned_unread = True
    if p.anisotropy > 1 and all(v.anisotropy == 1 for v in values):
        warn_unused("anisotropy", p.anisotropy, "engraving screens only in view (a 1D ramp)",
                    "remove anisotropy, or give a dither or stroke-map screen")  # fmt: skip
        style._warned_unread = True


def _shade_objects(
    objects: list, frame: Any, record: Any, show: str, out: np.ndarray, raw: np.ndarray
) -> None:
    """Run the object kernel for ``show`` over ``objects`` (``(screen, Tables)`` of each object
    in view), into ``out`` (``show`` color) or ``raw``."""
    for screen, tables in objects:
        kernel = K.shade_object_for(
            PARAMS.code("show", show),
            screen.normals is not None,
            bool(record.fwidth),
            bool(tables.values.per_level),
        )
        kernel(frame, record, tables, out, raw)
