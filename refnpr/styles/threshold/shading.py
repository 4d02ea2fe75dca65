"""The ``threshold`` style's shading of a frame: the frame record, the style record (the declared
parameters and the frame constants) and the :class:`._kernels.Tables` that
:func:`._kernels.shade_threshold_for` reads, and its call. Image thresholds, the line noise and
the bump-mapped normals are host tables; the procedural lines and dots and every formula of the
shading are evaluated in the kernel.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from refnpr._jit import frozen
from refnpr.formulas import threshold as thr
from refnpr.formulas.threshold.stipple import NO_TABLE, seed_bits

from .._common import keep_all, kept_out, rgba_out
from .._frame import frame_record
from . import _kernels as K
from .images import grid_offsets
from .noise import value_noise
from .params import PARAMS

__all__ = ["shade_rgba", "uv_scale_table"]


def uv_scale_table(style: Any, scene: Any) -> np.ndarray:
    """Per object ``[su, sv]`` multiplying uv: the style's ``uv_scale`` or the material's,
    times the deprecated ``scale``, ``(O, 2)`` float64."""
    p = style.p
    rows = [p.uv_scale if p.uv_scale is not None else o.material.uv_scale for o in scene.objects]
    uvs = np.array(rows, dtype=np.float64).reshape(len(scene.objects), 2)
    uvs = uvs if style.scale is None else uvs * style.scale
    return np.ascontiguousarray(uvs, dtype=np.float64)


def _channels(style: Any, ctx: Any) -> tuple[str, ...]:
    """The G-buffer grids the kernel reads."""
    p, gb = style.p, ctx.gb
    out = ["normal"]
    points = any(light.kind == "point" for light in ctx.scene.lights)
    if p.specular or p.facing_fade > 0.0 or points:
        out.append("position")
    if p.source == "stipple":
        out += ["uv", "duv_dx", "duv_dy"]
    elif p.source == "lines":
        out.append("uv")
        if "duv_dx" in gb and "duv_dy" in gb:
            out += ["duv_dx", "duv_dy"]
        if style._channel_scale() and "dyadic_scale" in gb:
            out.append("dyadic_scale")
    return tuple(out)


def shade_rgba(style: Any, ctx: Any) -> np.ndarray:
    """(nH, nW, 4) float32 straight-alpha RGBA of ``style`` (a ``ThresholdStyle``) at ``ctx``.

    Raises ValueError for a G-buffer whose ``mesh_id`` names no object of the scene.
    """
    p = style.p
    gb, scene = ctx.gb, ctx.scene
    frame = frame_record(ctx, _channels(style, ctx))
    mask = ctx.mask
    n_obj = len(scene.objects)
    row_start = np.zeros(mask.shape[0], dtype=np.int64)
    np.cumsum(np.count_nonzero(mask, axis=1)[:-1], out=row_start[1:])
    normals = np.zeros((0, 3))
    if style._bump is not None:  # Fig. 2: the bump-mapped normals of the covered samples
        fp = style.footprint(ctx, mask)
        n, dpdx, dpdy = (gb[c][mask].astype(np.float64) for c in ("normal", *_DP))
        normals = np.ascontiguousarray(style._bump.normals(n, fp.uv, fp.gx, fp.gy, dpdx, dpdy))
    # eq. 2's specular sum adds exactly 0 for an object with m_s = 0 (finite lights): skip f_s
    m_s = frame.materials.specular
    finite = bool(np.all(np.isfinite(frame.lights.color)))
    spec_on = np.any(m_s != 0.0, axis=1) | ~np.all(np.isfinite(m_s), axis=1) | (not finite)
    # ---- the thresholds' tables
    t_tab, w_tab = np.zeros((1, 1)), np.zeros((1, 0))
    offsets = np.zeros((1, 2))
    noise = np.zeros(0)
    uv_scale = np.ones((n_obj, 2))
    log2_sv = np.zeros(n_obj)
    dirs: tuple[float, ...] = ()
    channel = np.zeros(0, dtype=np.bool_)
    lam, levels = np.zeros(1), np.zeros((1, 1))
    cdf = NO_TABLE
    has_grad = False
    k = int(round(p.samples**0.5)) if p.filter == "pcf" else 1
    if p.source == "lines":
        src = K.ANALYTIC if p.filter == "analytic" else K.LINES
        has_grad = "duv_dx" in gb and "duv_dy" in gb
        uv_scale = uv_scale_table(style, scene)
        has_channel = style._channel_scale() and "dyadic_scale" in gb
        if has_channel:
            log2_sv = np.log2(uv_scale[:, 1])  # eq. 5 with the object's v scale
        dirs = p.directions
        channel = np.array([d == 0.0 and has_channel for d in dirs], dtype=np.bool_)
        offsets = grid_offsets(k) / gb.n
        if p.noise != 0.0:  # sec. 3.2: phase noise in line periods
            fp = style.footprint(ctx, mask)
            noise = p.noise * value_noise(fp.uv * p.noise_scale, seed=p.noise_seed)
        if len(dirs) > 1:
            lam, levels = thr.layer_schedule(
                p.onsets if p.onsets is not None else (1.0,) * len(dirs)
            )
    elif p.source == "stipple":
        src = K.STIPPLE
        uv_scale = uv_scale_table(style, scene)
        offsets = grid_offsets(k) / gb.n if p.filter == "pcf" else np.zeros((0, 2))
        if p.uniform:
            cdf = style.stipple_tone_table().cdf
    elif p.source == "image":
        src = K.IMAGE
        t_tab, w = style.image_thresholds(ctx, mask)
        w_tab = w_tab if w is None else w
    else:
        src = K.CONSTANT
    angles = [float(np.radians(d)) for d in dirs]  # as hatch_coordinate takes them
    tables = frozen(
        K.Tables(
            row_start=row_start,
            normals=normals,
            t=np.ascontiguousarray(t_tab, dtype=np.float64),
            w=np.ascontiguousarray(w_tab, dtype=np.float64),
            offsets=np.ascontiguousarray(offsets, dtype=np.float64),
            noise=np.ascontiguousarray(noise, dtype=np.float64),
            uv_scale=uv_scale,
            log2_sv=np.ascontiguousarray(log2_sv, dtype=np.float64),
            sin=np.array([math.sin(a) for a in angles], dtype=np.float64),
            cos=np.array([math.cos(a) for a in angles], dtype=np.float64),
            channel=channel,
            lam=np.ascontiguousarray(lam, dtype=np.float64),
            levels=np.ascontiguousarray(levels, dtype=np.float64),
            cdf=np.ascontiguousarray(cdf, dtype=np.float64),
            spec_on=np.ascontiguousarray(spec_on),
        )
    )
    record = PARAMS.record(
        p,
        dark=float(p.tone_fade[0]),
        bright=float(p.tone_fade[1]),
        spec_t=-1.0 if isinstance(p.specular_threshold, str) else float(p.specular_threshold),
        log2_w=float(np.log2(np.float64(p.period))),
        seed=seed_bits(p.noise_seed),
        n_sub=float(gb.n),
        has_grad=bool(has_grad),
    )
    out = rgba_out(ctx, mask.shape)  # written in full by the kernel
    filtered = tables.t.shape[1] > 1 or tables.w.shape[1] > 0 or tables.offsets.shape[0] > 1
    kept = kept_out(ctx, mask.shape, 2)
    kernel = K.shade_threshold_for(src, len(dirs) > 1, bool(filtered))
    kernel(frame, record, tables, out, kept)
    keep_all(ctx, kept, ("tone", "threshold"))
    return out


_DP = ("dposition_dx", "dposition_dy")
