"""render(): channel requests, compositing, and the smooth/toon styles against hand-computed tone."""

import numpy as np
import pytest

from refnpr.render import render, required_channels
from refnpr.styles import get_style, list_styles


def test_toon_without_specular_asks_only_normal_and_mesh_id(plane_scene):
    style = get_style("toon", specular=False)
    assert required_channels(plane_scene, style) == {"normal", "mesh_id"}
    _, gb = render(plane_scene, style, 32, 24, return_gbuffer=True)
    assert set(gb) == {"normal", "mesh_id"}  # no uv, no derivatives, no depth paid for


def test_specular_adds_position_only(plane_scene):
    assert required_channels(plane_scene, get_style("smooth")) == {"normal", "mesh_id", "position"}


def _expected_smooth(plane_scene, px_dir_to_eye):
    obj = plane_scene.objects[0]
    m = obj.material
    n = np.array([0.0, 0.0, 1.0])
    light = np.array(plane_scene.lights[0].direction, float)
    light /= np.linalg.norm(light)
    f_d = max(n @ light, 0.0)
    h = light + px_dir_to_eye
    h /= np.linalg.norm(h)
    f_s = max(n @ h, 0.0) ** m.shininess
    return np.array(m.ambient) + np.array(m.diffuse) * f_d + np.array(m.specular) * f_s


def test_smooth_matches_eq1_at_the_centre(plane_scene):
    img = render(plane_scene, "smooth", 33, 33)
    centre = img.rgba[16, 16]
    # the centre pixel's ray hits (0, 0, 0); V points to the eye (0, 0, 4)
    expected = _expected_smooth(plane_scene, np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(centre[:3], np.clip(expected, 0, 1), atol=1e-5)
    assert centre[3] == 1.0
    # background pixel (corner) is the scene background
    np.testing.assert_array_equal(img.rgba[0, 0], [0, 0, 0, 1])


def test_toon_step_takes_only_discrete_tones(plane_scene):
    n = 3
    img = render(plane_scene, get_style("toon", n=n, specular=False), 40, 30)
    m = plane_scene.objects[0].material
    covered = img.rgba[..., 0] > 0
    reds = np.unique(img.rgba[covered, 0])
    allowed = np.array([m.ambient[0] + m.diffuse[0] * k / n for k in range(n + 1)])
    distance = np.abs(reds[:, None] - allowed[None, :]).min(axis=1)
    assert distance.max() < 1e-6  # every tone is one of m_a + m_d k / n


def test_supersampling_box_resolves_edge_pixels(plane_scene):
    img = render(plane_scene, get_style("toon", specular=False), 40, 30, spp=16)
    alpha_one = img.rgba[..., 3]
    assert np.all(alpha_one == 1.0)  # opaque background
    # pixels on the quad's silhouette mix quad and background colour
    reds = img.rgba[..., 0]
    inside = reds.max()
    assert np.any((reds > 0.0) & (reds < inside))


def test_unknown_style_lists_available(plane_scene):
    with pytest.raises(ValueError, match=r"unknown style 'nope'; available styles: \["):
        render(plane_scene, "nope", 8, 8)
    assert {"smooth", "toon"} <= set(list_styles())


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"n": 0}, r"n: expected an integer in \[1, 256\], got 0"),
        ({"t": 1.5}, r"t: expected a value in \[0, 1\], got 1.5"),
        ({"mode": "flat"}, r"mode: expected one of \['step', 'lake'\], got 'flat'"),
    ],
)
def test_toon_bad_parameters(params, match):
    with pytest.raises(ValueError, match=match):
        get_style("toon", **params)


def test_style_table_from_scene_file_form(plane_scene):
    img = render(plane_scene, {"name": "toon", "n": 2, "mode": "lake"}, 16, 12)
    assert img.rgba.shape == (12, 16, 4)


def test_scene_argument_type_error():
    with pytest.raises(TypeError, match="scene: expected a refnpr.scenes.Scene"):
        render(42, "toon", 8, 8)


def test_integer_flags_are_not_bools():
    with pytest.raises(TypeError, match="specular: expected a bool"):
        get_style("toon", specular=1)
