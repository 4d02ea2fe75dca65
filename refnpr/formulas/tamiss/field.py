"""The RPTAM stroke field TAMISS gathers its fragments from (Szécsi et al., sec. 3.1).

The paper cites RPTAM (Szécsi and Szirányi 2014) without restating it; refnpr defines the field
as ``docs/tamiss.md`` ("The stroke field") and :mod:`refnpr.styles.tamiss.field` describe: per
hatching layer, stroke coordinates (p along the strokes, q across) of the scaled uv, a level
from the dyadic scale of q's pixel spacing, seven seeds per cell nested across levels, stroke
ids packed from (chart, layer, birth level, cell, row), and per-stroke attributes hashed from
the id (tone threshold, length, width factor).

Each per-sample line of that definition is a scalar device function (``f.scalar``) that the
style kernels call, and ``f`` its numpy face: the stroke coordinates and pixel spacings
(:func:`layer_frame`), the dyadic scale, the level rule and the fade-in of the next level, the
fraction of a layer's strokes drawn (:func:`layer_density`), a row's distance across, the born
test of a seed, the id packing, the hashes, a stroke's length, start and parameter t, its width
factor, the texture-space coverage of the TAM baseline, "over", and the darkness the tone
mapping reads.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit

from .._face import elementwise, face
from .._validate import (
    INT64_MIN,
    as_float,
    as_ints,
    as_vectors,
    check_bool,
    check_int,
    check_scalar,
    describe,
)
from ..lighting import luminance

__all__ = [
    "KX",
    "KX7",
    "N_ROWS",
    "MAX_LEVEL",
    "CELL_BITS",
    "SPLITMIX64",
    "splitmix64",
    "salt_offset",
    "hash01",
    "key32",
    "pack_id",
    "unpack_id",
    "born_at",
    "seed_set",
    "layer_frame",
    "dyadic_scale",
    "level_rule",
    "fade_in",
    "layer_density",
    "row_distance",
    "stroke_length",
    "stroke_start",
    "stroke_param",
    "width_factor",
    "tam_opacity",
    "tam_coverage",
    "ink_over",
    "darkness",
]

#: Column (in sevenths) of the base seed of row r: S_0 = {(KX[r] / 7, r / 7)}.
KX = np.array([0, 6, 5, 1, 3, 4, 2], dtype=np.int64)
#: KX / 7 per row (the seed's p within its cell at level 0).
KX7 = KX / 7.0
#: Rows (and seeds) per cell.
N_ROWS = 7
#: Deepest level; ids hold the birth level in 4 bits and cells in 22 bits.
MAX_LEVEL = 12
#: Bits of a cell index in an id.
CELL_BITS = 22
_CELL_OFF = 1 << (CELL_BITS - 1)
_MASK22 = (1 << CELL_BITS) - 1

#: The multipliers of SplitMix64 (the golden-ratio increment, then the two of the finalizer).
SPLITMIX64 = (0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB)
_M1, _M2, _M3 = (np.uint64(m) for m in SPLITMIX64)
_S11, _S27, _S30, _S31, _S32 = (np.uint64(k) for k in (11, 27, 30, 31, 32))
_INV53 = 1.0 / 9007199254740992.0
_EMPTY32 = np.uint64(0xFFFFFFFF)


#: The fields of an id (:func:`pack_id`): name, lowest and highest value, bits.
_ID_FIELDS = (
    ("chart", 0, 1023, 10),
    ("layer", 0, 3, 2),
    ("level", 0, 15, 4),
    ("gx", -_CELL_OFF, _CELL_OFF - 1, CELL_BITS),
    ("gy", -_CELL_OFF, _CELL_OFF - 1, CELL_BITS),
    ("r", 0, 7, 3),
)
_ROW_HINT = f"a cell has {N_ROWS} rows, 0 .. {N_ROWS - 1}"


def _bits(name: str, value) -> np.ndarray:
    """Integers taken as 64-bit patterns (ids, hash inputs): any int64 or uint64 value, as int64
    of the same bits."""
    return as_ints(name, value, lo=INT64_MIN, hi=2**64 - 1)


def _floats(**named) -> tuple[np.ndarray, ...]:
    return tuple(as_float(k, v) for k, v in named.items())


# ---------------------------------------------------------------------- hashes and ids


@njit
def _splitmix64(z):
    z = z + _M1
    z = (z ^ (z >> _S30)) * _M2
    z = (z ^ (z >> _S27)) * _M3
    return z ^ (z >> _S31)


@face(_splitmix64)
def splitmix64(x) -> np.ndarray:
    """SplitMix64 finalizer on uint64 (wrapping), elementwise; at least 1-D.

    Parameters
    ----------
    x : (...) integer array
        Values taken modulo 2^64: int64 (negative values wrap) or uint64.

    Returns
    -------
    (...) uint64 ndarray, at least 1-D
    """
    z = np.atleast_1d(_bits("x", x)).astype(np.uint64)
    return elementwise(splitmix64.scalar, np.int64, z).view(np.uint64)


def salt_offset(salt: int) -> np.uint64:
    """salt * 0x9E3779B97F4A7C15 modulo 2^64 (added to ids before hashing).

    Parameters
    ----------
    salt : int
        An integer in [-2^63, 2^64 - 1] (int64 or uint64); not a float or a bool.

    Returns
    -------
    numpy.uint64
    """
    salt = check_int("salt", salt, hi=2**64 - 1, hint="pass an integer salt, e.g. 1")
    return np.uint64((salt * 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF)


@njit
def _hash01(sid, salt):
    return np.float64(_splitmix64(np.uint64(sid) + salt) >> _S11) * _INV53


@face(_hash01)
def hash01(ids, salt: int) -> np.ndarray:
    """A uniform float64 in [0, 1) per id: the top 53 bits of splitmix64(id + salt * M1).
    ``hash01.scalar(id, offset)`` takes the offset (:func:`salt_offset`). At least 1-D.

    Parameters
    ----------
    ids : (...) integer array
        Stroke ids (:func:`pack_id`), int64 or uint64.
    salt : int
        The hash's salt (:func:`salt_offset`).

    Returns
    -------
    (...) float64 ndarray in [0, 1), at least 1-D
    """
    z = np.atleast_1d(_bits("ids", ids))
    return elementwise(hash01.scalar, np.float64, z, salt_offset(salt))


@njit
def _key32(sid):
    k = _splitmix64(np.uint64(sid)) >> _S32
    return k - np.uint64(1) if k == _EMPTY32 else k


@face(_key32)
def key32(ids) -> np.ndarray:
    """32-bit key of each id for the double-hashing table (top half of splitmix64(id)).

    0xFFFFFFFF marks empty slots, so that value is folded to 0xFFFFFFFE. Distinct ids may share
    a key (probability about S^2 / 2^33 for S strokes); the hashed route reports such aliases.
    """
    return elementwise(key32.scalar, np.int64, _bits("ids", ids)).astype(np.uint32)


@njit
def _pack_id(chart, layer, level, gx, gy, r):
    v = chart * 4 + layer
    v = v * 16 + level
    v = (v << CELL_BITS) + (gx + _CELL_OFF)
    v = (v << CELL_BITS) + (gy + _CELL_OFF)
    return v * 8 + r


@face(_pack_id)
def pack_id(chart, layer, level, gx, gy, r) -> np.ndarray:
    """Globally unique stroke id: int64 from (chart, layer, birth level, birth cell, row).

    Bit layout (63 bits): chart 10 | layer 2 | level 4 | gx + 2^21 (22) | gy + 2^21 (22) | row 3.

    Parameters
    ----------
    chart, layer, level, gx, gy, r : (...) integer arrays, broadcast together
        chart in [0, 1023], layer in [0, 3], level in [0, 15], gx and gy in [-2^21, 2^21 - 1],
        r in [0, 7]: each field's bits above. A value outside its field would spill into
        the next one (two tuples, one id), so it is refused.

    Returns
    -------
    (...) int64 ndarray of ids >= 0
    """
    named = {"chart": chart, "layer": layer, "level": level, "gx": gx, "gy": gy, "r": r}
    fields = [
        as_ints(k, named[k], lo=lo, hi=hi, hint=f"an id holds {k} in {bits} bits")
        for k, lo, hi, bits in _ID_FIELDS
    ]
    return elementwise(pack_id.scalar, np.int64, *fields)


def unpack_id(ids) -> dict[str, np.ndarray]:
    """Inverse of :func:`pack_id`: dict of int64 arrays chart, layer, level, gx, gy, row."""
    v = np.asarray(ids, dtype=np.int64)
    gy = ((v >> 3) & _MASK22) - _CELL_OFF
    gx = ((v >> (3 + CELL_BITS)) & _MASK22) - _CELL_OFF
    top = v >> (3 + 2 * CELL_BITS)  # chart 10 | layer 2 | level 4
    chart, layer, level = top >> 6, (top >> 4) & 3, top & 15
    return {"chart": chart, "layer": layer, "level": level, "gx": gx, "gy": gy, "row": v & 7}


@njit
def _born_at(level, gx, gy, r, kx):
    return not (level > 0 and (gx & 1) == (kx & 1) and (gy & 1) == (r & 1))


@face(_born_at)
def born_at(level, gx, gy, r) -> np.ndarray:
    """Whether the seed of row r in cell (gx, gy) of ``level`` is new there (not in level - 1):
    a seed of level l >= 1 already existed at l - 1 exactly when (gx & 1, gy & 1) == (KX[r] & 1,
    r & 1). ``born_at.scalar(level, gx, gy, r, kx)`` takes the row's column kx = KX[r].

    Parameters
    ----------
    level, gx, gy : (...) integer arrays
    r : (...) integer array in [0, 6]
        The seed's row in its cell.

    Returns
    -------
    (...) bool ndarray, broadcast shape
    """
    args = [as_ints(k, v) for k, v in zip("level gx gy".split(), (level, gx, gy), strict=True)]
    rows = as_ints("r", r, lo=0, hi=N_ROWS - 1, hint=_ROW_HINT)
    return elementwise(born_at.scalar, np.bool_, *args, rows, KX[rows])


def seed_set(level: int) -> np.ndarray:
    """S_level of one tile: (7 4^level, 2) float64 seed positions (p, q) in [0, 1)^2."""
    level = check_int("level", level, lo=0, hi=MAX_LEVEL)
    n = 1 << level
    g = np.arange(n)
    gx, gy, r = np.meshgrid(g, g, np.arange(N_ROWS), indexing="ij")
    return np.stack([(gx + KX[r] / 7.0) / n, (gy + r / 7.0) / n], axis=-1).reshape(-1, 2)


# ---------------------------------------------------------------------- a layer at a sample


@njit
def _layer_frame(uv, dx, dy, scale, ca, sa):
    u = uv[0] * scale[0]  # uv' = uv * uv_scale
    v = uv[1] * scale[1]
    ux = dx[0] * scale[0]
    vx = dx[1] * scale[1]
    uy = dy[0] * scale[0]
    vy = dy[1] * scale[1]
    p = ca * u + sa * v  # along the strokes
    q = -sa * u + ca * v  # across them
    gp = math.hypot(ca * ux + sa * vx, ca * uy + sa * vy)
    gq = math.hypot(-sa * ux + ca * vx, -sa * uy + ca * vy)
    if not (gq > 0.0 and gp > 0.0 and gq < 1e30 and gp < 1e30):
        return p, q, math.nan, math.nan
    return p, q, 1.0 / gp, 1.0 / gq


@face(_layer_frame)
def layer_frame(uv, duv_dx, duv_dy, uv_scale, angle) -> np.ndarray:
    """(..., 4): p, q and the pixel spacings d_p = 1 / |grad p|, d_q = 1 / |grad q| of the
    layer at ``angle`` degrees (0: strokes along u) at each sample: uv' = uv * uv_scale,
    p = cos a u' + sin a v', q = -sin a u' + cos a v'. d_p, d_q are NaN where a gradient is 0 or
    not below 1e30 (no strokes there)."""
    a = math.radians(check_scalar("angle", angle))
    vecs = [as_vectors(k, v, 2) for k, v in (("uv", uv), ("duv_dx", duv_dx), ("duv_dy", duv_dy))]
    scale = as_vectors("uv_scale", uv_scale, 2)
    args = [(x[..., 0], x[..., 1]) for x in (*vecs, scale)]
    return elementwise(layer_frame.scalar, np.float64, *args, math.cos(a), math.sin(a))


@njit
def _dyadic_scale(d_q, period):
    return math.log2(d_q / (7.0 * period))


@face(_dyadic_scale)
def dyadic_scale(d_q, period: float) -> np.ndarray:
    """s = log2(d_q / (7 period)): the level at which rows (7 per cell) are ``period`` pixels
    apart, for d_q pixels per unit of q (Veryovka's eq. 5 for the coordinate across)."""
    period = check_scalar("period", period, lo=0.0, lo_open=True)
    return elementwise(dyadic_scale.scalar, np.float64, as_float("d_q", d_q), period)


@njit
def _fade_in(f):
    return math.pow(2.0, f) - 1.0


@face(_fade_in)
def fade_in(f) -> np.ndarray:
    """alpha(f) = 2^f - 1: the fraction of the next level's strokes shown at transition f."""
    return elementwise(fade_in.scalar, np.float64, as_float("f", f))


@njit
def _level_rule(s, max_level):
    big_l = math.floor(s)
    f = s - big_l
    thin = 1.0
    if big_l < 0:  # rows closer than the period even at level 0: thin them, same ink
        thin = math.pow(2.0, s)
        big_l = 0
        f = 0.0
    if big_l >= max_level:
        big_l = max_level
        f = 0.0
    return big_l, f, thin


#: Dyadic scales below this thin rows to nothing: 2^s rounds to 0 below -1075.
_S_FLOOR = -1100.0


@face(_level_rule)
def level_rule(s, max_level: int) -> np.ndarray:
    """(..., 3): L, f and the thinning gain of a dyadic scale s: L = floor(s), f = s - L; where
    s < 0, L = 0, f = 0 and the gain 2^s (rows thinned at random, same ink); where L >=
    ``max_level``, L = max_level and f = 0. Levels <= L are active, level L + 1 fades in with
    :func:`fade_in` (f).

    Parameters
    ----------
    s : (...) float array
        Finite dyadic scales; any magnitude (every s >= ``max_level`` gives (max_level, 0, 1),
        every s <= -1075 the gain 0).
    max_level : int in [0, 12]
        The deepest level (at most :data:`MAX_LEVEL`).

    Returns
    -------
    (..., 3) float64 ndarray: L, f, gain
    """
    s_ = as_float("s", s, finite=True)
    top = check_int(
        "max_level", max_level, lo=0, hi=MAX_LEVEL, hint="the field's deepest level is MAX_LEVEL"
    )
    # s past either end changes nothing: L = max_level, f = 0 above; 2^s = 0 below -1075 (so
    # floor(s) stays an int64 for any finite s)
    s_ = np.clip(s_.astype(np.float64), _S_FLOOR, float(top))
    return elementwise(level_rule.scalar, np.float64, s_, top)


@njit
def _layer_density(darkness, tone_lo, density):
    rho = (darkness - tone_lo) / (1.0 - tone_lo) * density
    return min(max(rho, 0.0), 1.0)


@face(_layer_density)
def layer_density(darkness, tone_lo, density) -> np.ndarray:
    """rho = clip(density (d - d_k) / (1 - d_k), 0, 1): the fraction of a layer's strokes drawn
    at darkness d, for the layer starting at darkness d_k (``tone_lo``)."""
    d, lo = as_float("darkness", darkness), as_float("tone_lo", tone_lo)
    if np.any(lo >= 1.0):
        raise ValueError(f"tone_lo: expected values < 1 (a layer must start below black), got {lo}")
    rho = as_float("density", density)
    return elementwise(layer_density.scalar, np.float64, d, lo, rho)


@njit
def _row_distance(q, ry, rows, d_q):
    return abs(q - ry / rows) * d_q


@face(_row_distance)
def row_distance(q, ry, rows, d_q) -> np.ndarray:
    """|q - ry / rows| d_q: pixels across from q to row ry of a level with ``rows`` rows per
    unit of q (7 2^level)."""
    args = as_float("q", q), as_ints("ry", ry), as_float("rows", rows), as_float("d_q", d_q)
    return elementwise(row_distance.scalar, np.float64, *args)


# ---------------------------------------------------------------------- one stroke


@njit
def _stroke_length(h, length, jitter, inv_scale):
    return length * (1.0 + jitter * (2.0 * h - 1.0)) * inv_scale


@face(_stroke_length)
def stroke_length(h, length: float, jitter: float, level) -> np.ndarray:
    """lam (1 + j (2 h - 1)) 2^-level: a stroke's length along p, h its length hash."""
    inv = np.ldexp(1.0, -as_ints("level", level))
    lam, j = as_float("length", length), as_float("jitter", jitter)
    return elementwise(stroke_length.scalar, np.float64, as_float("h", h), lam, j, inv)


@njit
def _stroke_start(gx, kx7, inv_scale, length):
    return (gx + kx7) * inv_scale - 0.5 * length


@face(_stroke_start)
def stroke_start(gx, r, level, length) -> np.ndarray:
    """p_start = (gx + KX[r] / 7) 2^-level - length / 2: where the stroke of seed (gx, r) of
    ``level`` starts along p (centred on its seed). ``stroke_start.scalar(gx, kx7, 2^-level,
    length)`` takes the row's KX[r] / 7.

    Parameters
    ----------
    gx : (...) integer array
    r : (...) integer array in [0, 6]
        The seed's row in its cell.
    level : (...) integer array
    length : (...) float array

    Returns
    -------
    (...) float64 ndarray, broadcast shape
    """
    rows = as_ints("r", r, lo=0, hi=N_ROWS - 1, hint=_ROW_HINT)
    args = as_ints("gx", gx), KX7[rows], np.ldexp(1.0, -as_ints("level", level))
    return elementwise(stroke_start.scalar, np.float64, *args, as_float("length", length))


@njit
def _stroke_param(p, p_start, length, d_p):
    t = (p - p_start) / length
    return t, max(-t, t - 1.0) * length * d_p


@face(_stroke_param)
def stroke_param(p, p_start, length, d_p) -> np.ndarray:
    """(..., 2): the stroke parameter t = (p - p_start) / length and the signed pixel distance
    past the nearer end, max(-t, t - 1) length d_p (negative inside the stroke)."""
    args = _floats(p=p, p_start=p_start, length=length, d_p=d_p)
    return elementwise(stroke_param.scalar, np.float64, *args)


@njit
def _width_factor(h, jitter):
    return 1.0 + jitter * (2.0 * h - 1.0)


@face(_width_factor)
def width_factor(h, jitter: float) -> np.ndarray:
    """1 + wj (2 h - 1): a stroke's width factor, h its width hash."""
    j = check_scalar("jitter", jitter)
    return elementwise(width_factor.scalar, np.float64, as_float("h", h), j)


@njit
def _tam_opacity(limit, tau, fade, clip):
    if clip:
        return 1.0 if tau < limit else 0.0
    return min(max((limit - tau) / fade, 0.0), 1.0)


@face(_tam_opacity)
def tam_opacity(limit, tau, fade: float, clip: bool) -> np.ndarray:
    """The TAM baseline's density decision of a stroke: 1 if tau < limit else 0 (``clip``), or
    clip((limit - tau) / fade, 0, 1); limit = rho * gain."""
    args = as_float("limit", limit), as_float("tau", tau)
    clip = check_bool("clip", clip)
    fade = check_scalar("fade", fade, lo=0.0, lo_open=not clip)
    return elementwise(tam_opacity.scalar, np.float64, *args, fade, clip)


@njit
def _tam_coverage(width, wf, dist, beyond):
    cov_q = min(max(0.5 * width * wf - dist + 0.5, 0.0), 1.0)
    cov_p = min(max(0.5 - beyond, 0.0), 1.0)
    return cov_q * cov_p


@face(_tam_coverage)
def tam_coverage(width, wf, dist, beyond) -> np.ndarray:
    """clip(w f / 2 - d + 0.5, 0, 1) clip(0.5 - e, 0, 1): the TAM baseline's anti-aliased
    coverage of a stroke of ``width`` pixels and width factor f at d pixels across and e pixels
    past its nearer end (signed)."""
    args = _floats(width=width, wf=wf, dist=dist, beyond=beyond)
    return elementwise(tam_coverage.scalar, np.float64, *args)


@njit
def _ink_over(ink, a):
    return ink + a * (1.0 - ink)


@face(_ink_over)
def ink_over(ink, a) -> np.ndarray:
    """ink + a (1 - ink): a stroke of coverage a over the ink so far ("over"; strokes combine to
    1 - prod(1 - a))."""
    return elementwise(ink_over.scalar, np.float64, as_float("ink", ink), as_float("a", a))


# ---------------------------------------------------------------------- tone

_luminance = luminance.scalar


@njit
def _darkness(r, g, b):
    lum = _luminance(r, g, b)
    lum = 0.0 if lum < 0.0 else (1.0 if lum > 1.0 else lum)
    return 1.0 - lum  # NaN stays NaN


@face(_darkness)
def darkness(rgb) -> np.ndarray:
    """1 - clip(Y, 0, 1), Y the Rec. 709 luminance (``lighting.luminance``) of linear ``rgb``
    (..., C >= 3): the darkness the layers' densities follow (of Veryovka eq. 1's diffuse
    colour)."""
    c = as_float("rgb", rgb)
    if c.ndim < 1 or c.shape[-1] < 3:
        raise ValueError(f"rgb: expected shape (..., 3), got {describe(c)}")
    return elementwise(darkness.scalar, np.float64, c[..., 0], c[..., 1], c[..., 2])
