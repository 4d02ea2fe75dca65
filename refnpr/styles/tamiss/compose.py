"""What the ``tam`` and ``tamiss`` styles share: channels, colours and compositing ink over a base."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._common import rgba_out
from .._declare import short_repr
from ..base import ShadeContext, Style, nested_style

__all__ = [
    "check_color",
    "field_channels",
    "base_style",
    "composite_ink",
    "keep_darkness",
    "FieldStyle",
]


def check_color(
    name: str, value: Any, *, optional: bool = True
) -> tuple[float, float, float] | None:
    """A linear RGB triple in [0, 1] (a single number means grey); None passes through where
    ``optional`` (``paper``), else is refused (``ink``)."""
    if value is None:
        if optional:
            return None
        raise TypeError(f"{name}: expected 3 numbers in [0, 1] (linear RGB), got None")
    vals = [value] * 3 if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    try:
        c = np.asarray(vals, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise TypeError(f"{name}: expected 3 numbers in [0, 1], got {short_repr(value)}") from None
    if c.shape != (3,) or not np.all(np.isfinite(c)) or np.any(c < 0) or np.any(c > 1):
        raise ValueError(
            f"{name}: expected 3 numbers in [0, 1] (linear RGB), got {short_repr(value)}"
        )
    return tuple(float(x) for x in c)


def field_channels(
    scene: Any, constant_tone: float | None, derivatives: str = "smooth"
) -> set[str]:
    """G-buffer channels the stroke field reads (tone needs normals, point lights positions;
    smooth derivatives the barycentrics, normals, positions and their screen derivatives)."""
    req = {"uv", "duv_dx", "duv_dy", "tri_id", "mesh_id"}
    if constant_tone is None:
        req.add("normal")
        if any(light.kind == "point" for light in scene.lights):
            req.add("position")
    if derivatives == "smooth":
        req |= {"bary", "normal", "position", "dposition_dx", "dposition_dy"}
    return req


def keep_darkness(ctx: ShadeContext, inputs: Any) -> None:
    """Keep the stroke field's darkness rho of each sample (``inputs``: the ``FieldInputs`` the
    strokes were made from) as the intermediate ``darkness`` when ``ctx`` asks for intermediates;
    0 where nothing is covered. Where the strokes were gathered on another grid
    (``gather_scale``), each covered sample takes the gather sample that holds its centre: row
    ``floor((j + 0.5) G / nH)`` of the G gather rows, and likewise for columns."""
    if not ctx.wants_intermediates:
        return
    full = np.zeros(inputs.shape)
    full.reshape(-1)[inputs.sample] = inputs.darkness
    nh, nw = ctx.gb.sample_shape
    if full.shape != (nh, nw):
        rows = ((np.arange(nh) + 0.5) * full.shape[0] / nh).astype(np.int64)
        cols = ((np.arange(nw) + 0.5) * full.shape[1] / nw).astype(np.int64)
        full = np.where(ctx.mask, full[np.ix_(rows, cols)], 0.0)
    ctx.keep("darkness", full)


def base_style(base: Any) -> Style | None:
    """The style drawn under the strokes (None: none); errors name ``base``."""
    return None if base is None else nested_style("base", base)


def composite_ink(
    ctx: ShadeContext,
    ink: np.ndarray,
    ink_color: tuple[float, float, float] | np.ndarray,
    *,
    base: Style | None,
    paper: tuple[float, float, float] | None,
) -> np.ndarray:
    """(nH, nW, 4) float32 straight-alpha RGBA: ink (coverage ``ink``) over the base style, or over
    the ``paper`` colour on covered samples, or over nothing (alpha = ink: the scene background
    shows through, also where strokes run past the silhouette). ``ink_color`` is one linear RGB
    or an (nH, nW, 3) colour per sample (the ``show`` views).

    One numba pass (``styles._kernels.ink_composite``): the coverage in float64, the base's
    RGBA in float32 (a style's ``shade`` gives float32; other dtypes are converted)."""
    from .._kernels import UNDER_NONE, UNDER_PAPER, UNDER_RGBA, Under, ink_composite

    ink = np.asarray(ink, dtype=np.float64)
    shape = ink.shape
    no_rgba, no_mask, no_rgb = np.zeros((1, 1, 4), np.float32), np.zeros((1, 1), bool), np.zeros(3)
    if base is not None:
        nested = ctx.under() if hasattr(ctx, "under") else ctx  # its intermediates: base.*
        under = np.broadcast_to(np.asarray(base.shade(nested), dtype=np.float32), shape + (4,))
        base_of = Under(UNDER_RGBA, np.ascontiguousarray(under), no_mask, no_rgb)
    elif paper is not None:
        # as rgba_from stores it: clipped, rounded to float32
        paper_rgb = np.clip(np.asarray(paper, dtype=np.float64), 0.0, 1.0)
        paper_rgb = paper_rgb.astype(np.float32).astype(np.float64)
        mask = np.ascontiguousarray(ctx.mask, dtype=np.bool_)
        base_of = Under(UNDER_PAPER, no_rgba, mask, paper_rgb)
    else:
        base_of = Under(UNDER_NONE, no_rgba, no_mask, no_rgb)
    colors = np.asarray(ink_color, dtype=np.float64)
    if colors.shape != (3,):
        colors = np.broadcast_to(colors, shape + (3,))
    out = rgba_out(ctx, shape)  # written in full by the kernel
    ink_rgb = np.ascontiguousarray(colors.reshape(-1, 3))
    ink_composite(base_of, (np.ascontiguousarray(ink), ink_rgb), out)
    return out


class FieldStyle(Style):
    """Base of the ``tam`` and ``tamiss`` styles: the G-buffer channels and raster options of
    the stroke field (:meth:`stroke_channels`) and of the ``base`` style under the strokes, and
    their ink composited over it."""

    base: Style | None = None
    paper: tuple[float, float, float] | None = None
    values: Any  # the validated parameters

    def stroke_channels(self, scene: Any) -> set[str]:
        """The channels the style reads for its strokes (:func:`field_channels`)."""
        return field_channels(scene, self.values.constant_tone, self.values.derivatives)

    def requires(self, scene: Any) -> frozenset[str]:
        req = self.stroke_channels(scene)
        if self.base is not None:
            req |= set(self.base.requires(scene))
        return frozenset(req)

    def raster_options(self, scene: Any) -> dict[str, Any]:
        opts = dict(self.base.raster_options(scene)) if self.base is not None else {}
        opts["dtype"] = np.float64  # uv to ~1e-12: cells of level 12 stay exact
        return opts

    def composite(self, ctx: ShadeContext, ink: np.ndarray, color: Any) -> np.ndarray:
        """:func:`composite_ink` of ``ink`` in ``color`` over this style's base or paper."""
        return composite_ink(ctx, ink, color, base=self.base, paper=self.paper)
