"""X-Toon attribute maps as images (Figs. 2-4): ``show`` draws D, 1 - D or the tone as grey, and
``distance`` picks either depth of Fig. 2 (view axis or eye) for the depth and focus maps; both
against independent oracles (a float64 ray cast of the floor, the paper's formulas)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.render import render, required_channels
from refnpr.styles import get_style

from .test_xtoon_style import (
    EYE,
    _oracle_depth,
    _oracle_focus,
    context,
    floor_rays,
    floor_scene,
    interior,
)

W, H = 64, 48


def _shown(scene, spec) -> tuple[np.ndarray, np.ndarray]:
    """The displayed (sRGB-encoded) red channel of a render, (H, W) float in [0, 1], and a mask
    of the pixels drawn grey and opaque (R = G = B, alpha 1)."""
    img = render(scene, spec, W, H).to_srgb8().astype(np.float64) / 255.0
    grey = (img[..., 0] == img[..., 1]) & (img[..., 1] == img[..., 2]) & (img[..., 3] == 1.0)
    return img[..., 0], grey


@pytest.mark.parametrize(
    "spec",
    [
        {"detail": "depth", "z_min": 4.0, "r": 3.0},
        {"detail": "focus", "focus_point": (0.5, 0.0, -6.0), "z_min": 1.0, "r": 3.0},
        {"detail": "orientation", "r": 2.0},
        {"detail": "highlight", "s": 4.0},
    ],
    ids=lambda s: s["detail"],
)
def test_show_draws_detail_inverse_detail_and_tone_as_displayed_grey(spec):
    scene = floor_scene()
    style = get_style("xtoon", **spec)
    f = style.fields(context(scene, style))
    covered = np.isfinite(f["detail"])
    for show, want in (
        ("detail", f["detail"]),
        ("inverse_detail", 1.0 - f["detail"]),
        ("tone", f["tone"]),
    ):
        grey, opaque_grey = _shown(scene, {"name": "xtoon", **spec, "show": show})
        assert np.all(opaque_grey[covered])
        # 8-bit sRGB rounding: the displayed value is the quantity within half a code
        np.testing.assert_allclose(grey[covered], want[covered], atol=0.5 / 255 + 1e-6)


def test_show_detail_spans_black_to_white_on_the_floor():
    scene = floor_scene()
    grey, _ = _shown(scene, {"name": "xtoon", "z_min": 4.0, "r": 3.0, "show": "detail"})
    _, z, inside = floor_rays(scene)
    ok = interior(inside)
    assert grey[ok].min() == 0.0 and grey[ok].max() == 1.0  # D = 0 far away, 1 near
    assert np.corrcoef(grey[ok], z[ok])[0, 1] < -0.9  # darker with distance: D falls


def test_depth_map_with_the_eye_distance_fig2a():
    scene = floor_scene()
    style = get_style("xtoon", detail="depth", distance="eye", z_min=4.0, r=3.0)
    got = style.fields(context(scene, style))["detail"]
    p, z_axis, inside = floor_rays(scene)
    ok = interior(inside)
    z_eye = np.linalg.norm(p - np.asarray(EYE), axis=-1)
    np.testing.assert_allclose(got[ok], _oracle_depth(z_eye[ok], 4.0, 3.0), atol=2e-6)
    # the two depths differ off the view axis (z_eye >= z_axis), so do their maps
    axis = get_style("xtoon", detail="depth", z_min=4.0, r=3.0)
    d_axis = axis.fields(context(scene, axis))["detail"]
    assert np.all(got[ok] <= d_axis[ok] + 1e-9)
    assert np.mean(np.abs(got[ok] - d_axis[ok]) > 0.01) > 0.2


def test_focus_map_with_the_view_axis_distance_fig2b():
    scene = floor_scene()
    c = (0.5, 0.0, -6.0)
    style = get_style("xtoon", detail="focus", distance="axis", focus_point=c, z_min=1.0, r=3.0)
    got = style.fields(context(scene, style))["detail"]
    _, z, inside = floor_rays(scene)
    ok = interior(inside)
    cam = scene.camera
    z_c = float(np.dot(np.asarray(c) - cam.eye, cam.forward))
    np.testing.assert_allclose(got[ok], _oracle_focus(z[ok], z_c, 1.0, 3.0), atol=1e-5)


def test_iso_detail_lines_are_straight_for_the_axis_and_curved_for_the_eye():
    """Fig. 2: on a floor seen by a level-rolled camera, the axis depth is constant along image
    rows of the floor, the eye distance is not (it grows towards the image sides)."""
    scene = floor_scene()
    rows = {}
    for distance in ("axis", "eye"):
        style = get_style("xtoon", detail="depth", distance=distance, z_min=3.0, r=8.0)
        d = style.fields(context(scene, style))["detail"]
        _, _, inside = floor_rays(scene)
        ok = interior(inside)
        spread = [np.ptp(d[y][ok[y]]) for y in range(H) if ok[y].sum() > W // 2]
        rows[distance] = max(spread)
    assert rows["axis"] < 1e-6
    assert rows["eye"] > 0.02


@pytest.mark.parametrize(
    "spec, has, lacks",
    [
        ({"detail": "depth"}, "depth", "position"),
        ({"detail": "depth", "distance": "eye"}, "position", "depth"),
        ({"detail": "focus", "focus_point": (0.0, 0.0, -6.0)}, "position", "depth"),
        (
            {"detail": "focus", "focus_point": (0.0, 0.0, -6.0), "distance": "axis"},
            "depth",
            "position",
        ),
    ],
)
def test_the_distance_decides_the_channel(spec, has, lacks):
    ch = required_channels(floor_scene(), get_style("xtoon", **spec))
    assert has in ch and lacks not in ch


def test_vertex_mode_uses_the_chosen_distance():
    scene = floor_scene(segments=4)
    (mesh,) = scene.world_meshes()
    cam = scene.camera
    z = {
        "axis": (mesh.positions - cam.eye) @ cam.forward,
        "eye": np.linalg.norm(mesh.positions - cam.eye, axis=-1),
    }
    for distance, zd in z.items():
        style = get_style("xtoon", distance=distance, z_min=4.0, r=3.0, detail_mode="vertex")
        (attrs,) = style.vertex_attributes(scene, width=W, height=H)
        np.testing.assert_allclose(attrs["xtoon_d"], _oracle_depth(zd, 4.0, 3.0), atol=1e-12)
    assert np.abs(_oracle_depth(z["axis"], 4, 3) - _oracle_depth(z["eye"], 4, 3)).max() > 0.05


def test_params_summary_names_the_resolved_distance_and_show():
    assert get_style("xtoon").params()["distance"] == "axis"
    p = get_style("xtoon", detail="focus", focus_point=(0, 0, -5)).params()
    assert p["distance"] == "eye" and p["show"] == "color"
    assert "distance" not in get_style("xtoon", detail="orientation").params()


@pytest.mark.parametrize(
    "params, match",
    [
        ({"distance": "euclid"}, r"distance: expected one of \['axis', 'eye'\], got 'euclid'"),
        ({"show": "D"}, r"show: expected one of \['color', 'detail', 'inverse_detail', 'tone'\]"),
    ],
)
def test_bad_distance_and_show_raise(params, match):
    with pytest.raises(ValueError, match=match):
        get_style("xtoon", **params)


def test_distance_is_ignored_with_a_warning_by_maps_without_depth():
    with pytest.warns(UserWarning, match=r"distance: 'eye' is ignored with detail='orientation'"):
        style = get_style("xtoon", detail="orientation", distance="eye")
    assert "distance" not in style.params()


def test_show_tone_is_n_dot_l():
    scene = floor_scene()
    grey, _ = _shown(scene, {"name": "xtoon", "show": "tone"})
    _, _, inside = floor_rays(scene)
    n_dot_l = 1.0 / math.sqrt(0.3**2 + 1.0 + 0.4**2)  # floor normal (0, 1, 0), LIGHT
    ok = interior(inside)
    np.testing.assert_allclose(grey[ok], n_dot_l, atol=0.5 / 255 + 1e-6)


def test_texture_sheet_draws_each_figures_presets_with_d_up():
    from refnpr.styles.xtoon.sheet import FIGURE_TEXTURES, texture_sheet

    w, h, gap = 40, 30, 2
    sheet = texture_sheet(width=w, height=h, gap=gap)
    n_cols = max(len(v) for v in FIGURE_TEXTURES.values())
    assert sheet.shape == (gap + len(FIGURE_TEXTURES) * (h + gap), gap + n_cols * (w + gap), 4)
    # Fig. 11a plastic (row 6, panel 1): white above tone 1 - 0.6 D, so the top row (D = 1)
    # is white from 40% of the tone axis on and the bottom row (D = 0) at most in its last texel
    r = list(FIGURE_TEXTURES).index("11a")
    y, x = gap + r * (h + gap), gap
    panel = sheet[y : y + h, x : x + w, :3].astype(int)
    white = np.all(panel >= 254, axis=-1)
    assert white[0].mean() == pytest.approx(0.6, abs=2 / w) and white[-1].mean() <= 1 / w
    with pytest.raises(ValueError, match="width: expected a positive integer"):
        texture_sheet(width=0)
