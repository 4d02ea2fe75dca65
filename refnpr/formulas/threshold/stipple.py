"""Screen-round, jittered multi-scale stipple threshold texture (Veryovka sec. 3.2, Fig. 4).

The dot texture of :func:`dot_threshold` sits on a square uv lattice at one isotropic dyadic
scale, so where the mapping stretches uv (a UV sphere: u runs twice as fast as v around the
equator) its dots are ellipses, and they lie on a rigid grid. This texture keeps the paper's
construction (eqs. 5-8: a dyadic scale, re-mapped coordinates, a blend of two consecutive
scales) and changes three things:

- **one dyadic scale per texture axis** (eq. 5 with d = 1 / |grad u| and d = 1 / |grad v|): a
  tile measures between w and 2 w pixels along each axis whatever the mapping's anisotropy,
  and the two scales blend as a tensor product of eq. 8 (four terms);
- **round dots in screen space**: the distance from a sample to its dot centre is measured in
  pixels (each tile axis scaled by its screen length), and the dot function is
  ``D = 1 - A(r) / (W_u W_v)`` with A(r) the area of the W_u x W_v tile within that distance
  of its centre, so D is exactly uniform over every tile (tone preserving) for any aspect;
- **jittered placement**: every row of tiles (an iso-line of v at its level) is shifted along u
  by a random phase hashed from the row's exact v, and each dot sits off its lattice point by
  a hashed offset of up to ``jitter`` tiles per axis (D then uses the off-centre dot's area,
  still exactly uniform per tile). The rows still tile the plane and the construction stays
  nested: a row at one level is the same row, same phase, at every finer level, a dot the
  same dot (the paper's condition that minima and maxima match at consecutive scales; the
  offset is kept in tiles, so a dot drifts by half its offset per octave of zoom), and finer
  levels add rows of fresh phases between them.

The residual anisotropy: the metric uses each axis's screen length, so it is exact when the
screen images of the u and v directions are perpendicular (a UV sphere, a plane seen along an
axis) and follows the shear of the mapping otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from llvmlite import ir
from numba import types as nbtypes
from numba.extending import intrinsic

from refnpr._jit import njit
from refnpr.device.scalars import clip

from .._face import Whole, elementwise, face
from .._shading_checks import broadcast, check_positive, real, trailing
from .._validate import check_int, describe, result_dtype
from .lines import dyadic_scale_from_gradient, ldexp, level

__all__ = [
    "stipple_scales",
    "StippleToneTable",
    "stipple_tone_table",
    "stipple_threshold",
    "DEFAULT_JITTER",
    "MAX_JITTER",
]

_TABLE_TILES = 64.0
_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xBF58476D1CE4E5B9)
_M3 = np.uint64(0x94D049BB133111EB)
#: No tone table (:func:`stipple_threshold`'s ``cdf`` argument): the plain blend. Read-only,
#: as a table's ``cdf`` is, so that the kernels reading either are compiled once.
NO_TABLE = np.zeros((0, 0, 0))
NO_TABLE.setflags(write=False)


#: Default and largest dot offset, in tiles of the dot's level.
DEFAULT_JITTER = 0.2
MAX_JITTER = 0.4


def _check_jitter(jitter) -> float:
    if isinstance(jitter, (bool, np.bool_)) or not isinstance(jitter, (int, float, np.floating)):
        raise TypeError(f"jitter: expected a number in [0, {MAX_JITTER}] (tiles), got {jitter!r}")
    j = float(jitter)
    if not 0.0 <= j <= MAX_JITTER:
        raise ValueError(
            f"jitter: expected a dot offset in [0, {MAX_JITTER}] tiles (0 = lattice), got {j}"
        )
    return j


def seed_bits(seed: int) -> np.uint64:
    """The 32 seed bits the hashes mix in, as :func:`stipple_threshold`'s ``seed`` argument."""
    return np.uint64(int(seed) & 0xFFFFFFFF)


@intrinsic
def _f64_bits(typingctx, x):
    """The bits of a float64 as a uint64."""
    if x != nbtypes.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return nbtypes.uint64(nbtypes.float64), codegen


@njit
def _bits(x):
    """float64 bits as uint64, -0.0 folded onto 0.0."""
    return _f64_bits(x + 0.0)


@njit
def _mix(h):
    """splitmix64 finalizer (uint64, wrapping)."""
    h = h ^ (h >> np.uint64(30))
    h = h * _M2
    h = h ^ (h >> np.uint64(27))
    h = h * _M3
    return h ^ (h >> np.uint64(31))


@njit
def _unit(h):
    return np.float64(h >> np.uint64(11)) / 9007199254740992.0  # / 2^53: [0, 1)


@njit
def _quadrant_area(r, x_half, y_half):
    """Area of {0 <= x <= X, 0 <= y <= Y, x^2 + y^2 <= r^2}: ``int_0^min(X, r) min(Y,
    sqrt(r^2 - x^2)) dx`` in closed form."""
    m = x_half if x_half <= r else r
    q = r * r - y_half * y_half
    xc = math.sqrt(q if q >= 0.0 else 0.0)  # where the arc meets Y
    xc = xc if xc <= m else m
    q = r * r - m * m  # antiderivative of sqrt(r^2 - x^2) at m, then at xc
    root = math.sqrt(q if q >= 0.0 else 0.0)
    pm = 0.5 * (m * root + r * r * math.atan2(m, root))
    q = r * r - xc * xc
    root = math.sqrt(q if q >= 0.0 else 0.0)
    pc = 0.5 * (xc * root + r * r * math.atan2(xc, root))
    return y_half * xc + pm - pc


@njit
def _round_dot(u, v, k, a, seed, jitter):
    """Exactly uniform dot function of one level ``k = (k_u, k_v)``: 1 at the dot centre, round
    in pixels.

    The tile (W_u x W_v = ``a``) is centred on its lattice point; the dot sits ``jitter``
    tiles at most from it along each axis (offsets hashed from the dot's identity, the same at
    every level), and ``D = 1 - A(r) / (a_u a_v)`` with A(r) the tile's area within distance r
    of the dot: four quadrant areas of half-extents ``(1/2 -+ offset) a``.
    """
    ku, kv = k
    a_u, a_v = a
    big_v = ldexp(v, kv)  # eq. 6 along v: v 2^kv
    j = np.floor(big_v + 0.5)  # nearest row of dot centres
    dv = big_v - j
    v_row = ldexp(j, -kv)  # the row's exact v: the same row at every level
    phase = 0.0
    if jitter > 0:  # the row's phase: a hash of its exact v and the seed
        phase = _unit(_mix(_bits(v_row) * _M1 + seed * _M3))
    big_u = ldexp(u - phase, ku)  # eq. 6 along u, in the row's shifted lattice
    i = np.floor(big_u + 0.5)
    du = big_u - i
    ou = 0.0
    ov = 0.0
    if jitter > 0:  # the dot's offset in tiles: two hashes of its row's v and its exact u
        h = _mix(_bits(v_row) * _M1 + seed * _M3 + np.uint64(1))
        h = _mix(h ^ (_bits(ldexp(i, -ku)) * _M2))
        g = _mix(h + _M1)
        ou = jitter * (2.0 * _unit(h) - 1.0)
        ov = jitter * (2.0 * _unit(g) - 1.0)
    r = math.hypot((du - ou) * a_u, (dv - ov) * a_v)  # distance to the dot in tile pixels
    xl = (0.5 + ou) * a_u
    xr = (0.5 - ou) * a_u
    yl = (0.5 + ov) * a_v
    yr = (0.5 - ov) * a_v
    area = (
        _quadrant_area(r, xl, yl)
        + _quadrant_area(r, xr, yl)
        + _quadrant_area(r, xl, yr)
        + _quadrant_area(r, xr, yr)
    )
    return clip(1.0 - area / (a_u * a_v), 0.0, 1.0)


@njit
def _split(x, n):
    """Cell and weight of ``x`` in [0, 1] on a table axis of ``n`` cells."""
    c = clip(x, 0.0, 1.0) * n
    i = clip(np.floor(c), 0.0, n - 1.0)
    return int(i), c - i


@njit
def _stipple_threshold(u, v, s_u, s_v, seed, jitter, cdf):
    ku = level(s_u)
    tu = s_u - np.floor(s_u)
    kv = level(s_v)
    tv = s_v - np.floor(s_v)
    a_u = np.exp2(tu)  # tile width at level ku, in units of w
    a_v = np.exp2(tv)
    f = 0.0
    for bu in range(2):
        wu = tu if bu else 1.0 - tu  # eq. 8 along u
        for bv in range(2):
            wv = tv if bv else 1.0 - tv  # eq. 8 along v
            k = (ku + bu, kv + bv)
            d = _round_dot(u, v, k, (a_u / (1 + bu), a_v / (1 + bv)), seed, jitter)
            f = f + wu * wv * d
    if cdf.shape[0] > 0:  # the tone table: trilinear G(f | t_u, t_v)
        nt = cdf.shape[0] - 1
        ny = cdf.shape[2] - 1
        a, fa = _split(tu, float(nt))
        b, fb = _split(tv, float(nt))
        i, fi = _split(f, float(ny))
        out = 0.0
        for da in range(2):
            wa = fa if da else 1 - fa
            for db in range(2):
                wb = fb if db else 1 - fb
                g = cdf[a + da, b + db, i] * (1 - fi) + cdf[a + da, b + db, i + 1] * fi
                out = out + wa * wb * g
        f = out
    return clip(f, 0.0, 1.0)


def stipple_scales(duv_dx, duv_dy, w) -> tuple[np.ndarray, np.ndarray]:
    """Per-axis dyadic scales of the stipple texture: eq. 5 for u and for v separately.

    ``s_u = -log2(w |grad u|)`` and ``s_v = -log2(w |grad v|)`` (d = 1 / |grad u| is the screen
    distance between the iso-lines u and u + 1), so a tile of level floor(s) spans
    ``w 2^Frac(s)`` in [w, 2 w) pixels along each axis.

    Parameters
    ----------
    duv_dx, duv_dy : (..., 2) arrays
        Screen derivatives of the texture coordinates per pixel.
    w : float or (...) array > 0
        Dot spacing in pixels.

    Returns
    -------
    (s_u, s_v) : two (...) ndarrays; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(duv_dx, duv_dy, w)
    gx = real("duv_dx", duv_dx, dt)
    gy = real("duv_dy", duv_dy, dt)
    trailing("duv_dx", gx, 2, "texture coordinate derivatives (du, dv)")
    trailing("duv_dy", gy, 2, "texture coordinate derivatives (du, dv)")
    w = real("w", w, dt)
    check_positive("w", w, "w is the dot spacing in pixels, e.g. 6")
    broadcast(duv_dx=gx, duv_dy=gy)
    s_u = dyadic_scale_from_gradient(gx[..., 0], gy[..., 0], w)  # eq. 5 along u
    s_v = dyadic_scale_from_gradient(gx[..., 1], gy[..., 1], w)  # eq. 5 along v
    return s_u, s_v


@dataclass(frozen=True, eq=False)
class StippleToneTable:
    """Tabulated CDF of the blended stipple texture, ``cdf[a, b, i] = G(y_i | t_u, t_v)``.

    ``t_u = a / (n_t - 1)``, ``t_v = b / (n_t - 1)``, ``y_i = i / (n_y - 1)``. Corners (integer
    scales) are the identity: D is exactly uniform there.

    Attributes
    ----------
    cdf : (n_t, n_t, n_y) float64 ndarray, non-decreasing along y, 0 at y = 0 and 1 at y = 1.
    jitter : float
        The placement it was measured for.
    """

    cdf: np.ndarray
    jitter: float


def stipple_tone_table(
    *,
    jitter: float = DEFAULT_JITTER,
    n_t: int = 9,
    n_y: int = 129,
    samples: int = 160,
    seed: int = 0,
) -> StippleToneTable:
    """Build the :class:`StippleToneTable` from ``samples**2`` random points over 64 x 64 tiles.

    The tensor blend of eq. 8 is not uniform between integer scales (as for lines and for
    :func:`dot_tone_table`); its CDF depends only on (t_u, t_v) and is tabulated here. The
    defaults take about 1 s; the corrected texture is uniform to about 0.01 (0.02 over a few
    dozen tiles, the spread of the random row phases).

    Parameters
    ----------
    jitter : float in [0, MAX_JITTER], keyword-only
        Placement as in :func:`stipple_threshold`.
    n_t, n_y : int >= 2, keyword-only
        Table resolution in each t and in the threshold value y.
    samples : int >= 16, keyword-only
        ``samples**2`` points (seeded) over 64 x 64 tiles of the coarse level.
    seed : int, keyword-only
        Seed of the sample points and row phases (any seed has the same statistics).

    Returns
    -------
    StippleToneTable
    """
    jitter = _check_jitter(jitter)
    n_t = check_int("n_t", n_t, lo=2)
    n_y = check_int("n_y", n_y, lo=2)
    samples = check_int("samples", samples, lo=16)
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0.0, _TABLE_TILES, (2, samples * samples))  # many rows of random phase
    y = np.linspace(0.0, 1.0, n_y)
    ts = np.linspace(0.0, 1.0, n_t)
    cdf = np.empty((n_t, n_t, n_y))
    bits = seed_bits(seed)
    for a, t_u in enumerate(ts):
        for b, t_v in enumerate(ts):
            s_u = min(t_u, 1.0 - 1e-12)
            s_v = min(t_v, 1.0 - 1e-12)
            f = elementwise(
                _stipple_threshold, np.float64, u, v, s_u, s_v, bits, jitter, Whole(NO_TABLE)
            )
            cdf[a, b] = np.searchsorted(np.sort(f), y, side="right") / f.size
    for a in (0, n_t - 1):
        for b in (0, n_t - 1):
            cdf[a, b] = y
    cdf[..., 0] = 0.0
    cdf[..., -1] = 1.0
    cdf.setflags(write=False)
    return StippleToneTable(cdf=cdf, jitter=jitter)


@face(_stipple_threshold)
def stipple_threshold(
    uv,
    s_u,
    s_v,
    *,
    jitter: float = DEFAULT_JITTER,
    seed: int = 0,
    tone_table: StippleToneTable | None = None,
) -> np.ndarray:
    """Screen-round jittered multi-scale stipple threshold texture (see the module docstring).

    ``F = sum_{b_u, b_v in {0, 1}} w(b_u, t_u) w(b_v, t_v) D_{k_u + b_u, k_v + b_v}`` with
    ``k = floor(s)``, ``t = Frac(s)`` per axis, ``w(0, t) = 1 - t``, ``w(1, t) = t`` (eq. 8 on
    each axis) and D the exactly uniform round dot of each level. Black (``x < F``) is a round
    dot around each centre that grows with darkness; no jump where either scale crosses an
    integer. With ``tone_table`` the blend is made uniform at every (t_u, t_v).

    Parameters
    ----------
    uv : (..., 2) array
        Texture coordinates (one dot per texture unit and axis at scale 0).
    s_u, s_v : (...) arrays
        Per-axis dyadic scales, e.g. :func:`stipple_scales`; broadcast against ``uv[..., 0]``.
    jitter : float in [0, MAX_JITTER], keyword-only
        Placement: rows of dots at random phases along u, and each dot up to ``jitter`` tiles
        off its lattice point along each axis (0: every level's dots on a rectangular
        lattice). A dot keeps its offset in tiles of the current level, so it stays the same
        dot across scales and drifts towards its lattice point by half its offset per octave
        of zoom; dots are round up to an ink fraction of about pi (1/2 - jitter)^2.
    seed : int, keyword-only
        Seed of the row phases; its low 32 bits (:func:`seed_bits`): seeds equal modulo 2**32
        give the same dots.
    tone_table : StippleToneTable or None, keyword-only
        From :func:`stipple_tone_table` with the same ``jitter``; None keeps the plain blend.

    Returns
    -------
    (...) ndarray in [0, 1]; float64, or float32 if the inputs are float32.
    """
    if tone_table is not None and not isinstance(tone_table, StippleToneTable):
        raise TypeError(
            "tone_table: expected a StippleToneTable from stipple_tone_table(), "
            f"got {describe(tone_table)}"
        )
    jitter = _check_jitter(jitter)
    if tone_table is not None and tone_table.jitter != jitter:
        raise ValueError(
            f"tone_table: built for jitter={tone_table.jitter}, used with jitter={jitter}; "
            "build it with stipple_tone_table(jitter=...) matching the texture"
        )
    seed = check_int("seed", seed)
    dt = result_dtype(uv, s_u, s_v)
    uv = real("uv", uv, dt)
    trailing("uv", uv, 2, "texture coordinates (u, v)")
    s_u = real("s_u", s_u, dt)
    s_v = real("s_v", s_v, dt)
    broadcast(uv_u=uv[..., 0], s_u=s_u, s_v=s_v)
    cdf = NO_TABLE if tone_table is None else tone_table.cdf
    return elementwise(
        stipple_threshold.scalar, dt, uv[..., 0], uv[..., 1], s_u, s_v, seed_bits(seed), jitter,
        Whole(np.ascontiguousarray(cdf, dtype=np.float64)),
    )  # fmt: skip
