"""Material colour maps (``Material.color_texture``, glTF's ``baseColorTexture``): the smooth and
toon styles multiply m_a and m_d by the map's sRGB-decoded trilinear sample. Checked against a
naive float64 loop (GL_REPEAT bilinear taps at texel centres (i + 0.5) / size, box-filtered
levels, the isotropic LOD of OpenGL sec. 8.14) evaluated at the G-buffer's uv and derivatives."""

from __future__ import annotations

import dataclasses
import math

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.raster import Camera, Mesh
from refnpr.render import render
from refnpr.scenes import Light, Material, Scene, SceneObject
from refnpr.styles import get_style
from refnpr.styles.albedo import color_pyramid

RNG = np.random.default_rng(7)
TEXTURE = RNG.integers(0, 256, size=(8, 8, 3), dtype=np.uint8)  # sRGB-encoded, as glTF's


def _srgb_to_linear(c):
    c = c / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _levels(image):
    """Box-filtered mip levels of a power-of-two image, float64."""
    levels = [image]
    while levels[-1].shape[0] > 1:
        a = levels[-1]
        levels.append((a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2]) / 4.0)
    return levels


def _bilinear(level, u, v):
    rows, cols = level.shape[:2]
    x = u * cols - 0.5
    y = v * rows - 0.5
    i0, j0 = math.floor(x), math.floor(y)
    fx, fy = x - i0, y - j0
    out = np.zeros(3)
    for dj, wy in ((0, 1 - fy), (1, fy)):
        for di, wx in ((0, 1 - fx), (1, fx)):
            out += wx * wy * level[(j0 + dj) % rows, (i0 + di) % cols]
    return out


def _trilinear(levels, u, v, dx, dy):
    size = np.array([levels[0].shape[1], levels[0].shape[0]], dtype=np.float64)
    rho = max(np.hypot(*(np.asarray(dx) * size)), np.hypot(*(np.asarray(dy) * size)))
    lod = min(max(math.log2(max(rho, 2.0**-64)), 0.0), len(levels) - 1)
    k = math.floor(lod)
    f = lod - k
    out = (1 - f) * _bilinear(levels[k], u, v)
    if f > 0:
        out += f * _bilinear(levels[min(k + 1, len(levels) - 1)], u, v)
    return out


def _quad_scene(repeats: float, color_texture, uv_scale=(1.0, 1.0)) -> Scene:
    """A unit-normal quad facing the camera, lit head-on, with uv running over ``repeats``
    texture repeats (magnified for small values, minified for large)."""
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
    uv = (pos[:, :2] + 1.0) / 2.0 * repeats
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    mesh = Mesh(pos, np.array([[0, 1, 2], [0, 2, 3]]), normals, uv, name="quad")
    material = Material(
        ambient=0.2,
        diffuse=(0.7, 0.6, 0.5),
        specular=0.0,
        color_texture=color_texture,
        uv_scale=uv_scale,
    )
    camera = Camera.look_at(eye=(0.3, 0.2, 2.4), target=(0.0, 0.0, 0.0), fov_y=50.0)
    light = Light(direction=(0.0, 0.0, 1.0))
    return Scene(objects=(SceneObject(mesh, material=material),), camera=camera, lights=(light,))


@pytest.fixture(scope="module")
def texture_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("tex") / "albedo.png"
    iio.imwrite(path, TEXTURE)
    return path


@pytest.mark.parametrize("repeats, uv_scale", [(0.6, (1.0, 1.0)), (3.0, (2.0, 1.5))])
def test_smooth_colour_is_the_material_times_the_maps_trilinear_sample(
    texture_file, repeats, uv_scale
):
    scene = _quad_scene(repeats, str(texture_file), uv_scale)
    image, gb = render(scene, "smooth", 48, 40, 1, return_gbuffer=True)
    levels = _levels(_srgb_to_linear(TEXTURE.astype(np.float64)))
    m = scene.objects[0].material
    n_dot_l = gb["normal"][..., 2].astype(np.float64)  # the light is +z
    covered = np.argwhere(gb["mesh_id"] >= 0)
    assert len(covered) > 500
    s = np.asarray(uv_scale)
    worst = 0.0
    for y, x in covered:
        u, v = gb["uv"][y, x].astype(np.float64) * s
        dx = gb["duv_dx"][y, x].astype(np.float64) * s
        dy = gb["duv_dy"][y, x].astype(np.float64) * s
        a = _trilinear(levels, u, v, dx, dy)
        want = np.clip(np.asarray(m.ambient) * a + np.asarray(m.diffuse) * a * n_dot_l[y, x], 0, 1)
        worst = max(worst, float(np.abs(image.rgba[y, x, :3] - want).max()))
    # the pyramid's texels are float32 (the kit's), the rest float64: float32 rounding only
    assert worst < 2e-6, worst


def test_a_map_leaves_untextured_objects_and_the_specular_term_alone(texture_file):
    plain = _quad_scene(0.6, None)
    textured = _quad_scene(0.6, str(texture_file))
    for style in ("smooth", "toon"):
        a = render(plain, style, 32, 24, 1).rgba
        b = render(textured, style, 32, 24, 1).rgba
        assert np.abs(a - b).max() > 0.1  # the map shows
    # a white map is the identity, bit for bit (m a = m exactly when a = 1)
    white = texture_file.parent / "white.png"
    iio.imwrite(white, np.full((4, 4, 3), 255, np.uint8))
    for style in ("smooth", "toon"):
        np.testing.assert_array_equal(
            render(plain, style, 32, 24, 1).rgba,
            render(_quad_scene(0.6, str(white)), style, 32, 24, 1).rgba,
        )


def test_toon_steps_the_tone_then_colours_it(texture_file):
    scene = _quad_scene(0.6, str(texture_file))
    style = get_style("toon", n=2, t=0.5, specular=False)
    image, gb = render(scene, style, 32, 24, 1, return_gbuffer=True)
    plain, _ = render(_quad_scene(0.6, None), style, 32, 24, 1, return_gbuffer=True)
    covered = gb["mesh_id"] >= 0
    m = scene.objects[0].material
    # without the map the colour is m_a + m_d T; with it (m_a + m_d T) a, per channel
    tone = (plain.rgba[..., :3] - np.asarray(m.ambient)) / np.asarray(m.diffuse)
    levels = _levels(_srgb_to_linear(TEXTURE.astype(np.float64)))
    y, x = np.argwhere(covered)[len(np.argwhere(covered)) // 2]
    a = _trilinear(
        levels,
        *gb["uv"][y, x].astype(np.float64),
        gb["duv_dx"][y, x].astype(np.float64),
        gb["duv_dy"][y, x].astype(np.float64),
    )
    want = np.asarray(m.ambient) * a + np.asarray(m.diffuse) * a * tone[y, x]
    np.testing.assert_allclose(image.rgba[y, x, :3], np.clip(want, 0, 1), atol=2e-6)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_colour_maps_come_from_gltf_and_toml(tmp_path, texture_file):
    from refnpr.scenes import load_scene

    scene = _quad_scene(1.0, None)
    mesh = scene.objects[0].mesh
    import trimesh
    from PIL import Image as PILImage

    tm = trimesh.Trimesh(mesh.positions, mesh.faces, process=False)
    tm.visual = trimesh.visual.TextureVisuals(uv=mesh.uv, image=PILImage.fromarray(TEXTURE))
    glb = tmp_path / "quad.glb"
    trimesh.Scene(tm).export(glb)
    loaded = load_scene(glb)
    tex = loaded.objects[0].material.color_texture
    assert tex is not None and "images[0]" in tex
    got = render(loaded, "smooth", 32, 24, 1).rgba
    assert np.ptp(got[..., 0][got[..., 3] > 0]) > 0.2  # the map shows on the quad
    toml = tmp_path / "s.toml"
    toml.write_text(
        'gltf = "quad.glb"\n[materials."*"]\ncolor_texture = "albedo.png"\n', encoding="utf-8"
    )
    (tmp_path / "albedo.png").write_bytes(texture_file.read_bytes())
    over = load_scene(toml)
    assert over.objects[0].material.color_texture == str(tmp_path / "albedo.png")


def test_bad_colour_maps_are_named_errors(tmp_path):
    with pytest.raises(TypeError, match="color_texture: expected a texture name or a file path"):
        Material(color_texture=3)
    missing = _quad_scene(1.0, str(tmp_path / "nope.png"))
    with pytest.raises(ValueError, match="color_texture"):
        render(missing, "smooth", 16, 16, 1)
    no_uv = _quad_scene(1.0, "brick")
    obj = no_uv.objects[0]
    bare = Mesh(obj.mesh.positions, obj.mesh.faces, obj.mesh.normals, None, name="bare")
    no_uv = dataclasses.replace(no_uv, objects=(dataclasses.replace(obj, mesh=bare),))
    with pytest.raises(ValueError, match="uv"):
        render(no_uv, "smooth", 16, 16, 1)
    # a map on one object, a mesh without uv beside it: the cause is named
    beside = _quad_scene(1.0, "brick")
    plain = dataclasses.replace(no_uv.objects[0], material=Material(), name="plain")
    beside = dataclasses.replace(beside, objects=(*beside.objects, plain))
    with pytest.raises(ValueError, match=r"object 'quad' has a colour map.*\['plain'\] have none"):
        render(beside, "toon", 16, 16, 1)


def test_a_cmyk_jpeg_map_is_read_as_rgb(tmp_path):
    from PIL import Image as PILImage

    path = tmp_path / "red.jpg"
    PILImage.new("CMYK", (8, 8), (0, 255, 255, 0)).save(path)  # red, as CMYK
    a = color_pyramid(str(path)).levels[0]
    np.testing.assert_allclose(a[0, 0], [1.0, 0.0, 0.0], atol=0.02)
