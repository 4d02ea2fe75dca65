"""The RPTAM stroke field of TAMISS: nested seeds, levels, stroke ids and per-stroke attributes.

TAMISS (Szécsi et al.) gathers its fragments from an RPTAM (Szécsi and Szirányi 2014), which the
paper only cites; DESIGN.md's notes fix what is needed. Its per-sample formulas are the scalar
functions of :mod:`refnpr.formulas.tamiss.field` (with their numpy faces), which the
``_kernels`` call per G-buffer sample; this module holds the field's parameters
(:class:`StrokeField`) and the geometry of strokes from their ids.

Coordinates. Per hatching layer with angle ``a`` (0: strokes along u, 90: along v), the scaled
texture coordinates uv' = uv * uv_scale are rotated into stroke coordinates::

    p = cos(a) u' + sin(a) v'     (along the strokes)
    q = -sin(a) u' + cos(a) v'    (across them)

A texture *tile* is a unit square of (p, q); level ``l`` splits it into 2^l x 2^l cells, indexed
by the global integer cell (gx, gy) = floor(2^l (p, q)) (the tile is (gx >> l, gy >> l)).

Seeds. The base seed set S_0 has seven points (KX[r] / 7, r / 7), r = 0..6, one per row::

    KX = (0, 6, 5, 1, 3, 4, 2)

and level l repeats it in every cell at scale 2^-l: S_l = {(g + s) / 2^l : g in Z^2, s in S_0}.
S_0 is closed under s -> (s + o) / 2 for the right o in {0, 1}^2 and under its inverse (its
coordinates are sevenths with periodic binary expansions: the cycles (1 4 2), (3 5 6) and the
fixed point 0), so S_l is a subset of S_{l+1}: the same seed set repeats at half scale on a 2 x 2
grid, every coarse seed persists and three times as many new seeds appear between the old ones.
The seed of row r in cell (gx, gy) of level l >= 1 already existed at level l - 1 exactly when
(gx & 1, gy & 1) == (KX[r] & 1, r & 1); otherwise it is *born* at level l.

Stroke id. A stroke is identified by its birth level b, birth cell (gx, gy) and row r, the chart
(object and uv chart: the paper's "object index", and for overlapping charts such as the teapot's
patches the "layer" of the mapping) and the hatching layer, packed into a non-negative int64
(:func:`pack_id`). It does not depend on the level the stroke is seen at.

Attributes from the id (hashes of the id, that is of the stroke's global position and birth
level): tone threshold ``tau`` in [0, 1); length ``lam (1 + j (2 h - 1)) 2^-b`` in texture units
along p; a width factor ``1 + wj (2 h - 1)``. The stroke runs along p over
[p_seed - length / 2, p_seed + length / 2] at q = q_row, and t = (p - p_start) / length in [0, 1]
is its stroke-space coordinate. Its width is given in pixels (texture-space width
``width * factor / D_q`` at each texel), so hatching keeps its screen-space weight.

Level (per layer and sample). With D_q = 1 / |grad q| (pixels per unit of q) the row spacing at
level l is D_q / (7 2^l) pixels; the dyadic scale is s = log2(D_q / (7 w)) for the target row
spacing w pixels (``period``), L = floor(s), f = s - L (L clamped to [0, max_level], f = 0 at the
clamps). Strokes born at levels <= L are fully active; strokes born at L + 1 fade in with
alpha = 2^f - 1 (their density test is tau < rho alpha). The ink of levels <= L is
10.5 * 2^L - 3.5 cell lengths per tile and level L + 1 adds 10.5 * 2^L, so the ink per screen area
is 10.5 - 3.5 / 2^(L + f): constant in the limit of many levels, within 25 % over f at L = 0 and
10 % at L = 1, continuous across level boundaries (alpha reaches 1 at f = 1, where level L + 1
takes over without popping). Where s < 0 (rows closer than w even at level 0) the density test
uses rho 2^s instead: the rows are thinned at random so that the ink stays the same.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.formulas.tamiss.field import (
    KX,
    N_ROWS,
    hash01,
    stroke_length,
    stroke_start,
    unpack_id,
    width_factor,
)

from .._declare import Values
from .params import DEFAULT_DENSITY, FIELD, FIELD_PARAMS, SALTS, resolve_field

__all__ = [
    "KX",
    "N_ROWS",
    "MAX_CHARTS",
    "TILE_LIMIT",
    "SALT_TONE",
    "SALT_LENGTH",
    "SALT_WIDTH",
    "StrokeField",
    "StrokeGeometry",
    "stroke_geometry",
]

#: Charts (objects x uv charts) an id can hold (10 bits).
MAX_CHARTS = 1024
#: |p|, |q| must stay below this many tiles (cells at level 12 then fit 22 bits).
TILE_LIMIT = 512
#: Salts of the per-stroke hashes.
SALT_TONE, SALT_LENGTH, SALT_WIDTH = SALTS["tone"], SALTS["length"], SALTS["width"]
_FIELD = [p.name for p in FIELD]


@dataclass(frozen=True)
class StrokeField:
    """Parameters of the RPTAM stroke field shared by the ``tam`` and ``tamiss`` styles: the
    parameters declared in :data:`refnpr.styles.tamiss.params.FIELD` (their docs), with
    ``directions`` as angles in degrees from u towards v and ``layer_tones`` resolved."""

    directions: tuple[float, ...] = (0.0, 90.0)
    layer_tones: tuple[float, ...] = (0.0, 0.5)
    period: float = 4.0
    length: float = 1.0
    length_jitter: float = 0.3
    width_jitter: float = 0.2
    density: float = DEFAULT_DENSITY
    max_level: int = 10

    @classmethod
    def from_params(cls, **params: Any) -> StrokeField:
        """Validate the field's parameters (TOML values; :data:`~.params.FIELD`) into a field;
        ``layer_tones`` defaults to ``k / n_layers`` for layer k."""
        return cls.of(FIELD_PARAMS.validate(params))

    @classmethod
    def of(cls, values: Values) -> StrokeField:
        """The field of a style's validated parameters (``tam`` or ``tamiss``)."""
        values = resolve_field(values)
        return cls(**{name: values[name] for name in _FIELD})

    @property
    def n_layers(self) -> int:
        return len(self.directions)

    def as_dict(self) -> dict:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in vars(self).items()}


@dataclass(frozen=True)
class StrokeGeometry:
    """Texture-space strokes (one per id), all (S,) float64 unless noted.

    Attributes
    ----------
    chart, layer, level : (S,) int64, birth level in ``level``
    p_start, p_end : start and end along p (p_end - p_start = length)
    q : the row's q
    length : texture units along p
    tau : tone threshold in [0, 1)
    width_factor : multiplies the pixel width
    """

    chart: np.ndarray
    layer: np.ndarray
    level: np.ndarray
    p_start: np.ndarray
    p_end: np.ndarray
    q: np.ndarray
    length: np.ndarray
    tau: np.ndarray
    width_factor: np.ndarray


def stroke_geometry(ids, field: StrokeField) -> StrokeGeometry:
    """Texture-space geometry and attributes of strokes from their ids (see module docstring):
    the length, start, tone threshold and width factor of each, as the kernels compute them."""
    d = unpack_id(ids)
    h_len = hash01(ids, SALT_LENGTH)
    length = stroke_length(h_len, field.length, field.length_jitter, d["level"])
    p_start = stroke_start(d["gx"], d["row"], d["level"], length)
    return StrokeGeometry(
        chart=d["chart"],
        layer=d["layer"],
        level=d["level"],
        p_start=p_start,
        p_end=p_start + length,
        q=(d["gy"] + d["row"] / 7.0) * np.ldexp(1.0, -d["level"]),
        length=length,
        tau=hash01(ids, SALT_TONE),
        width_factor=width_factor(hash01(ids, SALT_WIDTH), field.width_jitter),
    )
