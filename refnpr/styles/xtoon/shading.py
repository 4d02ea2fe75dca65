"""X-Toon shading of a whole frame in one numba pass (``_kernels.shade_xtoon``).

Without shape abstraction, with per-pixel detail from the depth, focus, orientation or highlight
map (or none), the kernel computes everything per sample from the G-buffer: normal, tone, D, the
2D toon texture lookup and the RGBA. Otherwise (shape abstraction, per-vertex detail, flow, a
user map) the numpy evaluation (``evaluation.evaluate``) gives tone and D at the covered samples
and the kernel does the lookup and the assembly. Either way the result equals the numpy code's
(``evaluate`` + ``toon_lookup`` + ``rgba_from``) up to libm versus numpy ``log``/``pow`` (an ulp
in float64; see tests/styles/test_xtoon_kernels.py).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._common import rgba_out
from . import _kernels as K
from .detail import resolve_frame
from .evaluation import Config, _light_of, evaluate

__all__ = ["shade_rgba", "fused"]

_SHOW = {
    "color": K.SHOW_COLOR,
    "detail": K.SHOW_DETAIL,
    "inverse_detail": K.SHOW_INVERSE,
    "tone": K.SHOW_TONE,
}
#: Attribute maps the kernel evaluates itself (per pixel, without shape abstraction).
_KERNEL_MAPS = ("depth", "focus", "orientation", "highlight", "none")


def fused(cfg: Config) -> bool:
    """Whether the kernel computes normal, tone and D itself for ``cfg`` (no numpy pass)."""
    return cfg.shape is None and cfg.detail_mode == "pixel" and cfg.detail.kind in _KERNEL_MAPS


def _grid(gb: Any, name: str, shape: tuple[int, ...]) -> np.ndarray:
    arr = np.asarray(gb[name])
    if arr.shape != shape:
        raise ValueError(
            f"G-buffer channel {name!r}: expected shape {shape} (the sample grid), got "
            f"{arr.shape}; rasterize every channel at the same size and spp"
        )
    if arr.dtype not in (np.float32, np.float64):
        arr = arr.astype(np.float64)
    return np.ascontiguousarray(arr)


def _detail_code(cfg: Config, scene: Any) -> tuple[int, np.ndarray]:
    """The kernel's ``detail_kind`` and ``params`` (frame constants after defaults)."""
    p = cfg.detail
    f = resolve_frame(p, scene, scene.camera)
    params = np.zeros(6)
    axis = p.distance == "axis"
    if p.kind == "depth":
        code = K.DETAIL_DEPTH_AXIS if axis else K.DETAIL_DEPTH_EYE
        params[:2] = (f.z_min, np.log(f.r))  # sec. 3.1: D = 1 - log(z / z_min) / log(r)
    elif p.kind == "focus":
        code = K.DETAIL_FOCUS_AXIS if axis else K.DETAIL_FOCUS_EYE
        z_c, z_min, r = f.z_focus, f.z_min, f.r
        params[:5] = (  # as formulas.xtoon.detail_focus: z_min^-+, log(z_max / z_min) per side
            z_c,
            z_c - z_min,
            z_c + z_min,
            np.log((z_c - r * z_min) / (z_c - z_min)),
            np.log((z_c + r * z_min) / (z_c + z_min)),
        )
    elif p.kind == "orientation":
        code = K.DETAIL_ORIENTATION
        params[0] = f.r
    elif p.kind == "highlight":
        code = K.DETAIL_HIGHLIGHT
        params[0] = p.s
    else:
        code = K.DETAIL_NONE
    return code, params


def shade_rgba(cfg: Config, ctx: Any, show: str = "color") -> np.ndarray:
    """Per-sample straight-alpha RGBA of X-Toon for one frame, ``(nH, nW, 4)`` float32.

    Parameters
    ----------
    cfg : Config
        The style's validated configuration.
    ctx : ShadeContext
        G-buffer (channels of ``evaluation.plan``) and scene.
    show : {"color", "detail", "inverse_detail", "tone"}
        The toon texture (alpha from the texture, colour times each object's diffuse colour
        with ``cfg.modulate``), or D, 1 - D or the tone as opaque grey (displayed sRGB value =
        the quantity).
    """
    if show not in _SHOW:
        raise ValueError(f"show: expected one of {list(_SHOW)}, got {show!r}")
    gb, scene = ctx.gb, ctx.scene
    mesh_id = np.asarray(gb["mesh_id"])
    if mesh_id.dtype not in (np.int32, np.int64):
        mesh_id = mesh_id.astype(np.int64)
    mesh_id = np.ascontiguousarray(mesh_id)
    shape = mesh_id.shape
    nh = shape[0]
    objs = scene.objects
    if mesh_id.size and int(mesh_id.max()) >= len(objs):
        raise ValueError(
            f"G-buffer channel 'mesh_id': got object index {int(mesh_id.max())} but the scene has "
            f"{len(objs)} objects; shade the G-buffer with the scene it was rasterized from"
        )
    light = _light_of(cfg, scene)
    point = light.kind == "point"
    vec = light.position if point else light.direction
    light_vec = np.ascontiguousarray(np.asarray(vec, dtype=np.float64))
    eye = np.ascontiguousarray(np.asarray(scene.camera.eye, dtype=np.float64))
    empty3 = np.zeros((1, 1, 3), dtype=np.float32)
    empty2 = np.zeros((1, 1), dtype=np.float32)
    flat = np.zeros(1)
    offsets = np.zeros(1, dtype=np.int64)
    if fused(cfg):
        given = False
        code, params = _detail_code(cfg, scene)
        normal = _grid(gb, "normal", shape + (3,))
        axis_map = code in (K.DETAIL_DEPTH_AXIS, K.DETAIL_FOCUS_AXIS)
        depth = _grid(gb, "depth", shape) if axis_map else empty2
        need_pos = point or code in (
            K.DETAIL_DEPTH_EYE,
            K.DETAIL_FOCUS_EYE,
            K.DETAIL_ORIENTATION,
            K.DETAIL_HIGHLIGHT,
        )
        position = _grid(gb, "position", shape + (3,)) if need_pos else empty3
        tone = detail = flat
    else:
        given = True
        code, params = K.DETAIL_NONE, np.zeros(6)
        normal, depth, position = empty3, empty2, empty3
        ev = evaluate(cfg, ctx, lookup=False)
        tone = np.ascontiguousarray(ev.tone, dtype=np.float64)
        detail = np.ascontiguousarray(ev.detail, dtype=np.float64)
        counts = np.count_nonzero(ev.mask, axis=1)
        offsets = np.zeros(nh + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
    diffuse = np.zeros((1, 3))
    if cfg.modulate:
        diffuse = np.array(
            [np.asarray(o.material.diffuse, dtype=np.float64) for o in objs], dtype=np.float64
        ).reshape(len(objs), 3)
    # the float32 texture's values in float64 (exact) and flat: the kernel's texel loads
    # need no conversion, and index it with unsigned offsets
    tex32 = np.asarray(cfg.texture, dtype=np.float32)
    rows, cols = tex32.shape[:2]
    tex = np.ascontiguousarray(tex32, dtype=np.float64).reshape(-1)
    out = rgba_out(ctx, shape)  # written in full by the kernel
    bad = np.zeros(nh, dtype=np.uint8)
    K.shade_xtoon(
        mesh_id,
        normal,
        depth,
        position,
        given,
        offsets,
        tone,
        detail,
        point,
        light_vec,
        eye,
        cfg.tone == "half_lambert",
        code,
        params,
        bool(cfg.detail.one_sided),
        tex,
        rows,
        cols,
        bool(cfg.modulate),
        np.ascontiguousarray(diffuse),
        _SHOW[show],
        out,
        bad,
    )
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"tone/detail: NaN at a covered sample of row {row}; the G-buffer normals, depths "
            "or positions there are not finite (mask them first)"
        )
    return out
