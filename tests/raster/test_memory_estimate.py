"""``refnpr._memory``: estimates against the measured peak of real calls, and the refusals."""

from __future__ import annotations

import subprocess
import sys
import tracemalloc

import pytest

from refnpr import _memory
from refnpr.raster import rasterize
from refnpr.raster.rasterize import attribute_widths
from refnpr.render import render, required_channels
from refnpr.scenes import load_scene
from refnpr.styles import style_from_spec

#: estimate / measured peak (tracemalloc, numpy's allocations included) must lie in this range
RASTER_FACTOR = (0.75, 1.6)
RENDER_FACTOR = (0.75, 2.0)  # a style's cost varies with its scene and parameters


def _peak(f):
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = f()
        return tracemalloc.get_traced_memory()[1] - base, out
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize(
    "channels",
    [
        ("tri_id",),
        ("depth", "tri_id"),
        ("uv",),
        ("dyadic_scale",),
        ("depth", "ndc_z", "bary"),
        ("uv", "dyadic_scale", "position", "normal", "mesh_id"),
        ("uv", "duv_dx", "duv_dy", "position", "dposition_dx"),
    ],
)
def test_rasterize_estimate_is_within_a_factor_of_the_peak(channels):
    scene = load_scene("room")
    args = (scene, scene.camera, 256, 192, channels, 4)
    rasterize(*args, texture_size=64)  # compile outside the measurement
    peak, gb = _peak(lambda: rasterize(*args, texture_size=64))
    est = sum(
        _memory.rasterize_bytes(
            256, 192, 4, channels, attributes=attribute_widths(scene.world_meshes())
        ).values()
    )
    assert gb.nbytes() <= est
    lo, hi = RASTER_FACTOR
    print(f"rasterize {channels}: estimate / peak = {est / peak:.2f}")
    assert lo <= est / peak <= hi, (channels, est, peak)


@pytest.mark.parametrize(
    "scene,style", [("sphere", "toon"), ("teapot", "smooth"), ("teapot", None)]
)
def test_render_estimate_is_within_a_factor_of_the_peak(scene, style):
    sc = load_scene(scene)
    render(sc, style, 32, 24, 4)
    peak, img = _peak(lambda: render(sc, style, 256, 192, 4))
    name = style_from_spec(style or sc.style or "toon").name
    est = sum(
        _memory.render_bytes(
            256,
            192,
            4,
            required_channels(sc, style),
            name,
            attributes=attribute_widths(sc.world_meshes()),
        ).values()
    )
    lo, hi = RENDER_FACTOR
    print(f"render {scene}/{name}: estimate / peak = {est / peak:.2f}")
    assert lo <= est / peak <= hi, (scene, style, est, peak)


def test_check_fits_passes_small_and_names_numbers_when_refusing(monkeypatch):
    parts = _memory.rasterize_bytes(64, 48, 4, ["depth", "tri_id"])
    _memory.check_fits(64, 48, 4, parts)
    monkeypatch.setattr(_memory, "available_bytes", lambda: (10**9, "available memory"))
    big = _memory.rasterize_bytes(20000, 20000, 4, ["depth", "tri_id"])
    with pytest.raises(
        ValueError, match=r"size: 20000x20000 at spp=4 needs about [0-9.]+ GB \(tri_id"
    ) as e:
        _memory.check_fits(20000, 20000, 4, big)
    assert "1.0 GB are available" in str(e.value) and "Render smaller (e.g. " in str(e.value)


def test_sample_grid_cap_holds_whatever_the_memory(monkeypatch):
    monkeypatch.setattr(_memory, "available_bytes", lambda: (10**15, "available memory"))
    parts = {"tri_id": 1}
    _memory.check_fits(46340, 46340, 1, parts)  # 2.147e9 samples: just below 2**31
    with pytest.raises(ValueError, match=r"size: 46341x46341 at spp=1 .*over the limit of 2\*\*31"):
        _memory.check_fits(46341, 46341, 1, parts)


def test_available_bytes_respects_rlimit_as_in_a_child():
    code = (
        "import resource\n"
        "resource.setrlimit(resource.RLIMIT_AS, (2000 << 20, 2000 << 20))\n"
        "from refnpr import _memory\n"
        "b, src = _memory.available_bytes(); print(b, src)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    n, src = out.stdout.split(maxsplit=1)
    assert 0 <= int(n) < 2000 << 20
    assert "RLIMIT_AS" in src


def test_format_bytes():
    assert _memory.format_bytes(160e9) == "160.0 GB"
    assert _memory.format_bytes(5e6) == "5.0 MB"


def test_interpolated_channels_agree_with_the_rasterizer():
    # one set: refnpr._memory defines it (raster imports _memory, never the other way round)
    from refnpr.raster.channels import INTERPOLATED

    assert _memory.INTERPOLATED == INTERPOLATED
