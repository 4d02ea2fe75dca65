"""The ``tam`` and ``tamiss`` styles: registry, channels, parameters, compositing."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.render import render, required_channels
from refnpr.scenes import Light, load_scene
from refnpr.styles import ShadeContext, get_style, list_styles
from refnpr.styles.tam import TamStyle
from refnpr.styles.tamiss import TamissStyle

FIELD = {"directions": ["u", "v"], "period": 4.0}


def test_registered_with_descriptions():
    styles = list_styles()
    assert "TAMISS" in styles["tamiss"] and "RPTAM" in styles["tam"]
    assert isinstance(get_style("tamiss"), TamissStyle) and isinstance(get_style("tam"), TamStyle)


def test_requires_only_what_the_field_needs():
    base = {"uv", "duv_dx", "duv_dy", "tri_id", "mesh_id"}
    sc = load_scene("tamiss_sphere")
    smooth = {"bary", "normal", "position", "dposition_dx", "dposition_dy"}
    assert required_channels(sc, {"name": "tamiss"}) == base | smooth
    flat = {"derivatives": "flat"}
    motion = {"position", "dposition_dx", "dposition_dy"}  # average_frames (default 4) carries
    assert required_channels(sc, {"name": "tamiss", **flat}) == base | {"normal"} | motion
    one = {"average_frames": 1}
    assert required_channels(sc, {"name": "tamiss", **flat, **one}) == base | {"normal"}
    assert required_channels(sc, {"name": "tam", "constant_tone": 0.5, **flat}) == base
    assert required_channels(sc, {"name": "tam", "constant_tone": 0.5}) == base | smooth
    point = type(sc)(
        objects=sc.objects, camera=sc.camera, lights=(Light(kind="point", position=(0, 3, 3)),)
    )
    assert "position" in get_style("tamiss", **flat).requires(point)
    with_base = get_style("tamiss", base={"name": "toon"}, constant_tone=0.3, **flat, **one)
    assert with_base.requires(sc) == frozenset(base | get_style("toon").requires(sc))
    assert get_style("tam").raster_options(sc)["dtype"] == np.float64


@pytest.mark.parametrize(
    ("kwargs", "err", "match"),
    [
        ({"extent": "all"}, ValueError, r"extent: expected one of \['visible', 'range'"),
        ({"aggregation": "gpu"}, ValueError, r"aggregation: expected one of \['exact', 'hashed'\]"),
        ({"table_size": 1000}, ValueError, r"table_size: expected a power of two, got 1000"),
        ({"dtype": "float16"}, ValueError, r"dtype: expected one of \['float32', 'float64'\]"),
        ({"min_fragments": 3}, ValueError, r"min_fragments: expected an integer >= 4, got 3"),
        ({"ink": [1, 2, 3]}, ValueError, r"ink: expected 3 numbers in \[0, 1\]"),
        ({"brush": 3}, TypeError, r"brush: expected None"),
        ({"width": -1}, ValueError, r"width: expected a value in \(0, 64\], got -1.0"),
        ({"directions": [10**400]}, ValueError, r"directions: each layer is 'u', 'v' or"),
        (
            {"colour": 1},
            TypeError,
            r"unknown parameter\(s\) \['colour'\]; valid parameters: \[.*'ink'",
        ),
    ],
)
def test_tamiss_parameter_errors(kwargs, err, match):
    with pytest.raises(err, match=match):
        get_style("tamiss", **kwargs)


def test_tam_parameter_errors():
    with pytest.raises(ValueError, match=r"density_mode: expected one of \['clip', 'fade'\]"):
        get_style("tam", density_mode="smooth")
    with pytest.raises(ValueError, match=r"fade: expected a value in \(0, 1\], got 0.0"):
        get_style("tam", fade=0.0)


def test_params_round_trip_through_the_registry():
    st = get_style("tamiss", **FIELD, extent="overdraw", wobble=0.5, paper=0.9)
    again = get_style("tamiss", **{k: v for k, v in st.params().items() if k != "base"})
    assert again.params() == st.params()
    assert st.params()["directions"] == [0.0, 90.0] and st.params()["paper"] == [0.9] * 3


def test_strokes_cross_the_silhouette_only_with_overdraw():
    sc = load_scene("tamiss_sphere")
    kw = {**FIELD, "constant_tone": 0.9}
    out = {}
    for extent in ("range", "overdraw"):
        img, gb = render(sc, {"name": "tamiss", "extent": extent, **kw}, 96, 72,
                         return_gbuffer=True)  # fmt: skip
        out[extent] = 1.0 - img.rgba[..., :3].mean(-1)
    mask = gb["tri_id"] >= 0
    ring = ~mask & np.roll(mask, 3, 0) | ~mask & np.roll(mask, -3, 1)  # just outside
    assert out["overdraw"][ring].sum() > 2 * out["range"][ring].sum()


def test_composites_over_fill_base_and_contours():
    sc = load_scene("tamiss_sphere")
    ctx_img = {}
    for name, extra in {
        "bare": {},
        "fill": {"paper": [1.0, 0.9, 0.8]},
        "base": {"base": {"name": "toon", "n": 2}},
        "contours": {"contours": {"width": 1.5}},
    }.items():
        img, gb = render(sc, {"name": "tamiss", **FIELD, **extra}, 64, 48, return_gbuffer=True)
        ctx_img[name] = img.rgba
    mask = gb["tri_id"] >= 0
    bare, fill = ctx_img["bare"], ctx_img["fill"]
    paper = mask & (bare[..., :3].min(-1) > 0.999)  # object samples without ink
    assert paper.sum() > 100
    np.testing.assert_allclose(fill[paper][:, :3], np.tile([1.0, 0.9, 0.8], (paper.sum(), 1)),
                               atol=1e-6)  # fmt: skip
    assert not np.allclose(ctx_img["base"], bare)
    assert ctx_img["contours"][..., :3].sum() < bare[..., :3].sum()


def test_shade_output_contract():
    sc = load_scene("tamiss_torus_knot")
    from refnpr.raster import rasterize

    for style in (get_style("tamiss", **FIELD), get_style("tam", **FIELD, density_mode="clip")):
        gb = rasterize(sc, None, 48, 40, sorted(style.requires(sc)), 4,
                       **style.raster_options(sc))  # fmt: skip
        rgba = style.shade(ShadeContext(gb, sc))
        assert rgba.shape == (80, 96, 4) and rgba.dtype == np.float32
        assert np.all(np.isfinite(rgba)) and rgba.min() >= 0 and rgba.max() <= 1
        assert rgba[..., 3].max() > 0.5
        assert np.all(rgba[..., 3][gb["tri_id"] < 0] <= 1)


def test_tam_fade_tends_to_clip():
    sc = load_scene("tamiss_sphere")
    from refnpr.raster import rasterize

    clip = get_style("tam", **FIELD, density_mode="clip")
    gb = rasterize(sc, None, 64, 48, sorted(clip.requires(sc)), **clip.raster_options(sc))
    ctx = ShadeContext(gb, sc)
    a_clip = clip.ink_coverage(ctx)
    sharp = get_style("tam", **FIELD, density_mode="fade", fade=1e-12).ink_coverage(ctx)
    soft = get_style("tam", **FIELD, density_mode="fade", fade=0.5).ink_coverage(ctx)
    np.testing.assert_allclose(sharp, a_clip, atol=1e-9)
    assert a_clip.sum() > 20 and soft.sum() < a_clip.sum()  # fading lightens the partial strokes
