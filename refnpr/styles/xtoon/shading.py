"""X-Toon shading of a whole frame in one numba pass (``_kernels.shade_xtoon``).

Without shape abstraction, with per-pixel detail from the depth, focus, orientation or highlight
map (or none), the kernel computes everything per sample from the G-buffer: normal, tone, D, the
2D toon texture lookup and the RGBA. Otherwise (shape abstraction, per-vertex detail, flow, a
user map) ``evaluation.evaluate`` gives tone and D at the covered samples (the same formulas,
through their numpy faces) and the kernel does the lookup and the assembly.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._common import rgba_out
from .._frame import frame_record
from . import _kernels as K
from .detail import style_record, texels
from .evaluation import Config, _light_of, evaluate

__all__ = ["shade_rgba", "fused"]

#: Attribute maps the kernel evaluates itself (per pixel, without shape abstraction).
_KERNEL_MAPS = ("depth", "focus", "orientation", "highlight", "none")


def fused(cfg: Config) -> bool:
    """Whether the kernel computes normal, tone and D itself for ``cfg`` (no numpy pass)."""
    p = cfg.p
    return p.shape is None and p.detail_mode == "pixel" and p.detail in _KERNEL_MAPS


def _channels(cfg: Config, point: bool) -> tuple[str, ...]:
    """The G-buffer grids the kernel reads for ``cfg``."""
    p = cfg.p
    if not fused(cfg):
        return ()
    out = ["normal"]
    if p.detail in ("depth", "focus") and p.distance == "axis":
        out.append("depth")
    eye_maps = ("orientation", "highlight") + (("depth", "focus") if p.distance == "eye" else ())
    if point or p.detail in eye_maps:
        out.append("position")
    return tuple(out)


def shade_rgba(cfg: Config, ctx: Any) -> np.ndarray:
    """Per-sample straight-alpha RGBA of X-Toon for one frame, ``(nH, nW, 4)`` float32.

    Parameters
    ----------
    cfg : Config
        The style's validated configuration; its ``show`` picks the toon texture (alpha from
        the texture, colour times each object's diffuse colour with ``modulate``), or D, 1 - D
        or the tone as opaque grey (displayed sRGB value = the quantity).
    ctx : ShadeContext
        G-buffer (channels of ``evaluation.plan``) and scene.
    """
    scene = ctx.scene
    point = _light_of(cfg, scene).kind == "point"
    frame = frame_record(ctx, _channels(cfg, point))
    shape = frame.mesh_id.shape
    style = style_record(cfg.p, cfg.texture, scene, scene.camera)
    tex = texels(cfg.texture)
    if fused(cfg):
        tables = K.Tables(tex, False, np.zeros(1, dtype=np.int64), np.zeros(1), np.zeros(1))
    else:
        ev = evaluate(cfg, ctx, lookup=False)
        offsets = np.zeros(shape[0] + 1, dtype=np.int64)
        np.cumsum(np.count_nonzero(ev.mask, axis=1), out=offsets[1:])
        tables = K.Tables(
            tex,
            True,
            offsets,
            np.ascontiguousarray(ev.tone, dtype=np.float64),
            np.ascontiguousarray(ev.detail, dtype=np.float64),
        )
    out = rgba_out(ctx, shape)  # written in full by the kernel
    bad = np.zeros(shape[0], dtype=np.uint8)
    K.shade_xtoon(frame, style, tables, out, bad)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"tone/detail: NaN at a covered sample of row {row}; the G-buffer normals, depths "
            "or positions there are not finite (mask them first)"
        )
    return out
