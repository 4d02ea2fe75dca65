"""Terrain height field: no straight ridges (an isotropic spectrum), smooth normals across the
noise lattice, and the parameter checks of the height function."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.scenes import terrain, terrain_height


def _angular_energy(noise: str, seed: int, *, size: float = 10.0, n: int = 512) -> np.ndarray:
    """Fraction of the height field's (windowed) spectral energy in 36 orientation bins of 5
    degrees, over a square six terrain sizes across (DC excluded)."""
    t = np.linspace(-3.0 * size, 3.0 * size, n, endpoint=False)
    x, z = np.meshgrid(t, t)
    h = terrain_height(x, z, size=size, height=1.0, octaves=3, seed=seed, noise=noise)[0]
    w = np.hanning(n)
    power = np.abs(np.fft.fft2((h - h.mean()) * w[:, None] * w[None, :])) ** 2
    f = np.fft.fftfreq(n)
    fx, fz = np.meshgrid(f, f)
    keep = np.hypot(fx, fz) > 2.0 / n
    angle = np.degrees(np.arctan2(fz, fx)) % 180.0
    bins = np.histogram(angle[keep], bins=36, range=(0.0, 180.0), weights=power[keep])[0]
    return bins / bins.sum()


def _top4(bins: np.ndarray) -> float:
    return float(np.sort(bins)[-4:].sum())


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_plane_waves_concentrate_energy_in_few_orientations(seed):
    """The measure below can fail: the old height (plane waves) puts > 40% of its energy into 4
    of 36 orientation bins (its straight ridges and stripes)."""
    assert _top4(_angular_energy("waves", seed)) > 0.4


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_terrain_spectrum_is_isotropic_and_not_grid_aligned(seed):
    bins = _angular_energy("gradient", seed)
    assert _top4(bins) < 0.3  # uniform: 4/36 = 0.11; plane waves: > 0.4
    # the mesh grid's axes (0 and 90 degrees) carry no more than their share
    axes = (bins[0] + bins[-1] + bins[17] + bins[18]) / 4.0
    assert axes < 1.5 * bins.mean()


def test_terrain_normals_are_c1_across_lattice_lines():
    """With the quintic fade the normal field is C1: second differences of the gradient along a
    densely sampled line shrink as the step squared (ratio 4 when the step halves). A crease
    (a jump of h's second derivative, as the cubic fade gives at lattice lines) shrinks only as
    the step (measured: 2.5 with the cubic fade, 1.0 with a linear one)."""
    kw = dict(size=10.0, height=1.0, octaves=1, seed=5)
    peaks = []
    for step in (2e-3, 1e-3):  # the line crosses ~8 lattice lines of the octave (3 per size)
        s = np.arange(-5.0, 5.0, step)
        _, hx, hz = terrain_height(0.83 * s, 0.31 * s + 0.1, **kw)
        peaks.append((np.abs(np.diff(hx, 2)) + np.abs(np.diff(hz, 2))).max())
    assert peaks[0] / peaks[1] > 3.5


def test_terrain_bounds_and_default_is_gradient_noise():
    m = terrain(size=12.0, n=64, height=0.9, octaves=5, seed=7)
    assert np.abs(m.positions[:, 1]).max() <= 0.9
    h = terrain_height(
        m.positions[:, 0], m.positions[:, 2], size=12.0, height=0.9, octaves=5, seed=7
    )[0]
    assert np.array_equal(h, m.positions[:, 1])
    waves = terrain(size=12.0, n=64, height=0.9, octaves=5, seed=7, noise="waves")
    assert not np.allclose(waves.positions[:, 1], m.positions[:, 1])


@pytest.mark.parametrize("noise", ["perlin", 3])
def test_terrain_noise_validation(noise):
    with pytest.raises(ValueError, match=r"noise: unknown height function .*gradient, waves"):
        terrain(n=4, noise=noise)
