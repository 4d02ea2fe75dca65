"""X-Toon shading of a whole frame in one numba pass (``_kernels.shade_xtoon``): from the G-buffer
alone where :func:`fused`, else from the tone and D of ``evaluation.evaluate`` (the same
formulas, through their numpy faces)."""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr._jit import frozen

from .._common import keep_all, kept_out, rgba_out
from .._frame import frame_record
from . import _kernels as K
from .detail import style_record
from .evaluation import Config, evaluate, light_of, map_channels

__all__ = ["shade_rgba", "fused"]


def fused(cfg: Config) -> bool:
    """Whether the kernel computes normal, tone and D itself for ``cfg`` (no numpy pass)."""
    p = cfg.p
    kernel_maps = ("depth", "focus", "orientation", "highlight", "none")
    return p.shape is None and p.detail_mode == "pixel" and p.detail in kernel_maps


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
    channels: tuple[str, ...] = ()
    if fused(cfg):  # the grids the kernel reads
        point = light_of(cfg, scene).kind == "point"
        channels = ("normal", *sorted(map_channels(cfg.p) | ({"position"} if point else set())))
    frame = frame_record(ctx, channels)
    shape = frame.mesh_id.shape
    style = style_record(cfg.p, cfg.texture, scene, scene.camera)
    # the texture's float32 values as float64 (exact: the kernel's loads need no conversion)
    tex = np.ascontiguousarray(cfg.texture, dtype=np.float64).reshape(-1)
    if fused(cfg):
        tables = frozen(K.Tables(tex, False, np.zeros(1, dtype=np.int64), np.zeros(1), np.zeros(1)))
    else:
        ev = evaluate(cfg, ctx)
        offsets = np.zeros(shape[0] + 1, dtype=np.int64)
        np.cumsum(np.count_nonzero(ev.mask, axis=1), out=offsets[1:])
        given = (np.ascontiguousarray(a, dtype=np.float64) for a in (ev.tone, ev.detail))
        tables = frozen(K.Tables(tex, True, offsets, *given))
    out = rgba_out(ctx, shape)  # written in full by the kernel
    bad = np.zeros(shape[0], dtype=np.uint8)
    kept = kept_out(ctx, shape, 2)
    K.shade_xtoon(frame, style, tables, out, bad, kept)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"tone/detail: NaN at a covered sample of row {row}; the G-buffer normals, depths "
            "or positions there are not finite (mask them first)"
        )
    keep_all(ctx, kept, ("tone", "detail"))
    return out
