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

Public names are re-exported by :mod:`refnpr.formulas.threshold`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shading_checks import broadcast, check_positive, real, trailing
from .._validate import check_int, describe, result_dtype
from .lines import dyadic_scale_from_gradient, scale_split

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


def _mix(h: np.ndarray) -> np.ndarray:
    """splitmix64 finalizer on uint64 arrays."""
    with np.errstate(over="ignore"):
        h = h ^ (h >> np.uint64(30))
        h = h * _M2
        h = h ^ (h >> np.uint64(27))
        h = h * _M3
        h = h ^ (h >> np.uint64(31))
    return h


def _bits(x) -> np.ndarray:
    """float64 bits as uint64 (-0.0 folded onto 0.0)."""
    return np.ascontiguousarray(np.asarray(x, dtype=np.float64) + 0.0).view(np.uint64)


def _unit(h: np.ndarray) -> np.ndarray:
    return (h >> np.uint64(11)).astype(np.float64) / float(2**53)


def _row_phase(v_row: np.ndarray, seed: int) -> np.ndarray:
    """Hash of a row's exact v and the seed to a phase in [0, 1) texture units."""
    with np.errstate(over="ignore"):
        h = _bits(v_row) * _M1 + np.uint64(seed & 0xFFFFFFFF) * _M3
    return _unit(_mix(h))


def _dot_offsets(v_row: np.ndarray, u_dot: np.ndarray, seed: int) -> tuple:
    """Two hashes in [0, 1) of a dot's identity (its row's v, its exact lattice u)."""
    with np.errstate(over="ignore"):
        h = _mix(_bits(v_row) * _M1 + np.uint64(seed & 0xFFFFFFFF) * _M3 + np.uint64(1))
        h = _mix(h ^ (_bits(u_dot) * _M2))
        g = _mix(h + _M1)
    return _unit(h), _unit(g)


def _quadrant_area(r: np.ndarray, x_half: np.ndarray, y_half: np.ndarray) -> np.ndarray:
    """Area of {0 <= x <= X, 0 <= y <= Y, x^2 + y^2 <= r^2}: ``int_0^min(X, r) min(Y,
    sqrt(r^2 - x^2)) dx`` in closed form."""
    m = np.minimum(x_half, r)
    xc = np.minimum(np.sqrt(np.maximum(r * r - y_half * y_half, 0.0)), m)  # where the arc meets Y

    def prim(x):  # antiderivative of sqrt(r^2 - x^2)
        root = np.sqrt(np.maximum(r * r - x * x, 0.0))
        return 0.5 * (x * root + r * r * np.arctan2(x, root))

    return y_half * xc + prim(m) - prim(xc)


def _round_dot(u, v, ku, kv, a_u, a_v, seed, jitter):
    """Exactly uniform dot function of one level: 1 at the dot centre, round in pixels.

    The tile (W_u x W_v = a_u x a_v) is centred on its lattice point; the dot sits ``jitter``
    tiles at most from it along each axis (offsets hashed from the dot's identity, the same at
    every level), and ``D = 1 - A(r) / (a_u a_v)`` with A(r) the tile's area within distance r
    of the dot: four quadrant areas of half-extents ``(1/2 -+ offset) a``.
    """
    big_v = np.ldexp(v, kv)  # eq. 6 along v: v 2^kv
    j = np.floor(big_v + 0.5)  # nearest row of dot centres
    dv = big_v - j
    v_row = np.ldexp(j, -kv)  # the row's exact v: the same row at every level
    phase = _row_phase(v_row, seed) if jitter > 0 else 0.0
    big_u = np.ldexp(u - phase, ku)  # eq. 6 along u, in the row's shifted lattice
    i = np.floor(big_u + 0.5)
    du = big_u - i
    if jitter > 0:
        hu, hv = _dot_offsets(v_row, np.ldexp(i, -ku), seed)
        ou = jitter * (2.0 * hu - 1.0)  # dot offset in tiles
        ov = jitter * (2.0 * hv - 1.0)
    else:
        ou = ov = 0.0
    r = np.hypot((du - ou) * a_u, (dv - ov) * a_v)  # distance to the dot in tile pixels
    xl, xr = (0.5 + ou) * a_u, (0.5 - ou) * a_u
    yl, yr = (0.5 + ov) * a_v, (0.5 - ov) * a_v
    area = (
        _quadrant_area(r, xl, yl)
        + _quadrant_area(r, xr, yl)
        + _quadrant_area(r, xl, yr)
        + _quadrant_area(r, xr, yr)
    )
    return np.clip(1.0 - area / (a_u * a_v), 0.0, 1.0)


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


def _blend(u, v, s_u, s_v, seed, jitter):
    """Tensor-product eq. 8 over the two axes' consecutive scales (float64)."""
    ku, tu = scale_split(s_u)
    kv, tv = scale_split(s_v)
    a_u = np.exp2(tu)  # tile width at level ku, in units of w
    a_v = np.exp2(tv)
    f = np.zeros(np.broadcast(u, v, s_u, s_v).shape)
    for bu in (0, 1):
        wu = tu if bu else 1.0 - tu  # eq. 8 along u
        for bv in (0, 1):
            wv = tv if bv else 1.0 - tv  # eq. 8 along v
            d = _round_dot(u, v, ku + bu, kv + bv, a_u / (1 + bu), a_v / (1 + bv), seed, jitter)
            f = f + wu * wv * d
    return f, tu, tv


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
    for a, t_u in enumerate(ts):
        for b, t_v in enumerate(ts):
            s_u = np.full(u.shape, min(t_u, 1.0 - 1e-12))
            s_v = np.full(u.shape, min(t_v, 1.0 - 1e-12))
            f, _, _ = _blend(u, v, s_u, s_v, seed, jitter)
            cdf[a, b] = np.searchsorted(np.sort(f), y, side="right") / f.size
    for a in (0, n_t - 1):
        for b in (0, n_t - 1):
            cdf[a, b] = y
    cdf[..., 0] = 0.0
    cdf[..., -1] = 1.0
    cdf.setflags(write=False)
    return StippleToneTable(cdf=cdf, jitter=jitter)


def _apply(table: StippleToneTable, f: np.ndarray, tu: np.ndarray, tv: np.ndarray) -> np.ndarray:
    """Trilinear lookup of G(f | t_u, t_v)."""
    c = table.cdf
    nt, ny = c.shape[0] - 1, c.shape[2] - 1

    def split(x, n):
        x = np.clip(x, 0.0, 1.0) * n
        i = np.clip(np.floor(x), 0, n - 1).astype(np.intp)
        return i, x - i

    a, fa = split(tu, nt)
    b, fb = split(tv, nt)
    i, fi = split(f, ny)
    out = 0.0
    for da, wa in ((0, 1 - fa), (1, fa)):
        for db, wb in ((0, 1 - fb), (1, fb)):
            g = c[a + da, b + db, i] * (1 - fi) + c[a + da, b + db, i + 1] * fi
            out = out + wa * wb * g
    return out


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
        Seed of the row phases.
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
    u = uv[..., 0].astype(np.float64)
    v = uv[..., 1].astype(np.float64)
    f, tu, tv = _blend(u, v, s_u.astype(np.float64), s_v.astype(np.float64), seed, jitter)
    if tone_table is not None:
        f = _apply(tone_table, f, tu, tv)
    return np.asarray(np.clip(f, 0.0, 1.0), dtype=dt)
