"""A procedural height field: sums of plane waves with random directions (seeded)."""

from __future__ import annotations

import numpy as np

from ..raster import Mesh
from ._params import check_int, check_real
from ._topology import grid_faces, unit

__all__ = ["terrain", "terrain_height"]


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


def terrain_height(
    x: np.ndarray, z: np.ndarray, *, size: float, height: float, octaves: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Height ``h(x, z) = height * sum_w a_w sin(k_w . (x, z) + phase_w)`` and its gradient.

    Returns
    -------
    h, dh_dx, dh_dz : arrays shaped like ``x``
    """
    k, a, phase = _waves(seed, octaves, size)
    arg = x[..., None] * k[:, 0] + z[..., None] * k[:, 1] + phase
    h = height * np.sum(a * np.sin(arg), axis=-1)
    c = height * a * np.cos(arg)
    return h, np.sum(c * k[:, 0], axis=-1), np.sum(c * k[:, 1], axis=-1)


def terrain(
    size: float = 10.0,
    n: int = 128,
    height: float = 1.0,
    octaves: int = 4,
    seed: int = 0,
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
        Number of frequency octaves (>= 1).
    seed : int
        Seed of the wave directions and phases (``numpy.random.default_rng``).

    Returns
    -------
    Mesh
        Faces counter-clockwise seen from above; analytic normals ``(-h_x, 1, -h_z)`` normalized;
        uv in [0, 1]^2 with u along +x and v towards -z. Not closed.
    """
    size = check_real("size", size, positive=True)
    n = check_int("n", n, minimum=1)
    height = check_real("height", height, nonnegative=True)
    octaves = check_int("octaves", octaves, minimum=1, maximum=16)
    seed = check_int("seed", seed, minimum=0)
    a = np.arange(n + 1) / n
    x = size * (a - 0.5)
    z = size * (0.5 - a)
    zz, xx = np.meshgrid(z, x, indexing="ij")  # rows go towards -z, columns towards +x
    h, hx, hz = terrain_height(xx, zz, size=size, height=height, octaves=octaves, seed=seed)
    positions = np.stack([xx, h, zz], axis=-1).reshape(-1, 3)
    normals = unit(np.stack([-hx, np.ones_like(h), -hz], axis=-1)).reshape(-1, 3)
    vv, uu = np.meshgrid(a, a, indexing="ij")
    uv = np.stack([uu, vv], axis=-1).reshape(-1, 2)
    faces = grid_faces(n, n)  # d/dcol x d/drow = (+x) x (-z) = +y
    return Mesh(positions, faces, normals, uv, name="terrain")
