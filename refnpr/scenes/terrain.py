"""A procedural height field: fractal gradient noise with a quintic fade (seeded).

Each octave is Perlin's gradient noise (improved 2002 form: the quintic fade
``f(t) = 6 t^5 - 15 t^4 + 10 t^3``, so heights are C2 and normals C1 across lattice lines)
with unit gradients at uniformly random angles, and its lattice is rotated by a random angle
and shifted by a random offset, so no octave's lattice lines line up with another's or with
the mesh grid. The earlier sum of plane waves (``noise="waves"``) is kept for comparison: its
ridges are straight lines across the whole terrain.
"""

from __future__ import annotations

import numpy as np

from ..raster import Mesh
from ._params import check_grid, check_int, check_real
from ._topology import grid_faces, unit

__all__ = ["NOISE_KINDS", "terrain", "terrain_height"]

#: Height functions :func:`terrain` accepts as ``noise``.
NOISE_KINDS = ("gradient", "waves")

_TABLE = 256  # lattice hash period (cells) and number of gradient directions
_CELLS = 3.0  # lattice cells across ``size`` in the lowest octave


def _waves(seed: int, octaves: int, size: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wave vectors k (W, 2), amplitudes a (W,) and phases (W,): 3 waves per octave, frequency
    doubling and amplitude halving per octave, the lowest wavelength the whole ``size``."""
    rng = np.random.default_rng(seed)
    per = 3
    octave = np.repeat(np.arange(octaves), per)
    angle = rng.uniform(0.0, 2.0 * np.pi, octave.size)
    freq = (2.0 * np.pi / size) * 2.0**octave * rng.uniform(0.8, 1.25, octave.size)
    k = freq[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    a = 0.5**octave / (per * np.sum(0.5 ** np.arange(octaves)))  # sum(a) = 1: |h| <= height
    phase = rng.uniform(0.0, 2.0 * np.pi, octave.size)
    return k, a, phase


def _wave_height(x, z, *, size, height, octaves, seed):
    k, a, phase = _waves(seed, octaves, size)
    arg = x[..., None] * k[:, 0] + z[..., None] * k[:, 1] + phase
    h = height * np.sum(a * np.sin(arg), axis=-1)
    c = height * a * np.cos(arg)
    return h, np.sum(c * k[:, 0], axis=-1), np.sum(c * k[:, 1], axis=-1)


def _fade(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quintic fade ``6 t^5 - 15 t^4 + 10 t^3`` and its derivative ``30 t^2 (t - 1)^2``."""
    return t * t * t * (t * (6.0 * t - 15.0) + 10.0), 30.0 * t * t * (t - 1.0) ** 2


def _gradient_noise(
    x: np.ndarray, y: np.ndarray, perm: np.ndarray, grad: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2D gradient noise at lattice coordinates ``(x, y)`` and its gradient, scaled by
    ``sqrt(2)`` to [-1, 1] (unit-gradient noise is bounded by ``sqrt(2) / 2``); ``perm``
    (_TABLE,) is the hash permutation and ``grad`` (_TABLE, 2) the unit gradients."""
    xf, yf = np.floor(x), np.floor(y)
    i, j = xf.astype(np.int64) % _TABLE, yf.astype(np.int64) % _TABLE
    fx, fy = x - xf, y - yf
    corner = {}
    for a in (0, 1):
        for b in (0, 1):
            g = grad[perm[(perm[(i + a) % _TABLE] + j + b) % _TABLE]]
            gx, gy = g[..., 0], g[..., 1]
            corner[a, b] = (gx * (fx - a) + gy * (fy - b), gx, gy)
    u, du = _fade(fx)
    v, dv = _fade(fy)
    (n00, g00x, g00y), (n10, g10x, g10y) = corner[0, 0], corner[1, 0]
    (n01, g01x, g01y), (n11, g11x, g11y) = corner[0, 1], corner[1, 1]
    k1, k2, k3 = n10 - n00, n01 - n00, n00 - n10 - n01 + n11
    n = n00 + u * k1 + v * k2 + u * v * k3  # bilinear blend of the corner ramps
    dx = g00x + u * (g10x - g00x) + v * (g01x - g00x) + u * v * (g00x - g10x - g01x + g11x)
    dy = g00y + u * (g10y - g00y) + v * (g01y - g00y) + u * v * (g00y - g10y - g01y + g11y)
    dx = dx + du * (k1 + v * k3)
    dy = dy + dv * (k2 + u * k3)
    s = np.sqrt(2.0)
    return s * n, s * dx, s * dy


def _fractal_height(x, z, *, size, height, octaves, seed):
    rng = np.random.default_rng(seed)
    total_h, total_x, total_z = (np.zeros(np.shape(x)) for _ in range(3))
    a_sum = np.sum(0.5 ** np.arange(octaves))
    for o in range(octaves):
        perm = rng.permutation(_TABLE).astype(np.int64)
        angle = rng.uniform(0.0, 2.0 * np.pi, _TABLE)
        grad = np.stack([np.cos(angle), np.sin(angle)], axis=1)
        theta = rng.uniform(0.0, 2.0 * np.pi)
        offset = rng.uniform(0.0, _TABLE, 2)
        c, s = np.cos(theta), np.sin(theta)
        f = _CELLS * 2.0**o / size  # lattice cells per world unit
        lx = f * (c * x - s * z) + offset[0]  # rotated, scaled, shifted lattice coordinates
        ly = f * (s * x + c * z) + offset[1]
        n, nx, ny = _gradient_noise(lx, ly, perm, grad)
        a = height * 0.5**o / a_sum  # sum of amplitudes = height: |h| <= height
        total_h += a * n
        total_x += a * f * (c * nx + s * ny)  # chain rule through the rotation
        total_z += a * f * (-s * nx + c * ny)
    return total_h, total_x, total_z


def terrain_height(
    x: np.ndarray,
    z: np.ndarray,
    *,
    size: float,
    height: float,
    octaves: int,
    seed: int,
    noise: str = "gradient",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Height ``h(x, z)`` of :func:`terrain` and its analytic gradient.

    ``noise="gradient"``: ``h = height * sum_o a_o N_o(R_o (x, z) 2^o c / size + t_o)``, with
    ``N_o`` unit-gradient noise scaled to [-1, 1], ``a_o`` proportional to ``2^-o`` and summing
    to 1, ``R_o`` a random rotation, ``t_o`` a random shift, ``c = 3`` lattice cells across
    ``size`` in the lowest octave. ``noise="waves"``: ``h = height * sum_w a_w sin(k_w . (x, z) +
    phase_w)``, three plane waves per octave.

    Parameters
    ----------
    x, z : float64 arrays of one shape
        World coordinates.
    size, height : float
    octaves, seed : int
    noise : {"gradient", "waves"}

    Returns
    -------
    h, dh_dx, dh_dz : float64 arrays shaped like ``x``
        ``|h| <= height``.
    """
    if noise not in NOISE_KINDS:
        raise ValueError(
            f"noise: unknown height function {noise!r}; expected one of {', '.join(NOISE_KINDS)}"
        )
    x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
    fn = _fractal_height if noise == "gradient" else _wave_height
    return fn(x, z, size=size, height=height, octaves=octaves, seed=seed)


def terrain(
    size: float = 10.0,
    n: int = 128,
    height: float = 1.0,
    octaves: int = 4,
    seed: int = 0,
    noise: str = "gradient",
) -> Mesh:
    """A square height-field terrain ``y = h(x, z)`` over ``[-size/2, size/2]^2``.

    Parameters
    ----------
    size : float
        Side length (> 0).
    n : int
        Grid segments per side (>= 1); ``2 n^2`` triangles.
    height : float
        Amplitude scale (>= 0); |h| <= height.
    octaves : int
        Number of frequency octaves (1..16).
    seed : int
        Seed of the noise lattices (or wave directions and phases), ``numpy.random.default_rng``.
    noise : {"gradient", "waves"}
        The height function (see :func:`terrain_height`): fractal gradient noise with a quintic
        fade (default), or the older sum of plane waves, whose straight ridges cross the whole
        terrain.

    Returns
    -------
    Mesh
        Faces counter-clockwise seen from above; analytic normals ``(-h_x, 1, -h_z)`` normalized;
        uv in [0, 1]^2 with u along +x and v towards -z. Not closed.
    """
    size = check_real("size", size, positive=True)
    n = check_int("n", n, minimum=1)
    check_grid((n + 1) ** 2, {"n": n})
    height = check_real("height", height, nonnegative=True)
    octaves = check_int("octaves", octaves, minimum=1, maximum=16)
    seed = check_int("seed", seed, minimum=0)
    a = np.arange(n + 1) / n
    x = size * (a - 0.5)
    z = size * (0.5 - a)
    zz, xx = np.meshgrid(z, x, indexing="ij")  # rows go towards -z, columns towards +x
    h, hx, hz = terrain_height(
        xx, zz, size=size, height=height, octaves=octaves, seed=seed, noise=noise
    )
    positions = np.stack([xx, h, zz], axis=-1).reshape(-1, 3)
    normals = unit(np.stack([-hx, np.ones_like(h), -hz], axis=-1)).reshape(-1, 3)
    vv, uu = np.meshgrid(a, a, indexing="ij")
    uv = np.stack([uu, vv], axis=-1).reshape(-1, 2)
    faces = grid_faces(n, n)  # d/dcol x d/drow = (+x) x (-z) = +y
    return Mesh(positions, faces, normals, uv, name="terrain")
