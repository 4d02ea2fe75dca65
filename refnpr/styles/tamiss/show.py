"""The ``show`` views of the ``tamiss`` style: stages of the pipeline (Szécsi et al., fig. 5).

Each view is false-coloured by stroke id (a colour per id from its hash, so a stroke keeps its
colour from stage to stage and from frame to frame):

* ``"ids"``: the stroke-ID TAM of fig. 6, which TAMISS gathers but never draws: each covered
  sample shows the first fragment gathered there (band ``gather_width`` pixels across);
* ``"fits"``: the cubic x(t), y(t) fitted to each kept stroke's fragments, drawn one pixel wide
  over [t_min, t_max] (curve fitting, before the extent and the style);
* ``"strokes"``: the extruded strips as drawn by ``show="color"`` (the default), each in its stroke's colour;
* ``"levels"``: the same strips coloured by the stroke's birth level (:data:`LEVEL_COLORS`):
  the nesting of the RPTAM field (fig. 2's property): the strokes of a coarse level stay where
  finer levels add theirs, and a darker tone keeps the strokes of a lighter one.
"""

from __future__ import annotations

import numpy as np

from refnpr.formulas.tamiss import hash01, unpack_id

from .pipeline import PipelineResult
from .raster import rasterize_strips
from .strokes import drawn_segments, extrude

__all__ = ["LEVEL_COLORS", "first_ids", "id_colors", "level_colors", "show_layers"]

#: Salts of the three colour channels of an id.
_SALT_RGB = (11, 12, 13)


#: Colour of each birth level (linear RGB), level 0 first; deeper levels reuse the last.
LEVEL_COLORS = np.array(
    [
        [0.0, 0.0, 0.0],  # 0: black
        [0.75, 0.02, 0.02],  # 1: red
        [0.0, 0.2, 0.85],  # 2: blue
        [0.0, 0.45, 0.05],  # 3: green
        [0.85, 0.35, 0.0],  # 4: orange
        [0.45, 0.0, 0.6],  # 5: purple
        [0.0, 0.45, 0.45],  # 6+: teal
    ]
)


def id_colors(ids: np.ndarray) -> np.ndarray:
    """(n, 3) float64 linear RGB per stroke id: a saturated hue from a hash of the id
    (value 0.7, saturation 0.9; linear values, so they stay visible as thin lines on white)."""
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    h = hash01(ids, _SALT_RGB[0]) * 6.0
    k = (np.array([5.0, 3.0, 1.0])[None, :] + h[:, None]) % 6.0
    ramp = np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)  # HSV to RGB, hue h / 6
    return 0.7 * (1.0 - 0.9 * ramp)


def level_colors(ids: np.ndarray) -> np.ndarray:
    """(n, 3) float64 linear RGB per stroke id: :data:`LEVEL_COLORS` of its birth level."""
    level = unpack_id(np.asarray(ids, dtype=np.int64).reshape(-1))["level"]
    return LEVEL_COLORS[np.minimum(level, len(LEVEL_COLORS) - 1)]


def first_ids(result: PipelineResult) -> np.ndarray:
    """(nH, nW) int64 on the output grid of ``result.ink``: the stroke id of the first fragment
    gathered at each sample (fig. 6's stroke-ID TAM, ordered as gathered), -1 where none; a
    finer gather grid (``gather_scale``) gives each output sample the first fragment gathered
    inside it."""
    frags = result.fragments
    nh, nw = result.ink.shape
    ids = np.full(nh * nw, -1, dtype=np.int64)
    if len(frags) and frags.n_axis == result.n:
        first = np.r_[True, frags.sample[1:] != frags.sample[:-1]]  # ordered by sample
        ids[frags.sample[first]] = frags.id[first]
    elif len(frags):  # gathered on a finer grid (gather_scale): the first id per output sample
        n = result.n
        sx = np.minimum((frags.x * n).astype(np.int64), nw - 1)
        sy = np.minimum((frags.y * n).astype(np.int64), nh - 1)
        out, first = np.unique(sy * nw + sx, return_index=True)
        ids[out] = frags.id[first]
    return ids.reshape(nh, nw)


def _ids_view(result: PipelineResult) -> tuple[np.ndarray, np.ndarray]:
    ids = first_ids(result).reshape(-1)
    seen = ids >= 0
    alpha = seen.astype(np.float64)
    rgb = np.zeros((ids.size, 3))
    rgb[seen] = id_colors(ids[seen])
    nh, nw = result.ink.shape
    return alpha.reshape(nh, nw), rgb.reshape(nh, nw, 3)


def _strip_view(result: PipelineResult, strips, by_level: bool = False):
    p = result.params
    colors = level_colors(strips.ids) if by_level else id_colors(strips.ids)
    alpha, _, rgb = rasterize_strips(strips, result.ink.shape, result.n, aa=p.aa, colors=colors)
    straight = np.divide(rgb, alpha[..., None], out=np.zeros_like(rgb), where=alpha[..., None] > 0)
    return alpha, straight


def show_layers(result: PipelineResult) -> tuple[np.ndarray, np.ndarray]:
    """Coverage (nH, nW) float64 and straight colour (nH, nW, 3) float64 of ``result.params.show``
    (not ``"color"``, which the style composites with its ink colour)."""
    p = result.params
    if p.show == "ids":
        return _ids_view(result)
    if p.show in ("strokes", "levels"):
        return _strip_view(result, result.strips, by_level=p.show == "levels")
    if p.show == "fits":
        segments, _ = drawn_segments(result.fit, "range", keep=result.keep)
        strips = extrude(
            result.fit, result.stroke_ids, segments, p.field, width=1.0, taper=0.0,
            samples=p.samples,
        )  # fmt: skip
        return _strip_view(result, strips)
    raise ValueError(f"show: expected one of 'ids', 'fits', 'strokes', 'levels', got {p.show!r}")
