"""``rasterize(..., out=gb)``: repeated frames written in place, bit-identical to fresh buffers."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from refnpr.raster import Camera, rasterize

from .meshes import cube, icosphere
from .scenes import BUILTIN_CHANNELS, HEAT_CHANNELS, SCENES

FULL = ("depth", "tri_id", "uv", "duv_dx", "duv_dy", "normal")
#: Channel sets written straight into ``out`` and ones that go through the copying path.
SETS = [
    ("depth", "tri_id"),
    ("depth",),
    FULL,
    ("tri_id", "normal"),
    ("duv_dx",),
    ("bary", "coverage", "mesh_id", "coverage_count", "heat", "dheat_dy"),
    ("position", "dposition_dx", "uv", "depth"),
    BUILTIN_CHANNELS + HEAT_CHANNELS,
]


def _cameras():
    return [
        Camera.look_at((0.3, 0.4, 3.2), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 45.0, 0.1, 20.0),
        Camera.look_at((-2.0, 1.0, 1.5), (0.1, 0.0, 0.0), (0.0, 1.0, 0.0), 60.0, 0.1, 20.0),
        Camera.look_at((0.0, 0.0, 1.2), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 70.0, 0.5, 20.0),
    ]


def _meshes():
    return [icosphere(3), cube(0.8, center=(0.9, 0.2, 0.3))]


def _same(a, b) -> None:
    assert sorted(a) == sorted(b)
    for k in a:
        assert a[k].dtype == b[k].dtype and a[k].shape == b[k].shape, k
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


@pytest.mark.parametrize("channels", SETS, ids=lambda c: "+".join(c)[:40])
@pytest.mark.parametrize("spp", [1, 4])
def test_out_matches_fresh_across_cameras(channels, spp):
    meshes = _meshes()
    kw = dict(spp=spp, texture_size=(64, 32))
    cams = _cameras()
    gb = rasterize(meshes, cams[0], 40, 30, channels, **kw)
    arrays = {k: v for k, v in gb.channels.items()}
    for v in gb.channels.values():  # stale contents must never leak into a frame
        v.fill(-7)
    for cam in cams + cams[:1]:
        fresh = rasterize(meshes, cam, 40, 30, channels, **kw)
        got = rasterize(meshes, cam, 40, 30, channels, out=gb, **kw)
        assert got is gb
        assert all(gb.channels[k] is arrays[k] for k in arrays)  # filled in place
        _same(got, fresh)
        assert got.camera is cam
        np.testing.assert_array_equal(got.view_projection, fresh.view_projection)
        np.testing.assert_array_equal(got.mesh_first_tri, fresh.mesh_first_tri)
        assert got.texture_size == fresh.texture_size and got.line_period == fresh.line_period


def test_out_float64_and_scenes():
    for name in ("near_clip", "grazing"):
        scene = SCENES[name]()
        args = (scene.meshes, scene.camera, scene.width, scene.height)
        kw = dict(channels=BUILTIN_CHANNELS + HEAT_CHANNELS, texture_size=16, dtype=np.float64)
        gb = rasterize(*args, **kw)
        fresh = rasterize(*args, **kw)
        _same(rasterize(*args, out=gb, **kw), fresh)


def test_out_other_gbuffer_untouched():
    meshes = _meshes()
    a_cam, b_cam = _cameras()[:2]
    a = rasterize(meshes, a_cam, 32, 24, FULL)
    b = rasterize(meshes, b_cam, 32, 24, FULL)
    b_copy = {k: v.copy() for k, v in b.channels.items()}
    rasterize(meshes, b_cam, 32, 24, FULL, out=a)
    _same(a, b_copy)
    _same(b, b_copy)
    rasterize(meshes, a_cam, 32, 24, FULL, out=a)  # writing a again leaves b alone
    _same(b, b_copy)
    assert not any(np.shares_memory(a[k], b[k]) for k in FULL)


@pytest.mark.parametrize("threads", [1, 2])
def test_out_thread_count(threads):
    meshes = _meshes()
    cam = _cameras()[1]
    ref = rasterize(meshes, cam, 48, 36, FULL, spp=4)
    gb = rasterize(meshes, _cameras()[0], 48, 36, FULL, spp=4)
    old = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        _same(rasterize(meshes, cam, 48, 36, FULL, spp=4, out=gb), ref)
    finally:
        numba.set_num_threads(old)


def _base():
    meshes = _meshes()
    return meshes, _cameras()[0], rasterize(meshes, _cameras()[0], 20, 16, ("depth", "tri_id"))


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(width=21), r"out: holds a 20 x 16 spp 1 frame, this call renders 21 x 16 spp 1"),
        (dict(height=8), r"out: holds a 20 x 16 spp 1 frame, this call renders 20 x 8"),
        (dict(spp=4), r"out: holds a 20 x 16 spp 1 frame, this call renders 20 x 16 spp 4"),
        (dict(channels=("depth",)), r"extra in out: \['tri_id'\]"),
        (dict(channels=("depth", "tri_id", "uv")), r"missing from out: \['uv'\]"),
        (dict(dtype=np.float64), r"out\['depth'\]: is float32 .*dtype=float64 .*writes float64"),
    ],
)
def test_out_mismatch_refused(change, match):
    meshes, cam, gb = _base()
    kw = dict(width=20, height=16, channels=("depth", "tri_id"))
    kw.update(change)
    with pytest.raises(ValueError, match=match) as info:
        rasterize(meshes, cam, out=gb, **kw)
    assert "or out=None" in str(info.value)


def test_out_attribute_width_refused():
    meshes = _meshes()
    cam = _cameras()[0]
    gb = rasterize(meshes, cam, 20, 16, ("heat",))
    other = [m.with_(attributes={"heat": m.attributes["heat"][:, :1]}) for m in meshes]
    with pytest.raises(ValueError, match=r"out\['heat'\]: is float32 \(16, 20, 2\)"):
        rasterize(other, cam, 20, 16, ("heat",), out=gb)


def test_out_type_and_views_refused():
    meshes, cam, gb = _base()
    with pytest.raises(TypeError, match="out: expected a GBuffer"):
        rasterize(meshes, cam, 20, 16, ("depth", "tri_id"), out=dict(gb.channels))
    gb.channels["depth"].flags.writeable = False
    with pytest.raises(ValueError, match=r"out\['depth'\]: must be a writeable C-contiguous"):
        rasterize(meshes, cam, 20, 16, ("depth", "tri_id"), out=gb)
    gb2 = rasterize(meshes, cam, 20, 16, ("uv", "duv_dx"))
    gb2.channels["duv_dx"] = gb2.channels["uv"]  # hand-made aliasing
    with pytest.raises(ValueError, match=r"channels 'duv_dx' and 'uv' share memory"):
        rasterize(meshes, cam, 20, 16, ("uv", "duv_dx"), out=gb2)
