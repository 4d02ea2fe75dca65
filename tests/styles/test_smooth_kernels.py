"""Smooth shading's kernel (``lit._kernels.shade_smooth_for``): f_s = base ** k by multiplications
for integer shininess, checked against pow. Oracles: the numpy shade() of
tests/styles/test_shade_kernels.py and the same kernel with pow for every f_s (``pow_int=False``),
exact float32 equality; the fallback to pow forced by an inflated error bound; 1 vs 2 numba
threads."""

from __future__ import annotations

from types import SimpleNamespace

import numba
import numpy as np
import pytest

from refnpr._jit import Banded
from refnpr.scenes.scene import Light, Material
from refnpr.styles.base import ShadeContext
from refnpr.styles.lit import _kernels as K
from refnpr.styles.lit.shading import lit_rgba
from refnpr.styles.smooth import SmoothStyle

from .test_shade_kernels import LIGHTS, oracle_smooth


def shiny_ctx(seed: int, lights: str, shape=(67, 91)) -> ShadeContext:
    """Random unit normals facing the eye's side, positions near the origin, objects with
    integer shininess up to 1024 (the multiplication path) and one fractional (pow)."""
    rng = np.random.default_rng(seed)
    n = rng.standard_normal(shape + (3,))
    n[..., 2] = np.abs(n[..., 2])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    pos = rng.uniform(-1.0, 1.0, shape + (3,))
    mats = [
        Material(diffuse=(0.6, 0.5, 0.4), specular=(0.5, 0.5, 0.5), shininess=float(p))
        for p in (1, 2, 40, 97, 256, 1024, 12.5)
    ]
    mesh_id = rng.integers(-1, len(mats), shape).astype(np.int32)
    gb = {"normal": n.astype(np.float32), "position": pos.astype(np.float32), "mesh_id": mesh_id}
    scene = SimpleNamespace(
        objects=[SimpleNamespace(material=m) for m in mats],
        lights=LIGHTS[lights],
        ambient=(0.1, 0.1, 0.1),
        camera=SimpleNamespace(eye=(0.2, 0.4, 3.0)),
    )
    return ShadeContext(gb, scene)


def pow_kernel(ctx: ShadeContext, model: str) -> np.ndarray:
    """The same frame with libm's pow for every f_s."""
    style = SmoothStyle(model=model)
    return lit_rgba(ctx, style.PARAMS.record(style.p), smooth=True, pow_int=False)


def same_bits(a: np.ndarray, b: np.ndarray) -> None:
    bad = np.argwhere(np.any(a.view(np.uint32) != b.view(np.uint32), axis=-1))
    assert bad.size == 0, f"{len(bad)} samples differ, first at {bad[:3].tolist()}"


@pytest.mark.parametrize("model", ["blinn-phong", "phong"])
@pytest.mark.parametrize("lights", sorted(LIGHTS))
def test_multiplications_equal_pow(lights, model):
    for seed in (0, 1):
        ctx = shiny_ctx(seed, lights)
        got = SmoothStyle(model=model).shade(ctx)
        same_bits(got, pow_kernel(ctx, model))
        same_bits(got, oracle_smooth(SmoothStyle(model=model), ctx))


def test_fallback_to_pow_when_in_doubt():
    """An error bound inflated 1e12 times sends most samples back to pow: still exact."""
    ctx = shiny_ctx(2, "mixed")
    want = pow_kernel(ctx, "blinn-phong")
    got = SmoothStyle().shade(ctx)
    same_bits(got, want)
    real = K._POW_REL
    try:  # module constants are frozen into the compiled kernel: rebuild it uncached
        K._POW_REL = real * 1e12
        kernel = K.shade_smooth_for(False, False)
        body = numba.njit(error_model="numpy", nogil=True)(kernel.py_func)
        inflated = Banded(body, kernel.count)
        saved, K.shade_smooth_for = K.shade_smooth_for, lambda *modes: inflated
        same_bits(SmoothStyle().shade(ctx), want)
    finally:
        K._POW_REL = real
        K.shade_smooth_for = saved


def test_same_result_for_one_and_two_threads():
    ctx = shiny_ctx(3, "mixed", shape=(97, 131))
    saved = numba.get_num_threads()
    try:
        results = []
        for threads in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(threads)
            results.append(SmoothStyle().shade(ctx))
    finally:
        numba.set_num_threads(saved)
    same_bits(*results)


def test_float64_out_uses_pow():
    """A float64 ``out`` (tests of the arithmetic) takes pow everywhere: the pow kernel's
    float64 values, which the float32 path rounds."""
    ctx = shiny_ctx(4, "directional", shape=(9, 11))
    out = np.empty((9, 11, 4))
    SmoothStyle().shade(ctx, out=out)
    same_bits(out.astype(np.float32), pow_kernel(ctx, "blinn-phong"))


def test_zero_specular_light():
    ctx = shiny_ctx(5, "directional", shape=(9, 11))
    ctx.scene.lights = (Light(direction=(0.3, 0.3, 1.0), color=(0.0, 0.0, 0.0)),)
    same_bits(SmoothStyle().shade(ctx), pow_kernel(ctx, "blinn-phong"))
