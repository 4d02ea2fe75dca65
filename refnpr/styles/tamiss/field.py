"""The RPTAM stroke field of TAMISS: nested seeds, levels, stroke ids and per-stroke attributes.

TAMISS (Szécsi et al.) gathers its fragments from an RPTAM (Szécsi and Szirányi 2014), which the
paper only cites; DESIGN.md's notes fix what is needed. This module is the pure definition (numpy,
no rasterization); ``_kernels`` evaluates the same definition per G-buffer sample.

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

import math
from dataclasses import dataclass

import numpy as np

from .._common import check_count, check_number

__all__ = [
    "KX",
    "N_ROWS",
    "MAX_LEVEL",
    "MAX_CHARTS",
    "TILE_LIMIT",
    "SALT_TONE",
    "SALT_LENGTH",
    "SALT_WIDTH",
    "DEFAULT_DENSITY",
    "StrokeField",
    "seed_set",
    "born_at",
    "pack_id",
    "unpack_id",
    "splitmix64",
    "salt_offset",
    "hash01",
    "key32",
    "StrokeGeometry",
    "stroke_geometry",
    "fade_in",
    "layer_angles",
]

#: Column (in sevenths) of the base seed of row r: S_0 = {(KX[r] / 7, r / 7)}.
KX = np.array([0, 6, 5, 1, 3, 4, 2], dtype=np.int64)
#: Rows (and seeds) per cell.
N_ROWS = 7
#: Deepest level; ids hold the birth level in 4 bits and cells in 22 bits.
MAX_LEVEL = 12
#: Charts (objects x uv charts) an id can hold (10 bits).
MAX_CHARTS = 1024
#: |p|, |q| must stay below this many tiles (cells at level 12 then fit 22 bits).
TILE_LIMIT = 512

_CELL_BITS = 22
_CELL_OFF = 1 << (_CELL_BITS - 1)
_MASK22 = (1 << _CELL_BITS) - 1

#: Default ``density``: each layer is complete halfway from its starting darkness to black, so
#: that the darkest tones are fully cross-hatched (strokes of ``width`` 1.5 px every 4 px cover
#: at most about 37 % per layer; with density 1 a drawing stays pale: ink about a quarter of the
#: darkness, see ``docs/tamiss.md``, "Defaults").
DEFAULT_DENSITY = 2.0

#: Salts of the per-stroke hashes.
SALT_TONE, SALT_LENGTH, SALT_WIDTH = 1, 2, 3


def _finite(d: float) -> bool:
    """Whether the number ``d`` is a finite float (a Python int past float64 is not)."""
    try:
        return math.isfinite(float(d))
    except OverflowError:
        return False


def _check_angle_list(directions) -> tuple[float, ...]:
    vals = directions if isinstance(directions, (list, tuple)) else [directions]
    if not 1 <= len(vals) <= 4:
        raise ValueError(
            f"directions: expected 1 to 4 hatching layers, got {len(vals)} ({directions!r})"
        )
    out = []
    for d in vals:
        if d == "u":
            out.append(0.0)
        elif d == "v":
            out.append(90.0)
        elif isinstance(d, (int, float)) and not isinstance(d, bool) and _finite(d):
            out.append(float(d))
        else:
            raise ValueError(
                f"directions: each layer is 'u', 'v' or an angle in degrees from u towards v, "
                f"got {d!r}"
            )
    return tuple(out)


def layer_angles(directions) -> tuple[float, ...]:
    """Angles in degrees (0 = along u, 90 = along v) of ``directions`` ('u', 'v' or numbers)."""
    return _check_angle_list(directions)


@dataclass(frozen=True)
class StrokeField:
    """Parameters of the RPTAM stroke field shared by the ``tam`` and ``tamiss`` styles.

    Attributes
    ----------
    directions : tuple of float
        Hatching layers: angle in degrees from u towards v (0 = along u, 90 = along v).
    layer_tones : tuple of float
        Darkness in [0, 1) at which each layer starts (cross-hatching appears in darker tones).
    period : float
        Target spacing of stroke rows in pixels (w of the dyadic scale), > 0.
    length : float
        Stroke length in cells of the birth level (lam), > 0.
    length_jitter : float
        Relative texture-space length jitter in [0, 0.9].
    width_jitter : float
        Relative width jitter in [0, 0.9].
    density : float
        Multiplies the fraction of strokes drawn, rho = clip(density (d - d_k) / (1 - d_k), 0, 1).
    max_level : int
        Deepest level, 0..12.
    """

    directions: tuple[float, ...] = (0.0, 90.0)
    layer_tones: tuple[float, ...] = (0.0, 0.5)
    period: float = 4.0
    length: float = 1.0
    length_jitter: float = 0.3
    width_jitter: float = 0.2
    density: float = DEFAULT_DENSITY
    max_level: int = 10

    @classmethod
    def from_params(
        cls,
        *,
        directions=("u", "v"),
        layer_tones=None,
        period: float = 4.0,
        length: float = 1.0,
        length_jitter: float = 0.3,
        width_jitter: float = 0.2,
        density: float = DEFAULT_DENSITY,
        max_level: int = 10,
    ) -> StrokeField:
        """Validate style parameters (TOML values) into a field; ``layer_tones`` defaults to
        ``k / n_layers`` for layer k."""
        angles = _check_angle_list(directions)
        if layer_tones is None:
            tones = tuple(k / len(angles) for k in range(len(angles)))
        else:
            vals = layer_tones if isinstance(layer_tones, (list, tuple)) else [layer_tones]
            if len(vals) != len(angles):
                raise ValueError(
                    f"layer_tones: expected one darkness per layer ({len(angles)}), got "
                    f"{layer_tones!r}"
                )
            tones = tuple(check_number("layer_tones", v, lo=0.0, hi=0.999) for v in vals)
        return cls(
            directions=angles,
            layer_tones=tones,
            period=check_number("period", period, lo=0.0, lo_open=True),
            length=check_number("length", length, lo=0.0, lo_open=True, hi=8.0),
            length_jitter=check_number("length_jitter", length_jitter, lo=0.0, hi=0.9),
            width_jitter=check_number("width_jitter", width_jitter, lo=0.0, hi=0.9),
            density=check_number("density", density, lo=0.0),
            max_level=check_count("max_level", max_level, lo=0, hi=MAX_LEVEL),
        )

    @property
    def n_layers(self) -> int:
        return len(self.directions)

    def as_dict(self) -> dict:
        return {
            "directions": list(self.directions),
            "layer_tones": list(self.layer_tones),
            "period": self.period,
            "length": self.length,
            "length_jitter": self.length_jitter,
            "width_jitter": self.width_jitter,
            "density": self.density,
            "max_level": self.max_level,
        }


def seed_set(level: int) -> np.ndarray:
    """S_level of one tile: (7 4^level, 2) float64 seed positions (p, q) in [0, 1)^2."""
    level = check_count("level", level, lo=0, hi=MAX_LEVEL)
    n = 1 << level
    g = np.arange(n)
    gx, gy, r = np.meshgrid(g, g, np.arange(N_ROWS), indexing="ij")
    return np.stack([(gx + KX[r] / 7.0) / n, (gy + r / 7.0) / n], axis=-1).reshape(-1, 2)


def born_at(level, gx, gy, r) -> np.ndarray:
    """Whether the seed of row r in cell (gx, gy) of ``level`` is new there (not in level - 1)."""
    level, gx, gy, r = (np.asarray(a, dtype=np.int64) for a in (level, gx, gy, r))
    inherited = (level > 0) & ((gx & 1) == (KX[r] & 1)) & ((gy & 1) == (r & 1))
    return ~inherited


def pack_id(chart, layer, level, gx, gy, r) -> np.ndarray:
    """Globally unique stroke id: int64 from (chart, layer, birth level, birth cell, row).

    Bit layout (63 bits): chart 10 | layer 2 | level 4 | gx + 2^21 (22) | gy + 2^21 (22) | row 3.
    """
    chart, layer, level, gx, gy, r = (
        np.asarray(a, dtype=np.int64) for a in (chart, layer, level, gx, gy, r)
    )
    v = chart * 4 + layer
    v = v * 16 + level
    v = (v << _CELL_BITS) + (gx + _CELL_OFF)
    v = (v << _CELL_BITS) + (gy + _CELL_OFF)
    return v * 8 + r


def unpack_id(ids) -> dict[str, np.ndarray]:
    """Inverse of :func:`pack_id`: dict of int64 arrays chart, layer, level, gx, gy, row."""
    v = np.asarray(ids, dtype=np.int64)
    r = v & 7
    v = v >> 3
    gy = (v & _MASK22) - _CELL_OFF
    v = v >> _CELL_BITS
    gx = (v & _MASK22) - _CELL_OFF
    v = v >> _CELL_BITS
    level = v & 15
    v = v >> 4
    return {"chart": v >> 2, "layer": v & 3, "level": level, "gx": gx, "gy": gy, "row": r}


_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xBF58476D1CE4E5B9)
_M3 = np.uint64(0x94D049BB133111EB)


def splitmix64(x) -> np.ndarray:
    """SplitMix64 finalizer on uint64 (wrapping), elementwise."""
    z = np.atleast_1d(np.asarray(x).astype(np.uint64)) + _M1
    z = (z ^ (z >> np.uint64(30))) * _M2
    z = (z ^ (z >> np.uint64(27))) * _M3
    return z ^ (z >> np.uint64(31))


def salt_offset(salt: int) -> np.uint64:
    """salt * 0x9E3779B97F4A7C15 modulo 2^64 (added to ids before hashing)."""
    return np.uint64((int(salt) * 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF)


def hash01(ids, salt: int) -> np.ndarray:
    """A uniform float64 in [0, 1) per id: the top 53 bits of splitmix64(id + salt * M1)."""
    z = np.atleast_1d(np.asarray(ids, dtype=np.int64)).astype(np.uint64)
    z = z + salt_offset(salt)
    return (splitmix64(z) >> np.uint64(11)).astype(np.float64) * (1.0 / 9007199254740992.0)


def key32(ids) -> np.ndarray:
    """32-bit key of each id for the double-hashing table (top half of splitmix64(id)).

    0xFFFFFFFF marks empty slots, so that value is folded to 0xFFFFFFFE. Distinct ids may share
    a key (probability about S^2 / 2^33 for S strokes); the hashed route reports such aliases.
    """
    k = (splitmix64(np.asarray(ids, dtype=np.int64)) >> np.uint64(32)).astype(np.uint32)
    return np.where(k == np.uint32(0xFFFFFFFF), np.uint32(0xFFFFFFFE), k)


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

    def point(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(p, q) of stroke parameter t (broadcast against (S,))."""
        t = np.asarray(t, dtype=np.float64)
        return self.p_start + t * self.length, np.broadcast_to(
            self.q, np.broadcast(t, self.q).shape
        )


def stroke_geometry(ids, field: StrokeField) -> StrokeGeometry:
    """Texture-space geometry and attributes of strokes from their ids (see module docstring)."""
    d = unpack_id(ids)
    scale = np.ldexp(1.0, -d["level"])
    p_seed = (d["gx"] + KX[d["row"]] / 7.0) * scale
    q = (d["gy"] + d["row"] / 7.0) * scale
    h_len = hash01(ids, SALT_LENGTH)
    length = field.length * (1.0 + field.length_jitter * (2.0 * h_len - 1.0)) * scale
    return StrokeGeometry(
        chart=d["chart"],
        layer=d["layer"],
        level=d["level"],
        p_start=p_seed - 0.5 * length,
        p_end=p_seed + 0.5 * length,
        q=q,
        length=length,
        tau=hash01(ids, SALT_TONE),
        width_factor=1.0 + field.width_jitter * (2.0 * hash01(ids, SALT_WIDTH) - 1.0),
    )


def fade_in(f) -> np.ndarray:
    """alpha(f) = 2^f - 1: the fraction of the next level's strokes shown at transition f."""
    return np.exp2(np.asarray(f, dtype=np.float64)) - 1.0
