"""The styles' intermediates as EXR passes (``render(..., passes=True)``): each style keeps the
values its formulas computed on the way to the colour, and each is checked against an
independent float64 evaluation from the G-buffer (tone, X-Toon's D) or against the colour the
same sample got (the threshold a pixel was compared with, the stroke ids of fig. 6)."""

from __future__ import annotations

import numpy as np
import pytest

OpenEXR = pytest.importorskip("OpenEXR")

from refnpr.render import render  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402
from refnpr.styles import get_style  # noqa: E402

W, H = 40, 30
GEOMETRY = {"depth", "position", "tri_id", "mesh_id", "normal", "uv"}


def _render(style, **params):
    scene = load_scene("sphere")
    st = get_style(style, **params)
    image, gb = render(scene, st, W, H, 1, passes=True, return_gbuffer=True)
    plain = render(scene, st, W, H, 1)
    np.testing.assert_array_equal(image.rgba, plain.rgba)  # keeping them changes no pixel
    return scene, st, image, gb


def _n_dot_l(scene, gb):
    """max(N.L, 0) of unit vectors from the G-buffer's normals and the first (directional)
    light, float64."""
    light = scene.lights[0]
    assert light.kind == "directional"
    n = gb["normal"].astype(np.float64)
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    return np.maximum(n @ np.asarray(light.direction, dtype=np.float64), 0.0)


def test_every_style_declares_what_it_keeps_and_keeps_exactly_that(tmp_path):
    for style in ("smooth", "toon", "xtoon", "threshold", "halftone", "tam", "tamiss"):
        scene, st, image, gb = _render(style)
        kept = set(image.passes) - set(gb.channels)
        assert kept == set(type(st).INTERMEDIATES), style
        covered = gb["mesh_id"] < 0
        for name in kept:
            empty = -1 if image.passes[name].dtype.kind == "i" else 0
            assert np.all(image.passes[name][covered] == empty), (style, name)
        assert GEOMETRY <= set(image.passes)


def test_xtoon_tone_and_detail_are_the_lookups_coordinates():
    r = 2.5
    scene, st, image, gb = _render("xtoon", detail="orientation", r=r)
    covered = gb["mesh_id"] >= 0
    tone = _n_dot_l(scene, gb)
    np.testing.assert_allclose(image.passes["tone"][covered], tone[covered], atol=2e-6)
    # D = |n.v| ** r (sec. 3.2) with v towards the eye
    eye = np.asarray(scene.camera.eye, dtype=np.float64)
    n = gb["normal"].astype(np.float64)
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    v = eye - gb["position"].astype(np.float64)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    d = np.abs(np.sum(n * v, axis=-1)) ** r
    np.testing.assert_allclose(image.passes["detail"][covered], d[covered], atol=1e-5)
    assert np.ptp(image.passes["detail"][covered]) > 0.5  # the map varies over the sphere


def test_threshold_tone_and_threshold_decide_each_pixel():
    t = 0.37
    scene, st, image, gb = _render("threshold", source="constant", t=t, n=1, specular=False)
    covered = gb["mesh_id"] >= 0
    assert np.all(image.passes["threshold"][covered] == np.float32(t))
    tone = _n_dot_l(scene, gb)
    np.testing.assert_allclose(image.passes["tone"][covered], tone[covered], atol=2e-6)
    # eq. 3: a lit sample where f_d > t, an ambient one where below; off the boundary
    lum = image.rgba[..., :3].sum(axis=-1)
    clear = covered & (np.abs(tone - t) > 1e-4)
    above = lum[clear & (tone > t)]
    below = lum[clear & (tone < t)]
    assert above.size > 20 and below.size > 20
    assert above.min() > below.max()


def test_threshold_lines_keep_a_threshold_per_sample_in_the_unit_interval():
    scene, st, image, gb = _render("threshold", source="lines")
    covered = gb["mesh_id"] >= 0
    thr = image.passes["threshold"][covered]
    assert thr.min() >= 0.0 and thr.max() <= 1.0 and np.ptp(thr) > 0.5  # the hatching varies


def test_halftone_pixels_are_paper_exactly_where_intensity_clears_the_screen():
    scene, st, image, gb = _render("halftone", threshold="binary", specular=False)
    covered = gb["mesh_id"] >= 0
    inten = image.passes["intensity"].astype(np.float64)
    screen = image.passes["threshold"].astype(np.float64)
    # the target intensity: Rec. 709 luminance of eq. 1 (ambient + diffuse), clipped
    m = scene.objects[0].material
    f_d = _n_dot_l(scene, gb)[..., None]
    rgb = np.asarray(m.ambient) + np.asarray(m.diffuse) * f_d * np.asarray(scene.lights[0].color)
    lum = np.clip(rgb @ np.array([0.2126, 0.7152, 0.0722]), 0.0, 1.0)
    np.testing.assert_allclose(inten[covered], lum[covered], atol=1e-5)
    # sec. 3.1: white where screen + intensity > 1
    paper = np.all(image.rgba[..., :3] == np.float32(1.0), axis=-1)
    clear = covered & (np.abs(screen + inten - 1.0) > 1e-5)
    assert np.array_equal(paper[clear], (screen + inten > 1.0)[clear])
    assert 10 < paper[clear].sum() < clear.sum() - 10  # both outcomes occur


@pytest.mark.parametrize("options", [{}, {"mip": "per_level", "tone_correct": True}], ids=str)
def test_halftone_keeps_its_intermediates_from_the_color_pass(monkeypatch, options):
    """One pass of the object kernel gives the image and its intermediates, equal to the
    images that show='intensity' and show='screen' draw."""
    from refnpr.styles.halftone import shading

    passes = []
    run = shading._shade_objects
    monkeypatch.setattr(shading, "_shade_objects", lambda *a: passes.append(a[3]) or run(*a))
    style = {"name": "halftone", "screen": "gravel", **options}  # a dither screen
    image = render("halftone_teapot", style, 64, 48, 4, passes=True)
    assert passes == ["color"]
    for name, show in (("intensity", "intensity"), ("threshold", "screen")):
        drawn = render("halftone_teapot", {**style, "show": show}, 64, 48, 4, passes=True)
        assert np.array_equal(image.passes[name], drawn.passes[name]), name


@pytest.mark.parametrize("height", [1, 2])
def test_halftone_on_a_grid_of_one_or_two_rows_gives_the_image_with_or_without_passes(
    monkeypatch, height
):
    """Without intermediates the kernel gets a ``raw`` stand-in that no sample grid matches,
    even one of a single row (a (1, 1, 3) stand-in matched it: the kernel then wrote each
    sample's values past its end)."""
    from refnpr.styles.halftone import shading

    raws = []
    run = shading._shade_objects
    monkeypatch.setattr(shading, "_shade_objects", lambda *a: raws.append(a[5].shape) or run(*a))
    plain = render("halftone_teapot", "halftone", 64, height, 1)
    assert raws and all(shape[0] != height for shape in raws), raws
    with_passes = render("halftone_teapot", "halftone", 64, height, 1, passes=True)
    assert np.array_equal(plain.rgba, with_passes.rgba)
    assert set(with_passes.passes) >= {"intensity", "threshold"}


def test_tamiss_stroke_ids_match_its_ids_view_and_survive_the_exr(tmp_path):
    from refnpr.styles.tamiss.show import id_colors

    scene, st, image, gb = _render("tamiss")
    ids = image.passes["stroke_id"]
    assert ids.dtype == np.int64 and (ids >= 0).sum() > 50
    # show="ids" false-colours the same first-gathered id of each sample
    view = render(scene, get_style("tamiss", show="ids"), W, H, 1)
    seen = ids >= 0
    np.testing.assert_allclose(
        view.rgba[..., :3][seen], id_colors(ids[seen]).astype(np.float32), atol=1e-6
    )
    path = tmp_path / "t.exr"
    image.save(path)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.array(c.pixels) for k, c in f.channels().items()}
    assert ch["stroke_id.lo"].dtype == np.uint32 and ch["stroke_id.hi"].dtype == np.uint32
    back = ((ch["stroke_id.hi"].astype(np.uint64) << np.uint64(32)) | ch["stroke_id.lo"]).view(
        np.int64
    )
    np.testing.assert_array_equal(back, ids)
    d = ch["darkness"][seen]
    assert d.min() >= 0.0 and d.max() <= 1.0


def test_toon_tone_is_the_step_of_the_tone():
    scene, st, image, gb = _render("toon", n=3, t=0.5, specular=False)
    covered = gb["mesh_id"] >= 0
    tone = image.passes["tone"][covered].astype(np.float64)
    step = image.passes["toon_tone"][covered].astype(np.float64)
    np.testing.assert_allclose(tone, _n_dot_l(scene, gb)[covered], atol=2e-6)
    # eq. 4 with a constant t = 0.5: T_n = (floor(x n) + [Frac(x n) > 0.5]) / n
    xn = tone * 3
    frac = xn - np.floor(xn)
    clear = np.abs(frac - 0.5) > 1e-4
    want = (np.floor(xn) + (frac > 0.5)) / 3
    np.testing.assert_allclose(step[clear], want[clear], atol=1e-6)


def test_a_base_style_under_strokes_keeps_its_own_intermediates_beside_theirs():
    scene, st, image, gb = _render("tam", base="xtoon")
    assert {"darkness", "base.tone", "base.detail"} <= set(image.passes)
    assert "tone" not in image.passes
    # the same name in both is two channels, not one overwriting the other
    scene, st, image, gb = _render("tam", base={"name": "tam", "density_mode": "fade"})
    assert {"darkness", "base.darkness"} <= set(image.passes)


@pytest.mark.parametrize("gather_scale", [1, 3])
def test_tamiss_darkness_on_a_gather_grid_of_another_size(gather_scale):
    scene = load_scene("sphere")
    style = get_style("tamiss", gather_scale=gather_scale)
    image, gb = render(scene, style, 16, 12, 4, passes=True, return_gbuffer=True)
    d = image.passes["darkness"]
    assert d.shape == (12, 16)
    # each covered sample takes the gather sample holding its centre; the pass is sample (0, 0)
    # of each pixel's 2 x 2
    covered = (gb["mesh_id"] >= 0)[0::2, 0::2]
    inner = (gb["mesh_id"] >= 0).reshape(12, 2, 16, 2).all(axis=(1, 3))
    assert np.all(d[~covered] == 0) and (d[inner] > 0).mean() > 0.9 and inner.sum() > 50


def test_refnpr_styles_lists_a_styles_intermediates(capsys):
    from refnpr.cli import main

    assert main(["styles", "halftone"]) == 0
    out = capsys.readouterr().out
    assert "intermediates (EXR passes" in out
    for name in get_style("halftone").INTERMEDIATES:
        assert f"  {name} " in out
    assert main(["styles", "halftone", "--markdown"]) == 0  # the docs' tables stay tables
    assert "intermediates" not in capsys.readouterr().out
