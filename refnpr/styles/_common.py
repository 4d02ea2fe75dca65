"""Helpers shared by styles: colour assembly and parameter checks (imports formulas only)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._declare import short_repr

__all__ = ["rgba_out", "rgba_from", "kept_out", "keep_all", "needs_position", "check_uv_scale"]


def rgba_out(ctx: Any, shape: tuple[int, int]) -> np.ndarray:
    """``ctx.rgba_out(shape)`` (``ShadeContext``: a render context's buffer, lent for the
    frame), or a new ``shape + (4,)`` float32 array for a context object without it (a
    stand-in in a test or a user's own code). To be written in full."""
    lend = getattr(ctx, "rgba_out", None)
    if lend is None:
        return np.empty(tuple(shape) + (4,), dtype=np.float32)
    return lend(shape)


def kept_out(ctx: Any, shape: tuple[int, int], count: int) -> np.ndarray:
    """The buffer a kernel writes ``count`` intermediates per sample into: ``shape + (count,)``
    float64 when ``ctx`` asks for intermediates (``ShadeContext.wants_intermediates``), else a
    ``(0, 0, count)`` stand-in that tells the kernel to skip them."""
    wants = getattr(ctx, "wants_intermediates", False)
    return np.empty(tuple(shape) + (count,) if wants else (0, 0, count))


def keep_all(ctx: Any, kept: np.ndarray, names: tuple[str, ...]) -> None:
    """Hand the kernel's ``kept`` (:func:`kept_out`) to ``ctx.keep`` as one intermediate per
    name (component i: ``names[i]``); nothing for a stand-in."""
    if kept.shape[0]:
        for i, name in enumerate(names):
            ctx.keep(name, kept[..., i])


def rgba_from(rgb: np.ndarray, mask: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """(nH, nW, 4) float32 straight-alpha RGBA: ``rgb`` where ``mask``, alpha = mask (or ``alpha``)."""
    out = np.zeros(mask.shape + (4,), dtype=np.float32)
    rgb = np.broadcast_to(np.asarray(rgb, dtype=np.float64), mask.shape + (3,))
    out[..., :3] = np.where(mask[..., None], np.clip(rgb, 0.0, 1.0), 0.0)
    a = mask.astype(np.float64) if alpha is None else np.where(mask, np.clip(alpha, 0.0, 1.0), 0.0)
    out[..., 3] = a
    return out


def needs_position(scene: Any, view_dependent: bool) -> bool:
    """Whether shading needs world positions: for the view vector or for point lights."""
    return view_dependent or any(light.kind == "point" for light in scene.lights)


#: Range of a style's ``uv_scale`` factors: beyond it the texture LOD (log2 of the scaled uv
#: derivatives) and the lattice coordinates of procedural textures stop being finite or exact.
UV_SCALE_RANGE = (1e-6, 1e6)


def check_uv_scale(name: str, value: Any) -> tuple[float, float] | None:
    """A style's ``uv_scale``: None (each material's own) or a positive number or ``[su, sv]``
    (each in ``UV_SCALE_RANGE``) that multiplies uv in place of the material's ``uv_scale``; the
    same meaning in every style."""
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
