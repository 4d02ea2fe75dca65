"""Helpers shared by styles: colour assembly and parameter checks (imports formulas only)."""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr.formulas import lighting

from ._names import warn_caller


def rgba_out(ctx: Any, shape: tuple[int, int]) -> np.ndarray:
    """``ctx.rgba_out(shape)`` (``ShadeContext``: a render context's buffer, lent for the
    frame), or a new ``shape + (4,)`` float32 array for a context object without it (a
    stand-in in a test or a user's own code). To be written in full."""
    lend = getattr(ctx, "rgba_out", None)
    if lend is None:
        return np.empty(tuple(shape) + (4,), dtype=np.float32)
    return lend(shape)


__all__ = [
    "lit_rgba",
    "scatter_rgba",
    "rgba_from",
    "check_choice",
    "check_number",
    "check_count",
    "needs_position",
    "specular_field",
    "check_uv_scale",
    "short_repr",
    "warn_unused",
]


def lit_rgba(
    ctx: Any,
    *,
    mode: str,
    specular: bool,
    model: str = "blinn-phong",
    n: int = 1,
    t: float = 0.5,
    ramp: np.ndarray | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Toon or smooth shading of every sample in one numba pass: (nH, nW, 4) float32 RGBA.

    ``mode="smooth"``: Veryovka eq. 1, ``m_a l_a + sum m_d f_d l_i + sum m_s f_s l_i``;
    ``mode="step"``: eq. 2 with both terms through T_n(., t, n) of eq. 4; ``mode="lake"``:
    ``m_a l_a + sum m_d ramp(N.L) l_i`` with ``ramp (K,)`` (Lake et al. 2000, nearest texel).
    f_s is ``model`` (Blinn-Phong or Phong) with each object's shininess (``specular``; needs
    ``position``); point lights need ``position`` too. Colours are clipped to [0, 1], alpha is 1
    where covered (``ctx.mask``) and everything is 0 elsewhere. float64 arithmetic in the
    order of the numpy formulas (``lighting.diffuse``, ``lighting.specular``,
    ``threshold.step_n``), so the result equals theirs up to ``pow``: the kernel's is libm's,
    numpy's may be its SIMD one (AVX-512), which can differ by an ulp in f_s (float64), not in
    the float32 result (see tests/styles/test_shade_kernels.py).

    ``out``, optional: a C-contiguous (nH, nW, 4) float32 (or float64, for tests of the
    arithmetic) array to write into and return, every element overwritten (repeated frames).
    """
    from ._shade_kernels import (
        LIGHT_DIRECTIONAL,
        LIGHT_POINT,
        MODE_LAKE,
        MODE_SMOOTH,
        MODE_STEP,
        shade_lit,
        shade_smooth,
    )

    codes = {"smooth": MODE_SMOOTH, "step": MODE_STEP, "lake": MODE_LAKE}
    check_choice("mode", mode, tuple(codes))
    check_choice("model", model, ("blinn-phong", "phong"))
    gb, scene = ctx.gb, ctx.scene
    cover = gb["tri_id"] if "tri_id" in gb else gb["mesh_id"]
    mesh_id = gb["mesh_id"]
    normal = gb["normal"]
    shape = np.shape(cover)
    points = [light.kind == "point" for light in scene.lights]
    need_pos = specular or any(points)
    position = gb["position"] if need_pos else np.zeros((1, 1, 3), dtype=np.float32)
    for name, arr, want in (
        ("mesh_id", mesh_id, shape),
        ("normal", normal, shape + (3,)),
        ("position", position, shape + (3,) if need_pos else (1, 1, 3)),
    ):
        if np.shape(arr) != want:
            raise ValueError(
                f"G-buffer channel {name!r}: expected shape {want} (the sample grid), got "
                f"{np.shape(arr)}; rasterize every channel at the same size and spp"
            )
    cover, mesh_id = (_ints(a) for a in (cover, mesh_id))
    objs = scene.objects
    if mesh_id.size and int(mesh_id.max()) >= len(objs):
        raise ValueError(
            f"G-buffer channel 'mesh_id': got object index {int(mesh_id.max())} but the scene has "
            f"{len(objs)} objects; shade the G-buffer with the scene it was rasterized from"
        )
    normal, position = (_floats(a) for a in (normal, position))

    def table(attr: str) -> np.ndarray:
        rows = [np.asarray(getattr(o.material, attr), dtype=np.float64) for o in objs]
        arr = np.array(rows, dtype=np.float64).reshape(len(objs), -1)
        if arr.shape[1] != (1 if attr == "shininess" else 3):
            raise ValueError(f"material {attr}: expected an RGB triple per object, got {arr.shape}")
        return np.ascontiguousarray(arr)

    m_ambient = np.ascontiguousarray(table("ambient") * np.asarray(scene.ambient, float))
    kinds, vecs, colors = [], [], []
    for light, point in zip(scene.lights, points, strict=True):
        colors.append(np.asarray(light.color, dtype=np.float64))
        if point:
            kinds.append(LIGHT_POINT)
            vecs.append(np.asarray(light.position, dtype=np.float64))
        else:  # exactly as ShadeContext.light_dirs
            d = np.asarray(light.direction, dtype=np.float64)
            kinds.append(LIGHT_DIRECTIONAL)
            vecs.append(d / np.linalg.norm(d))
    n_lights = len(kinds)
    shininess = table("shininess").reshape(-1)
    edges = _step_edges(shininess, n, t) if mode == "step" and specular else None
    edge_lo, edge_hi, tones = edges or (np.zeros((1, 0)), np.zeros((1, 0)), np.zeros(1))
    if out is None:
        out = rgba_out(ctx, shape)  # written in full by the kernel
    elif (
        not isinstance(out, np.ndarray)
        or out.shape != shape + (4,)
        or out.dtype not in (np.float32, np.float64)
        or not out.flags.c_contiguous
        or not out.flags.writeable
    ):
        raise ValueError(
            f"out: expected a writable C-contiguous {shape + (4,)} float32 array, got "
            f"{type(out).__name__} {getattr(out, 'shape', '')} {getattr(out, 'dtype', '')}; "
            "pass None for a new one"
        )
    m_specular = table("specular")
    light_color = np.array(colors, dtype=np.float64).reshape(n_lights, 3)
    # the objects and lights with a specular colour (m_s and l_i both nonzero in a channel):
    # elsewhere the kernels skip the specular term, whose value is a signed zero there
    spec_on = np.ascontiguousarray(
        np.any((m_specular[:, None, :] != 0.0) & (light_color[None, :, :] != 0.0), axis=2)
    )
    if mode == "smooth":
        # f_s = base ** shininess by multiplications where the shininess is a small integer,
        # checked against pow's float32 result in the kernel (a float64 ``out``: pow itself)
        p = shininess
        whole = (p == np.floor(p)) & (p >= 1) & (p <= _POW_INT_MAX)
        pow_int = np.where(whole, p, 0).astype(np.int64)
        terms = (m_ambient, table("diffuse"), m_specular, light_color)
        if not specular or out.dtype != np.float32 or any(np.any(a < 0) for a in terms):
            pow_int[:] = 0
        spec_mag = 1.01 * np.abs(m_specular[:, None, :] * light_color[None, :, :]).sum(axis=2)
        shade_smooth(
            cover,
            mesh_id,
            normal,
            position,
            m_ambient,
            table("diffuse"),
            m_specular,
            shininess,
            pow_int,
            np.ascontiguousarray(spec_mag),
            spec_on,
            np.array(kinds, dtype=np.int64),
            np.array(vecs, dtype=np.float64).reshape(n_lights, 3),
            light_color,
            np.ascontiguousarray(np.asarray(scene.camera.eye, dtype=np.float64)),
            bool(specular),
            model == "phong",
            out,
        )
        return out
    shade_lit(
        cover,
        mesh_id,
        normal,
        position,
        m_ambient,
        table("diffuse"),
        m_specular,
        shininess,
        spec_on,
        np.array(kinds, dtype=np.int64),
        np.array(vecs, dtype=np.float64).reshape(n_lights, 3),
        light_color,
        np.ascontiguousarray(np.asarray(scene.camera.eye, dtype=np.float64)),
        codes[mode],
        int(n),
        float(t),
        np.ascontiguousarray(np.zeros(1) if ramp is None else ramp, dtype=np.float64),
        bool(specular),
        model == "phong",
        edge_lo,
        edge_hi,
        tones,
        out,
    )
    return out


#: Largest integer shininess whose f_s the kernel computes by multiplications (then checked).
_POW_INT_MAX = 1024
#: Relative widening of the breakpoints of T_n in base space (see ``_step_edges``).
_EDGE_MARGIN = 1e-7
#: Below this shininess the widening is too small against pow's rounding: always pow.
_EDGE_MIN_SHININESS = 1e-4


def _step_edges(
    shininess: np.ndarray, n: int, t: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where T_n(base ** p, t, n) (eq. 4 of a specular term) is known without pow.

    T_n (``threshold.step_n``) is a monotone step function of f_s whose steps lie at the
    breakpoints c = k / n and (k + t) / n; in float64 it is constant on each open interval
    between them up to a few ulps from its ends. With b_j = c_j ** (1 / p), a base in
    [b_{j-1} (1 + m), b_j (1 - m)] (m = 1e-7) has pow(base, p) inside (c_{j-1}, c_j) at a
    relative distance of about p m >= 1e-11 from both ends (pow is accurate to an ulp), so its
    tone is T_n of the interval's midpoint, ``tones[j]``. ``tones[j] = -1`` marks the intervals
    where pow must be evaluated: the first one when t = 0 (T_n jumps at f_s = 0 and pow may
    underflow to 0 there) and the last one (f_s above every breakpoint); objects with
    shininess < 1e-4, or whose widened edges overlap or underflow, evaluate pow everywhere.

    Returns ``edge_lo (O, B)``, ``edge_hi (O, B)``, ``tones (B + 1,)``, float64.
    """
    from refnpr.formulas.threshold import step_n

    k = np.arange(n + 2, dtype=np.float64)
    c = np.unique(np.concatenate([k / n, (k[: n + 1] + t) / n]))
    mid = np.concatenate([[-1.0], (c[:-1] + c[1:]) / 2, [2.0]])
    tones = step_n(mid, t, n).astype(np.float64)
    tones[0] = tones[-1] = -1.0  # below 0 (unreachable), above every breakpoint
    if t == 0.0:
        tones[1] = -1.0
    p = np.asarray(shininess, dtype=np.float64)[:, None]
    with np.errstate(divide="ignore", over="ignore"):
        b = c[None, :] ** (1.0 / p)
    edge_lo = b * (1.0 - _EDGE_MARGIN)
    edge_hi = b * (1.0 + _EDGE_MARGIN)
    # pow everywhere for a tiny shininess, or where the widened edges overlap or underflow
    # (b_j = 0 for j >= 1 when c_j ** (1 / p) is below the smallest float)
    always = (p[:, 0] < _EDGE_MIN_SHININESS) | ~np.all(edge_hi[:, :-1] < edge_lo[:, 1:], axis=1)
    edge_lo[always] = -np.inf
    edge_hi[always] = np.inf
    return np.ascontiguousarray(edge_lo), np.ascontiguousarray(edge_hi), tones


def _ints(arr: Any) -> np.ndarray:
    arr = np.asarray(arr)
    if arr.dtype not in (np.int32, np.int64):
        arr = arr.astype(np.int64)
    return np.ascontiguousarray(arr)


def _floats(arr: Any) -> np.ndarray:
    arr = np.asarray(arr)
    if arr.dtype not in (np.float32, np.float64):
        arr = arr.astype(np.float64)
    return np.ascontiguousarray(arr)


def scatter_rgba(rgb: np.ndarray, mask: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """(nH, nW, 4) float32 straight-alpha RGBA from colours ``rgb (K, 3)`` of the K samples where
    ``mask`` is true (alpha 1 there, or ``alpha (K,)``); zero elsewhere."""
    out = np.zeros(mask.shape + (4,), dtype=np.float32)
    out[mask, :3] = np.clip(rgb, 0.0, 1.0)
    out[mask, 3] = 1.0 if alpha is None else np.clip(alpha, 0.0, 1.0)
    return out


def rgba_from(rgb: np.ndarray, mask: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """(nH, nW, 4) float32 straight-alpha RGBA: ``rgb`` where ``mask``, alpha = mask (or ``alpha``)."""
    out = np.zeros(mask.shape + (4,), dtype=np.float32)
    rgb = np.broadcast_to(np.asarray(rgb, dtype=np.float64), mask.shape + (3,))
    out[..., :3] = np.where(mask[..., None], np.clip(rgb, 0.0, 1.0), 0.0)
    a = mask.astype(np.float64) if alpha is None else np.where(mask, np.clip(alpha, 0.0, 1.0), 0.0)
    out[..., 3] = a
    return out


def check_choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise ValueError(f"{name}: expected one of {list(choices)}, got {value!r}")
    return value


def check_number(
    name: str,
    value: Any,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__} {value!r}")
    v = float(value)
    if not np.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, got {v}")
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{name}: expected a value {'>' if lo_open else '>='} {lo}, got {v}")
    if hi is not None and v > hi:
        raise ValueError(f"{name}: expected a value <= {hi}, got {v}")
    return v


def check_count(name: str, value: Any, *, lo: int = 1, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if value < lo or (hi is not None and value > hi):
        raise ValueError(
            f"{name}: expected an integer in [{lo}, {hi if hi else 'inf'}], got {value}"
        )
    return int(value)


def needs_position(scene: Any, view_dependent: bool) -> bool:
    """Whether shading needs world positions: for the view vector or for point lights."""
    return view_dependent or any(light.kind == "point" for light in scene.lights)


def specular_field(
    ctx: Any,
    n: np.ndarray,
    light_dir: np.ndarray,
    v: np.ndarray,
    model: str = "blinn-phong",
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """f_s of Veryovka eq. 1 with each object's own shininess (needs ``mesh_id``).

    Evaluated once per distinct exponent; (nH, nW) float64, 0 where empty or shininess <= 0.
    With ``mask``, ``n``, ``v`` (and a per-sample ``light_dir``) hold only the K masked samples
    and the result is (K,).
    """
    shininess = ctx.material_field("shininess", mask)
    out = np.zeros(n.shape[:-1])
    for p in np.unique(shininess[shininess > 0]):
        sel = shininess == p
        ld = light_dir[sel] if np.ndim(light_dir) > 1 else light_dir
        out[sel] = lighting.specular(
            n[sel], ld, v[sel], shininess=float(p), model=model, normalize=False
        )
    return out


#: Range of a style's ``uv_scale`` factors: beyond it the texture LOD (log2 of the scaled uv
#: derivatives) and the lattice coordinates of procedural textures stop being finite or exact.
UV_SCALE_RANGE = (1e-6, 1e6)


def check_uv_scale(name: str, value: Any) -> tuple[float, float] | None:
    """A style's ``uv_scale``: None (each material's own) or a positive number or ``[su, sv]``
    that multiplies uv in place of the material's ``uv_scale``; the same meaning in every style.

    Each factor must lie in ``UV_SCALE_RANGE`` (1e-6 to 1e6), where the scaled texture
    coordinates, their derivatives and the LOD stay finite.
    """
    if value is None:
        return None
    v = [value, value] if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    try:
        arr = np.array(v, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        arr = np.array([np.nan])
    if arr.shape != (2,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(
            f"{name}: expected a positive number or two ([su, sv]) multiplying uv, got "
            f"{short_repr(value)}"
        )
    lo, hi = UV_SCALE_RANGE
    if np.any(arr < lo) or np.any(arr > hi):
        raise ValueError(
            f"{name}: expected factors in [{lo:g}, {hi:g}] (beyond them the texture LOD is no "
            f"longer finite), got {short_repr(value)}; use a factor in that range"
        )
    return (float(arr[0]), float(arr[1]))


def short_repr(value: Any, limit: int = 80) -> str:
    """``repr(value)``, cut to ``limit`` characters (a huge list stays readable)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 5] + " ...]"


def warn_unused(name: str, value: Any, mode: str, fix: str) -> None:
    """``UserWarning``: parameter ``name`` (``value``, not its default) is ignored by ``mode``;
    attributed to the first caller outside refnpr."""
    warn_caller(f"{name}: {short_repr(value)} is ignored with {mode}; {fix}", UserWarning)
