"""Smooth value noise in texture space for the noise-modulated lines of Veryovka sec. 3.2.

The paper only says that "the multi-scale textures can be modified by a noise function"; the
formula layer takes the noise as a phase shift in line periods (``line_threshold(noise=...)``).
This module supplies a deterministic, seedable, smooth field for it: value noise on the integer
lattice (an integer hash of the lattice point and the seed), quintic interpolation, two octaves.
"""

from __future__ import annotations

import numpy as np

__all__ = ["value_noise"]

_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xBF58476D1CE4E5B9)
_M3 = np.uint64(0x94D049BB133111EB)
_MASK53 = (1 << 53) - 1


def _hash01(i: np.ndarray, j: np.ndarray, seed: int) -> np.ndarray:
    """Uniform [0, 1) value per lattice point (i, j) (int64 arrays): splitmix64 of i, j, seed."""
    with np.errstate(over="ignore"):
        h = i.astype(np.uint64) * _M1
        h ^= j.astype(np.uint64) * _M2 + np.uint64(seed & 0xFFFFFFFF) * _M3
        h ^= h >> np.uint64(30)
        h *= _M2
        h ^= h >> np.uint64(27)
        h *= _M3
        h ^= h >> np.uint64(31)
    return (h >> np.uint64(11)).astype(np.float64) / float(_MASK53 + 1)


def _fade(x: np.ndarray) -> np.ndarray:
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)  # C2 quintic, fade(0) = 0, fade(1) = 1


def _octave(p: np.ndarray, seed: int) -> np.ndarray:
    i = np.floor(p).astype(np.int64)
    f = p - i
    wu, wv = _fade(f[..., 0]), _fade(f[..., 1])
    i0, j0 = i[..., 0], i[..., 1]
    h00 = _hash01(i0, j0, seed)
    h10 = _hash01(i0 + 1, j0, seed)
    h01 = _hash01(i0, j0 + 1, seed)
    h11 = _hash01(i0 + 1, j0 + 1, seed)
    top = h00 + wu * (h10 - h00)
    bottom = h01 + wu * (h11 - h01)
    return top + wv * (bottom - top)


def value_noise(p: np.ndarray, *, seed: int = 0) -> np.ndarray:
    """Two-octave smooth value noise in [-1, 1].

    Parameters
    ----------
    p : (..., 2) float64
        Position in noise cells (one lattice cell per unit).
    seed : int, keyword-only
        Different seeds give independent fields.

    Returns
    -------
    (...) float64 in [-1, 1]; C2 continuous in p, 0 on average.
    """
    p = np.asarray(p, dtype=np.float64)
    n = _octave(p, seed) + 0.5 * _octave(2.0 * p + 17.0, seed + 1)
    return (n / 1.5) * 2.0 - 1.0
