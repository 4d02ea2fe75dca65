"""Bad input gets a clear error naming the parameter, the value and the fix."""

from __future__ import annotations

import re

import numpy as np
import pytest

from refnpr.raster import Camera, Mesh, rasterize, valid_channels

TRI = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
FACES = np.array([[0, 1, 2]])
CAM = Camera.look_at((0.3, 0.3, 3.0), (0.3, 0.3, 0.0), (0.0, 1.0, 0.0), 45.0, 0.1, 10.0)


def _mesh(**kw) -> Mesh:
    return Mesh(TRI, FACES, **kw)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_vertices(bad):
    pos = TRI.copy()
    pos[1, 2] = bad
    with pytest.raises(
        ValueError, match=r"positions: contains NaN or inf \(first at index \(1, 2\)"
    ):
        Mesh(pos, FACES)


def test_non_finite_uv_normals_and_attributes():
    with pytest.raises(ValueError, match=r"uv: contains NaN or inf"):
        _mesh(uv=np.array([[0.0, 0.0], [np.nan, 1.0], [1.0, 1.0]]))
    with pytest.raises(ValueError, match=r"normals: contains NaN or inf"):
        _mesh(normals=np.array([[0.0, 0.0, 1.0]] * 2 + [[0.0, np.inf, 1.0]]))
    with pytest.raises(ValueError, match=r"attributes\['heat'\]: contains NaN or inf"):
        _mesh(attributes={"heat": np.array([1.0, np.nan, 2.0])})


@pytest.mark.parametrize("faces", [[[0, 1, 3]], [[0, -1, 2]]])
def test_faces_out_of_range(faces):
    with pytest.raises(
        ValueError, match=r"faces: index out of range .* for 3 vertices; .*zero-based"
    ):
        Mesh(TRI, np.array(faces))


def test_empty_mesh_and_empty_scene():
    with pytest.raises(ValueError, match=r"positions: mesh 'mesh' is empty \(0 vertices\)"):
        Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    with pytest.raises(ValueError, match=r"faces: mesh 'mesh' has no triangles"):
        Mesh(TRI, np.zeros((0, 3), dtype=int))
    with pytest.raises(ValueError, match=r"mesh_or_scene: no meshes to rasterize"):
        rasterize([], CAM, 8, 8)


def test_malformed_mesh_arrays():
    with pytest.raises(ValueError, match=r"positions: expected shape \(N, 3\), got \(3, 2\)"):
        Mesh(TRI[:, :2], FACES)
    with pytest.raises(ValueError, match=r"faces: expected shape \(M, 3\), got \(1, 4\)"):
        Mesh(TRI, np.array([[0, 1, 2, 0]]))
    with pytest.raises(TypeError, match=r"faces: expected integer indices, got dtype float64"):
        Mesh(TRI, np.array([[0.0, 1.5, 2.0]]))
    with pytest.raises(ValueError, match=r"uv: expected 3 rows \(one per vertex\), got 2"):
        _mesh(uv=np.zeros((2, 2)))
    with pytest.raises(TypeError, match=r"mesh_or_scene: expected a Mesh"):
        rasterize("mesh", CAM, 8, 8)
    with pytest.raises(TypeError, match=r"mesh_or_scene\[1\]: expected a Mesh, got int"):
        rasterize([_mesh(), 3], CAM, 8, 8)


@pytest.mark.parametrize("name", ["width", "height"])
@pytest.mark.parametrize("value", [0, -3])
def test_image_size_must_be_positive(name, value):
    size = {"width": 8, "height": 8, name: value}
    with pytest.raises(ValueError, match=rf"{name}: expected an integer >= 1, got {value}"):
        rasterize(_mesh(), CAM, size["width"], size["height"])


@pytest.mark.parametrize("value", [8.0, "8", True])
def test_image_size_must_be_an_integer(value):
    with pytest.raises(TypeError, match=r"width: expected an integer, got"):
        rasterize(_mesh(), CAM, value, 8)


@pytest.mark.parametrize("spp", [2, 3, 5, 8, 15])
def test_spp_must_be_a_square(spp):
    with pytest.raises(ValueError, match=rf"spp: expected a square number .*got {spp}; use"):
        rasterize(_mesh(), CAM, 8, 8, spp=spp)


@pytest.mark.parametrize("spp", [0, -4])
def test_spp_must_be_positive(spp):
    with pytest.raises(ValueError, match=rf"spp: expected an integer >= 1, got {spp}"):
        rasterize(_mesh(), CAM, 8, 8, spp=spp)


@pytest.mark.parametrize("spp", [4.0, 1.5, "4", None])
def test_spp_must_be_an_integer(spp):
    with pytest.raises(TypeError, match=r"spp: expected an integer"):
        rasterize(_mesh(), CAM, 8, 8, spp=spp)


@pytest.mark.parametrize("near", [0.0, -0.1])
def test_near_must_be_positive(near):
    with pytest.raises(ValueError, match=rf"near: expected a positive clip distance, got {near}"):
        Camera.look_at((0, 0, 3), (0, 0, 0), (0, 1, 0), 45.0, near, 10.0)


@pytest.mark.parametrize("far", [0.1, 0.05])
def test_far_must_exceed_near(far):
    with pytest.raises(ValueError, match=rf"far: must be greater than near \(0.1\), got {far}"):
        Camera.look_at((0, 0, 3), (0, 0, 0), (0, 1, 0), 45.0, 0.1, far)


@pytest.mark.parametrize("fov", [0.0, -10.0, 180.0, 200.0])
def test_fov_must_be_in_open_interval(fov):
    with pytest.raises(ValueError, match=rf"fov_y: expected degrees in \(0, 180\), got {fov}"):
        Camera.look_at((0, 0, 3), (0, 0, 0), (0, 1, 0), fov, 0.1, 10.0)


def test_non_finite_camera_parameters():
    with pytest.raises(ValueError, match=r"eye: must be finite"):
        Camera.look_at((0, np.nan, 3), (0, 0, 0))
    with pytest.raises(ValueError, match=r"near: must be finite, got nan"):
        Camera.look_at((0, 0, 3), (0, 0, 0), near=float("nan"))
    with pytest.raises(ValueError, match=r"target: equals eye"):
        Camera.look_at((0, 0, 3), (0, 0, 3))
    with pytest.raises(ValueError, match=r"up: .* is parallel to the view direction"):
        Camera.look_at((0, 0, 3), (0, 0, 0), (0, 0, 1))


@pytest.mark.parametrize(("far", "near"), [(1e308, 1.0), (9e307, 0.1), (1e300, 1e10)])
def test_a_far_plane_that_overflows_the_projection_is_refused(far, near):
    with pytest.raises(ValueError, match=r"far: .* overflows the perspective matrix.*at most"):
        Camera.look_at((0, 0, 3), (0, 0, 0), near=near, far=far)


def test_the_largest_far_plane_accepted_gives_a_finite_projection():
    cam = Camera.look_at((0, 0, 3), (0, 0, 0), near=1.0, far=8.98e307)
    assert np.all(np.isfinite(cam.view_projection(4, 4)))


def test_integers_beyond_the_float_range_are_not_finite():
    huge = 10**400  # float(huge) raises OverflowError
    with pytest.raises(ValueError, match=r"fov_y: expected a finite number, got an integer beyond"):
        Camera.look_at((0, 0, 3), (0, 0, 0), fov_y=huge)
    with pytest.raises(ValueError, match=r"eye: must be finite, got an integer beyond"):
        Camera.look_at((huge, 0, 3), (0, 0, 0))


def test_unknown_channel_lists_the_valid_ones():
    with pytest.raises(
        ValueError, match=r"channels: unknown channel 'colour'; valid channels are"
    ) as info:
        rasterize(_mesh(), CAM, 8, 8, ("depth", "colour"))
    message = str(info.value)
    for name in valid_channels(_mesh()):
        assert repr(name) in message, f"{name} missing from: {message}"


def test_unknown_channel_message_includes_attribute_channels():
    mesh = _mesh(attributes={"heat": np.arange(3.0)})
    with pytest.raises(
        ValueError, match=r"unknown channel 'dheat_dz'.*'dheat_dx'.*'dheat_dy'.*'heat'"
    ):
        rasterize(mesh, CAM, 8, 8, ("dheat_dz",))


def test_channels_must_be_names():
    with pytest.raises(ValueError, match=r"channels: ask for at least one channel"):
        rasterize(_mesh(), CAM, 8, 8, ())
    with pytest.raises(TypeError, match=r"channels: names must be strings, got 3"):
        rasterize(_mesh(), CAM, 8, 8, ("depth", 3))


@pytest.mark.parametrize("channel", ["uv", "duv_dx", "duv_dy", "lod", "dyadic_scale"])
def test_uv_channels_need_uv(channel):
    with pytest.raises(
        ValueError, match=r"channels: uv requested but mesh 'plain' has no uv; give"
    ):
        rasterize(Mesh(TRI, FACES, name="plain"), CAM, 8, 8, (channel,), texture_size=16)


def test_normal_channel_needs_normals():
    with pytest.raises(
        ValueError, match=r"channels: normal requested but mesh 'mesh' has no normals"
    ):
        rasterize(_mesh(), CAM, 8, 8, ("normal",))


def test_lod_needs_texture_size():
    mesh = _mesh(uv=TRI[:, :2])
    with pytest.raises(
        ValueError, match=re.escape("texture_size: the lod channel needs the texture size")
    ):
        rasterize(mesh, CAM, 8, 8, ("lod",))
    with pytest.raises(
        ValueError, match=r"texture_size: expected two positive integers, got \(0, 8\)"
    ):
        rasterize(mesh, CAM, 8, 8, ("lod",), texture_size=(0, 8))


def test_other_options_are_validated():
    mesh = _mesh(uv=TRI[:, :2])
    with pytest.raises(TypeError, match=r"camera: expected refnpr.raster.Camera, got str"):
        rasterize(mesh, "camera", 8, 8)
    with pytest.raises(TypeError, match=r"camera: expected a Camera \(None only works for a Scene"):
        rasterize(mesh, None, 8, 8)
    with pytest.raises(
        TypeError, match=r"dtype: expected numpy.float32 or numpy.float64, got float16"
    ):
        rasterize(mesh, CAM, 8, 8, dtype=np.float16)
    with pytest.raises(
        ValueError, match=r"line_period: expected a positive number of pixels, got 0"
    ):
        rasterize(mesh, CAM, 8, 8, ("dyadic_scale",), line_period=0.0)
    with pytest.raises(ValueError, match=r"dyadic_coord: expected 'u' or 'v', got 'w'"):
        rasterize(mesh, CAM, 8, 8, ("dyadic_scale",), dyadic_coord="w")
    with pytest.raises(TypeError, match=r"cull_backfaces: expected a bool, got 'yes'"):
        rasterize(mesh, CAM, 8, 8, cull_backfaces="yes")
    with pytest.raises(ValueError, match=r"tile: expected an integer >= 4, got 2"):
        rasterize(mesh, CAM, 8, 8, tile=2)


def test_sample_grid_too_large_for_fixed_point():
    with pytest.raises(ValueError, match=r"width/height/spp: the sample grid .* is too large"):
        rasterize(_mesh(), CAM, 2_000_000, 1)
