"""Determinism: bit-identical buffers across numba thread counts, tile sizes and repeated calls;
supersampled coverage is the exact sample fraction."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from refnpr.raster import rasterize

from .meshes import icosphere
from .scenes import BUILTIN_CHANNELS, HEAT_CHANNELS, SCENES

CHANNELS = BUILTIN_CHANNELS + HEAT_CHANNELS


def _render(scene_name: str, **kwargs):
    scene = SCENES[scene_name]()
    kwargs.setdefault("spp", 4)
    return rasterize(
        scene.meshes,
        scene.camera,
        2 * scene.width,
        2 * scene.height,
        CHANNELS,
        texture_size=(128, 128),
        dtype=np.float64,
        **kwargs,
    )


def _assert_identical(a, b, label):
    assert sorted(a) == sorted(b)
    for name in a:
        x, y = a[name], b[name]
        assert x.dtype == y.dtype and x.shape == y.shape, f"{label}: {name}"
        # bitwise: compare the raw bytes (NaN payloads and signed zeros included)
        assert x.tobytes() == y.tobytes(), f"{label}: channel {name!r} differs"


@pytest.mark.parametrize("scene_name", ["mixed", "near_clip", "grazing"])
def test_bit_identical_for_one_and_two_threads(scene_name):
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = _render(scene_name)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = _render(scene_name)
    finally:
        numba.set_num_threads(before)
    _assert_identical(one, two, "threads 1 vs 2")


@pytest.mark.parametrize("scene_name", ["mixed", "near_clip"])
def test_bit_identical_across_tile_sizes_and_repeats(scene_name):
    ref = _render(scene_name, tile=32)
    _assert_identical(ref, _render(scene_name, tile=32), "repeat")
    for tile in (8, 16, 64):
        _assert_identical(ref, _render(scene_name, tile=tile), f"tile {tile} vs 32")


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("spp", [4, 9, 16])
def test_coverage_is_the_exact_fraction_of_covered_samples(spp, dtype):
    """coverage[y, x] = k / n^2 (correctly rounded) for k covered samples of the pixel: the mean
    of the sample grid, so box-resolving tri_id >= 0 and reading coverage agree bit for bit."""
    n = int(round(spp**0.5))
    scene = SCENES["close_sphere"]()
    gb = rasterize(scene.meshes, scene.camera, 40, 30, ("tri_id", "coverage"), spp, dtype=dtype)
    k = (gb["tri_id"] >= 0).reshape(30, n, 40, n).sum(axis=(1, 3))
    expect = (k / (n * n)).astype(dtype)
    assert gb["coverage"].dtype == dtype
    assert 0 < np.count_nonzero((k > 0) & (k < n * n)), "needs partially covered pixels"
    bad = np.argwhere(gb["coverage"] != expect)
    assert bad.size == 0, (
        f"coverage is not k / {n * n} at {len(bad)} pixels, e.g. {tuple(bad[0])}: k = "
        f"{k[tuple(bad[0])]}, expected {expect[tuple(bad[0])]!r}, got {gb['coverage'][tuple(bad[0])]!r}"
    )


def test_float32_buffers_are_the_float64_buffers_rounded():
    """dtype only changes the storage: float32 channels equal the float64 ones rounded to
    float32 (to one float32 ulp; lod/dyadic_scale are derived from rounded derivatives)."""
    mesh = icosphere(2)
    scene = SCENES["close_sphere"]()
    kw = dict(texture_size=64, spp=4)
    f64 = rasterize(mesh, scene.camera, 30, 30, CHANNELS[:-3], dtype=np.float64, **kw)
    f32 = rasterize(mesh, scene.camera, 30, 30, CHANNELS[:-3], dtype=np.float32, **kw)
    np.testing.assert_array_equal(f32["tri_id"], f64["tri_id"])
    covered = f64["tri_id"] >= 0
    for name in f64:
        if f64[name].dtype.kind != "f":
            continue
        assert f32[name].dtype == np.float32, name
        if name == "coverage":  # per pixel
            a, b = f32[name], f64[name]
        else:
            a, b = f32[name][covered], f64[name][covered]
        ulp = np.spacing(np.abs(b).astype(np.float32)).astype(np.float64)
        if name in ("lod", "dyadic_scale"):  # log2 of float32-rounded derivatives
            ulp = ulp + 2.0**-22
        err = np.abs(a.astype(np.float64) - b)
        assert np.all(err <= ulp), f"{name}: {np.max(err / ulp):.3g} float32 ulp off"
