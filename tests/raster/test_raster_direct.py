"""The rasterizer writes interpolated channels straight into their arrays (one fused pass, then a
pass per further family): a channel's bits do not depend on what else was asked for (each
channel of a set against the same channel asked for alone, fresh buffers and ``out=``; the full
G-buffer's specialised kernel against the general one); ``lod`` and ``dyadic_scale`` agree with
a numpy oracle of OpenGL sec. 8.14 and Veryovka eq. 5; ``mesh_id`` from its kernel equals
numpy's ``searchsorted``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.raster import Camera, Mesh, rasterize
from refnpr.raster import _kernels as K

from .meshes import cube, icosphere

SETS = [
    ("uv", "duv_dx", "duv_dy", "position", "dposition_dx", "dposition_dy", "normal", "depth"),
    (
        "bary",
        "dposition_dx",
        "dposition_dy",
        "duv_dx",
        "duv_dy",
        "mesh_id",
        "normal",
        "position",
        "tri_id",
        "uv",
    ),  # the tam / tamiss set
    ("duv_dy", "dposition_dx", "heat", "temp"),  # derivatives only; two value families
    ("uv", "position", "heat", "temp", "normal"),  # value families only
    ("dheat_dx", "dtemp_dy", "duv_dx", "position"),  # three derivative families
    ("mesh_id", "normal", "position"),  # toon / smooth
    ("dyadic_scale", "mesh_id", "normal", "position", "uv"),  # threshold
    ("lod", "dyadic_scale", "duv_dy"),  # from uv derivatives not all asked for
    ("lod", "dposition_dx", "temp"),
    ("tri_id", "depth"),  # depth from the visibility pass (float32), against interp_depth
    ("depth", "uv", "duv_dx", "duv_dy", "normal", "tri_id"),  # the specialised full kernel
    ("ndc_z", "depth", "heat", "lod"),
    ("depth", "mesh_id", "coverage"),
]


def _meshes() -> list[Mesh]:
    out = []
    for m in (icosphere(3), cube(0.8, center=(0.9, 0.2, 0.3))):
        p = m.positions
        temp = np.cos(3.0 * p[:, 0]) + p[:, 1] * p[:, 2]  # a scalar attribute
        attrs = {"heat": m.attributes["heat"], "temp": temp}
        out.append(Mesh(p, m.faces, normals=m.normals, uv=m.uv, attributes=attrs, name=m.name))
    return out


CAM = Camera.look_at((0.3, 0.4, 3.2), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 45.0, 0.1, 20.0)
CAM2 = Camera.look_at((-2.0, 1.0, 1.5), (0.1, 0.0, 0.0), (0.0, 1.0, 0.0), 60.0, 0.1, 20.0)
KW = dict(texture_size=(64, 32), line_period=1.5)
NOT_INTERPOLATED = {"tri_id", "mesh_id", "coverage", "coverage_count", "depth"}
ATTR_DERIVATIVES = {f"d{a}_d{x}" for a in ("heat", "temp") for x in "xy"}


def _bits_equal(x: np.ndarray, y: np.ndarray, name: str) -> None:
    assert x.dtype == y.dtype and x.shape == y.shape, name
    assert np.array_equal(x.view(np.uint8), y.view(np.uint8)), name  # bit for bit


@pytest.mark.parametrize("channels", SETS, ids=lambda c: "+".join(c)[:48])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("spp", [1, 4])
def test_each_channel_as_if_asked_for_alone(channels, dtype, spp):
    meshes = _meshes()
    direct = rasterize(meshes, CAM, 37, 29, channels, spp, dtype=dtype, **KW)
    gb = rasterize(meshes, CAM2, 37, 29, channels, spp, dtype=dtype, **KW)
    in_place = rasterize(meshes, CAM, 37, 29, channels, spp, dtype=dtype, **KW, out=gb)
    assert in_place is gb
    assert sorted(direct.channels) == sorted(channels) == sorted(in_place.channels)
    interpolating = bool(set(channels) - NOT_INTERPOLATED)
    for name in channels:
        # bary: a companion that makes the interpolation pass run. depth is 1 / Q from the
        # depth plane without that pass and from the barycentric planes with it (the same
        # number within an ulp of float64); an attribute's derivative alone: see
        # test_attribute_derivative_alone
        plus = ATTR_DERIVATIVES | ({"depth"} if interpolating else set())
        alone = (name, "bary") if name in plus else (name,)
        alone = rasterize(meshes, CAM, 37, 29, alone, spp, dtype=dtype, **KW)[name]
        _bits_equal(direct[name], alone, name)
        _bits_equal(in_place[name], alone, name)


def test_attribute_derivative_alone():
    meshes = _meshes()
    with_bary = rasterize(meshes, CAM, 37, 29, ("dheat_dx", "bary"), 1, **KW)["dheat_dx"]
    alone = rasterize(meshes, CAM, 37, 29, ("dheat_dx",), 1, **KW)["dheat_dx"]
    _bits_equal(alone, with_bary, "dheat_dx")


def _screen_scales(duv_dx, duv_dy, empty, size, period, k):
    """numpy oracle of ``lod`` (OpenGL 4.x sec. 8.14: rho = max(|d(u,v)/dx|, |d(u,v)/dy|) in
    texels, lambda = log2 rho) and ``dyadic_scale`` (Veryovka eq. 5: d = 1/|grad_k|,
    s = log2(d / w), clipped to [-64, 64]) from the derivatives as stored; 0 where empty."""
    dx = duv_dx.astype(np.float64)
    dy = duv_dy.astype(np.float64)
    tw, th = size
    rho = np.maximum(
        np.hypot(dx[..., 0] * tw, dx[..., 1] * th), np.hypot(dy[..., 0] * tw, dy[..., 1] * th)
    )
    lod = np.where(empty, 0.0, np.log2(np.maximum(rho, 2.0**-64)))
    grad = np.hypot(dx[..., k], dy[..., k])
    s = np.clip(-np.log2(np.maximum(grad, 2.0**-64)) - math.log2(period), -64.0, 64.0)
    return lod, np.where(empty, 0.0, s)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("coord", ["u", "v"])
def test_lod_and_dyadic_scale_against_numpy(dtype, coord):
    meshes = _meshes()
    chans = ("tri_id", "duv_dx", "duv_dy", "lod", "dyadic_scale")
    gb = rasterize(meshes, CAM2, 41, 33, chans, 4, dtype=dtype, dyadic_coord=coord, **KW)
    k = 1 if coord == "v" else 0
    empty = gb["tri_id"] < 0
    lod, s = _screen_scales(gb["duv_dx"], gb["duv_dy"], empty, KW["texture_size"], 1.5, k)
    if dtype == np.float32:  # an ulp of log2 (libm's against numpy's SIMD one) rounds away
        np.testing.assert_array_equal(gb["lod"], lod.astype(np.float32))
        np.testing.assert_array_equal(gb["dyadic_scale"], s.astype(np.float32))
    else:  # within an ulp of the logarithms (s = -log2 |grad| - log2 w may cancel)
        assert (np.abs(gb["lod"] - lod) <= 4e-16 * np.abs(lod)).all()
        log2_grad = np.abs(s) + math.log2(1.5)
        assert (np.abs(gb["dyadic_scale"] - s) <= 4e-16 * log2_grad).all()
    assert (gb["lod"][empty] == 0).all() and (gb["dyadic_scale"][empty] == 0).all()


def test_dyadic_scale_of_a_constant_coordinate_is_clipped():
    # |grad| below the floor 2**-64: s = 64 - log2 w, then clipped to [-64, 64]
    assert K.dyadic_scale_of(0.0, 0.0, 0.0) == 64.0
    assert K.dyadic_scale_of(0.0, 0.0, 1.0) == 63.0
    assert K.dyadic_scale_of(0.0, 0.0, -3.0) == 64.0
    assert K.dyadic_scale_of(0.0, 0.25, 1.0) == 1.0  # d = 4 px, w = 2 px
    assert K.dyadic_scale_of(2.0**-70, 0.0, -100.0) == 64.0
    assert K.dyadic_scale_of(2.0**70, 0.0, 0.0) == -64.0
    assert K.gl_lod((0.0, 0.0), (0.0, 0.0), 64.0, 32.0) == -64.0
    assert K.gl_lod((1.0 / 64, 0.0), (0.0, 1.0 / 32), 64.0, 32.0) == 0.0


def test_mesh_ids_kernel_equals_searchsorted():
    rng = np.random.default_rng(7)
    # meshes without faces (repeated boundaries) and a last boundary never reached
    first_tri = np.array([0, 0, 5, 5, 5, 40, 41, 90], dtype=np.int64)
    tri_id = rng.integers(-3, 90, size=(23, 31)).astype(np.int32)
    got = np.full(tri_id.shape, 99, dtype=np.int32)
    K.mesh_ids(tri_id, first_tri, got)
    want = np.searchsorted(first_tri, tri_id, side="right").astype(np.int32) - 1
    want[tri_id < 0] = -1
    np.testing.assert_array_equal(got, want)
    one = np.zeros((4, 5), dtype=np.int32)  # a single mesh
    K.mesh_ids(np.arange(20, dtype=np.int32).reshape(4, 5) - 3, np.array([0, 17]), one)
    np.testing.assert_array_equal(one.ravel(), [-1, -1, -1] + [0] * 17)


def test_call_banded_runs_the_dispatchers_code():
    """``call_banded`` (the records typed once per call) writes what the kernel's own dispatch
    writes, and types a second call of the same argument types from its cache."""
    from refnpr import _jit

    rng = np.random.default_rng(3)
    tri_id = rng.integers(-1, 5, size=(7, 9)).astype(np.int32)
    duv = rng.normal(size=(2, 7, 9, 2)).astype(np.float32)
    scales = K.Scales(64.0, 32.0, 1, math.log2(3.0))
    outs = [(np.empty((7, 9), np.float32), np.empty((7, 9), np.float32)) for _ in range(2)]
    K.screen_scales(tri_id, duv[0], duv[1], scales, *outs[0])
    _jit.call_banded(K.screen_scales, tri_id, duv[0], duv[1], scales, *outs[1])
    n_typed = len(_jit._TYPED)
    _jit.call_banded(K.screen_scales, tri_id, duv[0], duv[1], scales, *outs[1])
    assert len(_jit._TYPED) == n_typed
    for a, b in zip(outs[0], outs[1], strict=True):
        _bits_equal(a, b, "screen_scales")
