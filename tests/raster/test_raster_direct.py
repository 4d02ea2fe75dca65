"""The rasterizer writes interpolated channels straight into their arrays (one fused pass, then a
pass per further family): bit-identical to ``interpolated_channels``, the combined-table path
(forced here by marking every channel as "copied"), for sets with several families with and
without derivatives, scalar and vector attributes, fresh buffers and ``out=``; and ``mesh_id``
from its kernel equals numpy's ``searchsorted``."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from refnpr.raster import Camera, Mesh, rasterize
from refnpr.raster import _kernels as K

from .meshes import cube, icosphere

#: the module (the package's ``rasterize`` name is the function)
R = importlib.import_module("refnpr.raster.rasterize")

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
    ("depth",),
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


def _same(a, b) -> None:
    assert sorted(a.channels) == sorted(b.channels)
    for k in a.channels:
        x, y = a[k], b[k]
        assert x.dtype == y.dtype and x.shape == y.shape, k
        if k in ("lod", "dyadic_scale") and x.dtype == np.float64:
            # libm's log2 (kernel) against numpy's, which may be a SIMD one within an ulp
            np.testing.assert_array_max_ulp(x, y, maxulp=2)
            continue
        assert np.array_equal(x.view(np.uint8), y.view(np.uint8)), k  # bit for bit


@pytest.mark.parametrize("channels", SETS, ids=lambda c: "+".join(c)[:48])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("spp", [1, 4])
def test_direct_path_equals_the_combined_tables(channels, dtype, spp, monkeypatch):
    meshes = _meshes()
    kw = dict(dtype=dtype, texture_size=(64, 32), line_period=1.5)
    direct = rasterize(meshes, CAM, 37, 29, channels, spp, **kw)
    gb = rasterize(meshes, CAM2, 37, 29, channels, spp, **kw)
    in_place = rasterize(meshes, CAM, 37, 29, channels, spp, **kw, out=gb)
    assert in_place is gb
    with monkeypatch.context() as mp:  # every channel through interpolated_channels
        everything = frozenset(channels) | {"ndc_z"}
        mp.setattr(R, "_COPIED", everything)
        combined = rasterize(meshes, CAM, 37, 29, channels, spp, **kw)
    _same(direct, combined)
    _same(in_place, combined)


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
