"""The ``threshold`` style's one-pass shading: inputs of :func:`._kernels.shade_threshold_for`.

:func:`shade_fast` gathers the frame's tables (materials, lights, uv scales per object, the
hatching layers and their schedule) and runs the numba kernel over the whole sample grid. The
procedural lines of sec. 3.2 (point-sampled, PCF and the analytic box filter of sec. 4) and the
stipple dots (Fig. 4) are evaluated inside the kernel; image thresholds are sampled from their
pyramids by :func:`.images.image_thresholds` (the texture samplers) into a table that the
kernel thresholds. ``ThresholdStyle._shade_numpy`` (the whole-array numpy path) is the tests' oracle.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from refnpr.formulas import threshold

from .._common import rgba_out
from .sources import _noise, grid_offsets

__all__ = ["shade_fast"]

_DUMMY3 = np.zeros((1, 1, 3), dtype=np.float32)
_DUMMY2 = np.zeros((1, 1, 2), dtype=np.float32)
_DUMMY1 = np.zeros((1, 1), dtype=np.float32)


def _unit(d: np.ndarray) -> np.ndarray:
    """``refnpr.formulas._shading_checks.unit_vectors`` of one (3,) vector."""
    m = np.max(np.abs(d), axis=-1, keepdims=True)
    w = d / np.where(m > 0, m, 1)
    length = np.sqrt(np.sum(w * w, axis=-1, keepdims=True))
    return w / np.where(length > 0, length, 1)


def _table(scene: Any, attr: str, width: int) -> np.ndarray:
    rows = [np.asarray(getattr(o.material, attr), dtype=np.float64) for o in scene.objects]
    arr = np.array(rows, dtype=np.float64).reshape(len(scene.objects), -1)
    if arr.shape[1] != width:
        raise ValueError(
            f"material {attr}: expected {width} value(s) per object, got shape {arr.shape}"
        )
    return np.ascontiguousarray(arr)


def _ints(a: np.ndarray) -> np.ndarray:
    return a if a.dtype.kind == "i" else a.astype(np.int64)


def _floats(a: np.ndarray) -> np.ndarray:
    a = a if a.dtype in (np.float32, np.float64) else a.astype(np.float64)
    return np.ascontiguousarray(a)


def _uv_scale_table(style: Any, scene: Any) -> np.ndarray:
    """Per object ``[su, sv]``, as ``ThresholdStyle.uv_scales`` gives per sample."""
    p = style.p
    n_obj = len(scene.objects)
    if p.uv_scale is None:
        uvs = _table(scene, "uv_scale", 2)
    else:
        uvs = np.broadcast_to(np.asarray(p.uv_scale, dtype=np.float64), (n_obj, 2))
    uvs = uvs if p.scale is None else uvs * p.scale
    return np.ascontiguousarray(uvs, dtype=np.float64)


def shade_fast(style: Any, ctx: Any) -> np.ndarray:
    """(nH, nW, 4) float32 straight-alpha RGBA of ``style`` (a ``ThresholdStyle``) at ``ctx``.

    The same image as ``style._shade_numpy(ctx)`` (float64 arithmetic in the same order; see
    ``tests/styles/test_threshold_kernels.py`` for the cases compared), for every parameter
    combination. Raises ValueError for a G-buffer whose ``mesh_id`` names no object.
    """
    from ._kernels import (
        LIGHT_DIRECTIONAL,
        LIGHT_POINT,
        SRC_ANALYTIC,
        SRC_CONST,
        SRC_LINES,
        SRC_STIPPLE,
        SRC_TABLE,
        shade_threshold_for,
    )

    p = style.p
    gb, scene = ctx.gb, ctx.scene
    mask = ctx.mask
    cover = _ints(gb["tri_id"] if "tri_id" in gb else gb["mesh_id"])
    mesh_id = _ints(gb["mesh_id"])
    shape = mask.shape
    objs = scene.objects
    if mesh_id.size and int(mesh_id.max()) >= len(objs):
        raise ValueError(
            f"G-buffer channel 'mesh_id': got object index {int(mesh_id.max())} but the scene has "
            f"{len(objs)} objects; shade the G-buffer with the scene it was rasterized from"
        )
    counts = np.count_nonzero(mask, axis=1)
    row_start = np.zeros(shape[0], dtype=np.int64)
    np.cumsum(counts[:-1], out=row_start[1:])
    normal = _floats(gb["normal"])
    normal_tab = np.zeros((0, 3))
    if style._bump is not None:
        n = gb["normal"][mask].astype(np.float64)
        fp = style.footprint(ctx, mask)
        dpdx = gb["dposition_dx"][mask].astype(np.float64)
        dpdy = gb["dposition_dy"][mask].astype(np.float64)
        normal_tab = style._bump.normals(n, fp.uv, fp.gx, fp.gy, dpdx, dpdy)  # Fig. 2
        normal_tab = np.ascontiguousarray(normal_tab, dtype=np.float64)
    points = [light.kind == "point" for light in scene.lights]
    need_pos = p.specular or p.facing_fade > 0.0 or any(points)
    position = _floats(gb["position"]) if need_pos else _DUMMY3
    kinds, vecs, units, colors = [], [], [], []
    for light, point in zip(scene.lights, points, strict=True):
        colors.append(np.asarray(light.color, dtype=np.float64))
        if point:
            kinds.append(LIGHT_POINT)
            vecs.append(np.asarray(light.position, dtype=np.float64))
            units.append(np.zeros(3))
        else:  # exactly as ShadeContext.light_dirs, then lighting.diffuse's normalization
            d = np.asarray(light.direction, dtype=np.float64)
            d = d / np.linalg.norm(d)
            kinds.append(LIGHT_DIRECTIONAL)
            vecs.append(d)
            units.append(_unit(d))
    n_lights = len(kinds)

    def lights(rows: list) -> np.ndarray:
        return np.array(rows, dtype=np.float64).reshape(n_lights, 3)

    m_ambient = _table(scene, "ambient", 3) * np.asarray(scene.ambient, dtype=np.float64)
    m_specular = _table(scene, "specular", 3)
    # eq. 2's specular sum adds exactly 0 for an object with m_s = 0 (finite lights): skip f_s
    finite = bool(np.all(np.isfinite(lights(colors))))
    spec_on = np.any(m_specular != 0.0, axis=1) | ~np.all(np.isfinite(m_specular), axis=1)
    spec_on = np.ascontiguousarray(spec_on | (not finite))
    # ---- thresholds
    t_const = float(p.t)
    t_tab = np.zeros((1, 1))
    w_tab = np.zeros((1, 0))
    uv, dx, dy, dyadic = _DUMMY2, _DUMMY2, _DUMMY2, _DUMMY1
    has_grad = has_channel = False
    uv_scale = np.ones((len(objs), 2))
    log2_sv = np.zeros(len(objs))
    dirs: list[float] = []
    dir_zero = np.zeros(0, dtype=np.bool_)
    offsets = np.zeros((1, 2))
    noise = np.zeros(0)
    lam_bp = np.zeros(1)
    lev_bp = np.zeros((1, 1))
    cdf = np.zeros((0, 0, 0))
    if p.source == "constant":
        src = SRC_CONST
    elif p.source == "lines":
        src = SRC_ANALYTIC if p.filter == "analytic" else SRC_LINES
        uv = _floats(gb["uv"])
        has_grad = "duv_dx" in gb and "duv_dy" in gb
        if has_grad:
            dx, dy = _floats(gb["duv_dx"]), _floats(gb["duv_dy"])
        has_channel = style._channel_scale() and "dyadic_scale" in gb
        uv_scale = _uv_scale_table(style, scene)
        if has_channel:
            dyadic = _floats(gb["dyadic_scale"])
            log2_sv = np.log2(uv_scale[:, 1])  # eq. 5 with the object's v scale
        dirs = [float(np.radians(d)) for d in p.directions]  # as line_layers
        dir_zero = np.asarray([d == 0.0 for d in p.directions], dtype=np.bool_)
        k = 1 if p.filter != "pcf" else int(round(p.samples**0.5))
        offsets = np.ascontiguousarray(grid_offsets(k) / gb.n)
        if p.noise != 0.0:
            noise = _noise(style.footprint(ctx, mask), p)  # sec. 3.2, line periods
        if len(p.directions) > 1:
            lam_bp, lev_bp = threshold.layer_schedule(
                p.onsets if p.onsets is not None else (1.0,) * len(p.directions)
            )
    elif p.source == "stipple":
        src = SRC_STIPPLE
        uv, dx, dy = _floats(gb["uv"]), _floats(gb["duv_dx"]), _floats(gb["duv_dy"])
        uv_scale = _uv_scale_table(style, scene)
        if p.filter == "pcf":
            k = int(round(p.samples**0.5))
            offsets = np.ascontiguousarray(grid_offsets(k) / gb.n)
        else:
            offsets = np.zeros((0, 2))
        if p.uniform:
            if style._tone_table is None:
                style._tone_table = threshold.stipple_tone_table(jitter=p.jitter)
            cdf = style._tone_table.cdf
    else:  # image: the numpy source samples the texture pyramids
        src = SRC_TABLE
        thr = style.thresholder(ctx, mask)
        t_tab = np.ascontiguousarray(thr.t, dtype=np.float64)
        if thr.weights is not None:
            w_tab = np.ascontiguousarray(thr.weights, dtype=np.float64)
    sin = np.array([math.sin(a) for a in dirs], dtype=np.float64)  # as hatch_coordinate
    cos = np.array([math.cos(a) for a in dirs], dtype=np.float64)
    out = rgba_out(ctx, shape)  # written in full by the kernel
    shade_threshold_for(src, len(dirs) > 1)(
        cover,
        mesh_id,
        row_start,
        normal,
        normal_tab,
        position,
        np.ascontiguousarray(m_ambient),
        _table(scene, "diffuse", 3),
        m_specular,
        spec_on,
        _table(scene, "shininess", 1).reshape(-1),
        np.array(kinds, dtype=np.int64),
        lights(vecs),
        lights(units),
        lights(colors),
        np.ascontiguousarray(np.asarray(scene.camera.eye, dtype=np.float64)),
        int(p.n),
        float(p.strength),
        float(p.facing_fade),
        float(p.facing_power),
        float(p.tone_fade[0]),
        float(p.tone_fade[1]),
        bool(p.specular),
        -1.0 if isinstance(p.specular_threshold, str) else float(p.specular_threshold),
        t_const,
        t_tab,
        w_tab,
        uv,
        dx,
        dy,
        dyadic,
        has_grad,
        has_channel,
        uv_scale,
        np.ascontiguousarray(log2_sv, dtype=np.float64),
        sin,
        cos,
        dir_zero,
        float(np.log2(np.float64(p.period))),
        bool(p.multiscale),
        bool(p.uniform),
        offsets,
        np.ascontiguousarray(noise, dtype=np.float64),
        np.ascontiguousarray(lam_bp, dtype=np.float64),
        np.ascontiguousarray(lev_bp, dtype=np.float64),
        float(gb.n),
        np.uint64(p.noise_seed & 0xFFFFFFFF),
        float(p.jitter),
        np.ascontiguousarray(cdf, dtype=np.float64),
        out,
    )
    return out
