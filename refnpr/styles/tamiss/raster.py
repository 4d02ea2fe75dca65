"""Anti-aliased rasterization of image-space stroke strips, and brush textures (TAMISS sec. 4).

A piece (one drawn interval of a stroke) covers a sample with the fraction of its ``aa x aa``
sub-samples that lie inside any of the strip's triangles (union, so a strip folding over itself on
the inside of a tight bend is not inked twice). Pieces are composited in order (ascending stroke
id) with "over": A <- A + a (1 - A), a = coverage * opacity * brush(u, v).

The brush is an alpha texture along the stroke: u = t (the stroke parameter, wrapping), v = across
(0 on the left edge, 1 on the right). Built-ins: ``"solid"`` (1 everywhere), ``"pen"`` (slightly
soft edges), ``"pencil"`` (graphite grain), ``"dry"`` (bristle streaks fading towards the end of
the stroke); any other name or path is loaded with ``refnpr.texture.load_texture`` and its dark
parts are ink (alpha = 1 - gray).
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from .params import BRUSHES, PARAMS
from .strokes import Strips

__all__ = ["BRUSHES", "brush_texture", "rasterize_strips"]


def _smooth(a: np.ndarray, axis: int, k: int) -> np.ndarray:
    out = np.zeros_like(a)
    for s in range(-k, k + 1):
        out += np.roll(a, s, axis=axis)
    return out / (2 * k + 1)


def brush_texture(brush: str | None) -> tuple[np.ndarray, bool]:
    """``(Hb, Wb)`` float64 alpha in [0, 1] (rows: across, columns: along t) and whether u wraps."""
    if brush is None or brush == "solid":
        return np.ones((1, 1)), True
    if brush == "pen":
        return np.array([[0.6], [1.0], [1.0], [1.0], [1.0], [1.0], [1.0], [0.6]]), True
    rng = np.random.default_rng(20150405)
    if brush == "pencil":
        grain = _smooth(_smooth(rng.random((16, 256)), 1, 2), 0, 1)
        grain = (grain - grain.min()) / (grain.max() - grain.min())
        return 0.3 + 0.7 * grain, True
    if brush == "dry":
        bristles = _smooth(rng.random((24, 1)), 0, 1)
        streak = np.clip((bristles - 0.25) * 2.0, 0.0, 1.0)
        along = np.clip(1.6 - 1.2 * np.linspace(0.0, 1.0, 64), 0.0, 1.0)[None, :]
        noise = 0.8 + 0.2 * _smooth(rng.random((24, 64)), 1, 2)
        return np.clip(streak * along * noise, 0.0, 1.0), False
    from refnpr.texture import load_texture

    gray = np.asarray(load_texture(brush, param="brush"), dtype=np.float64)
    return np.ascontiguousarray(1.0 - gray), True


def rasterize_strips(
    strips: Strips,
    shape: tuple[int, int],
    n: int = 1,
    *,
    aa: int = 4,
    brush: str | None = None,
    opacity: float = 1.0,
    colors: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray] | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ink coverage of the strips on the sample grid.

    Parameters
    ----------
    strips : Strips (vertices in pixels)
    shape : (nH, nW), the sample grid; n : samples per pixel along an axis
    aa : sub-samples per axis and sample, 1..8
    brush : see module docstring; opacity : in [0, 1]

    Returns
    -------
    alpha : (nH, nW) float64 ink coverage in [0, 1]
    pieces : (nH, nW) int32, number of pieces touching each sample
    rgb : (nH, nW, 3) float64 premultiplied colour, only when ``colors`` (P, 3) is given (a
        colour per piece, composited with the same "over")
    """
    aa = PARAMS["aa"].check(aa)  # a kernel per aa (sub-sample bits: 64 at most)
    nh, nw = int(shape[0]), int(shape[1])
    alpha = np.zeros((nh, nw))
    touched = np.zeros((nh, nw), dtype=np.int32)
    rgb = np.zeros((nh, nw, 3))
    if colors is not None:
        colors = np.ascontiguousarray(colors, dtype=np.float64)
        if colors.shape != (len(strips), 3):
            raise ValueError(
                f"colors: expected shape ({len(strips)}, 3) (one RGB per piece), got {colors.shape}"
            )
    if len(strips) == 0:
        return (alpha, touched) if colors is None else (alpha, touched, rgb)
    left = np.ascontiguousarray(strips.strip.left, dtype=np.float64)
    right = np.ascontiguousarray(strips.strip.right, dtype=np.float64)
    if n != 1:  # x * 1 is x: no copies at one sample per pixel
        left, right = left * n, right * n
    bbox = np.empty((left.shape[0], 4), dtype=np.int64)
    K.strip_bbox(left, right, nh, nw, bbox)
    tex, wrap = brush_texture(brush)
    tv = np.ascontiguousarray(strips.strip.t, dtype=np.float64)
    rgb_in = colors if colors is not None else np.zeros((0, 3))
    pieces = K.Strips(left, right, tv, np.full(left.shape[0], float(opacity)), rgb_in)
    brush_tex = (np.ascontiguousarray(tex), bool(wrap))
    K.raster_strips_for(aa)(pieces, bbox, (nh, nw), brush_tex, (alpha, touched, rgb))
    return (alpha, touched) if colors is None else (alpha, touched, rgb)
