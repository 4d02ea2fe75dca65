"""One name per concept across styles; the old names still work, with a DeprecationWarning.

The table ``CONCEPTS`` is the rule: every style that has the concept takes it under that name.
"""

from __future__ import annotations

import dataclasses
import pickle
import warnings

import numpy as np
import pytest

from refnpr.render import render
from refnpr.scenes import Material, Scene, SceneObject
from refnpr.styles import get_style, style_from_spec
from refnpr.styles.contours import CONTOURS, ContourLayer
from refnpr.styles.halftone import HalftoneStyle, screens
from refnpr.styles.tam import TamStyle
from refnpr.styles.tamiss import TamissStyle
from refnpr.styles.threshold import ThresholdStyle
from refnpr.styles.xtoon import XToonStyle

from .test_threshold_tone import flat_scene


def accepted(cls) -> set[str]:
    """Every parameter name a style (or the contour layer) takes."""
    if cls is ContourLayer:
        return set(CONTOURS.names)
    return set(cls.parameters())


#: concept -> (its one name, the classes that have the concept)
CONCEPTS = {
    "uv multiplier in place of the material's": ("uv_scale", [ThresholdStyle, HalftoneStyle]),
    "colour of lines and strokes": ("ink", [HalftoneStyle, TamStyle, TamissStyle, ContourLayer]),
    "colour of the paper": ("paper", [HalftoneStyle, TamStyle, TamissStyle]),
    "hatching directions": ("directions", [ThresholdStyle, TamStyle, TamissStyle]),
    "per-level vs trilinear thresholding": ("mip", [ThresholdStyle, HalftoneStyle]),
    "per-level CDF tone correction": ("tone_correct", [ThresholdStyle, HalftoneStyle]),
    "draw an intermediate stage or map instead of the picture": (
        "show",
        [HalftoneStyle, XToonStyle, TamissStyle],
    ),
}
#: concept -> (its one name, the one value meaning "the style's picture", the classes)
SAME_DEFAULT = {"show": ("color", [HalftoneStyle, XToonStyle, TamissStyle])}
OLD_NAMES = {"scale", "angles", "pcf_levels", "equalize", "fill", "color"}


@pytest.mark.parametrize("concept", sorted(CONCEPTS))
def test_one_name_per_concept(concept):
    name, classes = CONCEPTS[concept]
    for cls in classes:
        params = accepted(cls)
        assert name in params, f"{cls.__name__} calls '{concept}' something else"
        assert not params & OLD_NAMES, (cls.__name__, params & OLD_NAMES)


@pytest.mark.parametrize("name", sorted(SAME_DEFAULT))
def test_one_default_value_per_concept(name):
    value, classes = SAME_DEFAULT[name]
    for cls in classes:
        assert cls().params()[name] == value, cls.__name__


# (style, old params, the same with current names)
RENAMES = [
    ("threshold", {"angles": [0.0, 90.0]}, {"directions": [0.0, 90.0]}),
    ("threshold", {"pcf_levels": 1}, {"mip": "trilinear"}),
    ("threshold", {"pcf_levels": 2}, {"mip": "per_level"}),
    ("halftone", {"equalize": True}, {"tone_correct": True}),
    ("tam", {"fill": [0.9, 0.8, 0.7]}, {"paper": [0.9, 0.8, 0.7]}),
    ("tamiss", {"fill": 0.5}, {"paper": 0.5}),
]
#: old name -> the other parameters under which the style reads it (else it is only warned about)
READ_WITH = {"pcf_levels": {"source": "image", "filter": "pcf"}}


@pytest.mark.parametrize("style, old, new", RENAMES)
def test_old_names_warn_and_mean_the_same(style, old, new):
    (old_name,) = old
    ctx = READ_WITH.get(old_name, {})
    with pytest.warns(DeprecationWarning, match=rf"parameter '{old_name}' is deprecated, use"):
        by_old = get_style(style, **ctx, **old)
    assert by_old.params() == get_style(style, **ctx, **new).params()
    cls = type(by_old)
    with pytest.warns(DeprecationWarning, match=rf"'{old_name}' is deprecated"):
        direct = cls(**ctx, **old)  # direct construction goes through the same rename
    assert direct.params() == by_old.params()


@pytest.mark.parametrize("style, old, new", RENAMES)
def test_old_and_new_name_together_is_an_error(style, old, new):
    (old_name,) = old
    (new_name,) = new
    with pytest.raises(TypeError, match=rf"got both '{old_name}' .* and '{new_name}'"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            get_style(style, **old, **new)


def test_current_names_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        get_style("threshold", directions=["u", "v"], uv_scale=[2, 3])
        get_style("threshold", source="image", filter="pcf", mip="trilinear")
        get_style("halftone", tone_correct=True, screen={"kind": "dither", "rank_equalize": False})
        get_style("tamiss", paper=0.5)
        style_from_spec({"name": "toon", "contours": {"ink": [1.0, 0.0, 0.0]}})


def test_threshold_directions_take_u_and_v_as_tamiss_does():
    assert ThresholdStyle(directions=["u", "v", 30]).p.directions == (0.0, 90.0, 30.0)
    assert ThresholdStyle(directions="v").p.directions == (90.0,)


def _scene_with_material_scale(su: float) -> Scene:
    base = flat_scene(0.5)
    obj = base.objects[0]
    mat = dataclasses.replace(obj.material, uv_scale=(su, su))
    return dataclasses.replace(base, objects=(SceneObject(obj.mesh, material=mat),))


def test_threshold_scale_keeps_its_old_meaning_while_deprecated():
    """``scale`` multiplied the material's uv_scale; ``uv_scale`` replaces it (as halftone's)."""
    lines = dict(source="lines", period=4.0, specular=False)
    unit = _scene_with_material_scale(1.0)
    with pytest.warns(DeprecationWarning, match=r"'scale' is deprecated, use 'uv_scale'"):
        old = ThresholdStyle(**lines, scale=2.0)
    new = ThresholdStyle(**lines, uv_scale=2.0)
    a = render(unit, old, 64, 64).rgba
    b = render(unit, new, 64, 64).rgba
    np.testing.assert_array_equal(a, b)  # where the material's uv_scale is 1 they agree
    doubled = _scene_with_material_scale(1.5)
    c = render(doubled, old, 64, 64).rgba  # 2 x 1.5
    d = render(doubled, ThresholdStyle(**lines, uv_scale=3.0), 64, 64).rgba
    e = render(doubled, new, 64, 64).rgba  # replaces: 2
    np.testing.assert_array_equal(c, d)
    np.testing.assert_array_equal(e, b)
    assert np.abs(c - e).max() > 0.5  # the two meanings differ, and the test can tell
    with pytest.raises(TypeError, match=r"got both 'scale' \(deprecated\) and 'uv_scale'"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            ThresholdStyle(scale=2.0, uv_scale=2.0)


def test_uv_scale_is_validated_alike_in_both_styles():
    for cls in (ThresholdStyle, HalftoneStyle):
        with pytest.raises(ValueError, match=r"uv_scale: expected a positive number or two"):
            cls(uv_scale=[1.0, -1.0])


def test_contour_color_is_ink():
    with pytest.warns(DeprecationWarning, match=r"contours: parameter 'color' is deprecated"):
        styled = style_from_spec({"name": "toon", "contours": {"color": [1.0, 0.0, 0.0]}})
    assert styled.layer.ink == [1.0, 0.0, 0.0] or tuple(styled.layer.ink) == (1.0, 0.0, 0.0)
    assert styled.params()["contours"]["ink"] == list(styled.layer.ink)
    with pytest.warns(DeprecationWarning, match=r"'color' is deprecated, use 'ink'"):
        layer = ContourLayer(color=(0.0, 1.0, 0.0))
    assert layer == ContourLayer(ink=(0.0, 1.0, 0.0))
    with pytest.raises(TypeError, match=r"got both 'color' .* and 'ink'"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            style_from_spec({"name": "toon", "contours": {"color": [1, 0, 0], "ink": [0, 0, 1]}})


def test_dither_screen_uniform_is_rank_equalize():
    with pytest.warns(DeprecationWarning, match=r"screen: parameter 'uniform' is deprecated"):
        spec = screens.normalize_spec({"kind": "dither", "texture": "brick", "uniform": False})
    assert spec == screens.normalize_spec(
        {"kind": "dither", "texture": "brick", "rank_equalize": False}
    )
    assert "uniform" not in spec


def test_material_uv_scale_default_is_one():
    # the agreement of `scale` and `uv_scale` on the golden scenes rests on this default
    assert Material().uv_scale == (1.0, 1.0)


# ---------------------------------------------------------------------------------------------
# where the warnings point, unknown names, odd values
# ---------------------------------------------------------------------------------------------
OLD_SPELLINGS = [
    lambda: get_style("threshold", angles=[0.0]),
    lambda: style_from_spec({"name": "threshold", "pcf_levels": 1, **READ_WITH["pcf_levels"]}),
    lambda: ThresholdStyle(scale=2.0),
    lambda: HalftoneStyle(equalize=True),
    lambda: HalftoneStyle(screen={"kind": "dither", "texture": "brick", "uniform": True}),
    lambda: get_style("halftone", objects={"a": {"screen": {"kind": "dither", "uniform": True}}}),
    lambda: style_from_spec({"name": "tam", "fill": 0.5}),
    lambda: style_from_spec({"name": "toon", "contours": {"color": [1.0, 0.0, 0.0]}}),
    lambda: get_style("contoured", contours={"color": [1.0, 0.0, 0.0]}),
    lambda: ContourLayer(color=(1.0, 0.0, 0.0)),
]


@pytest.mark.parametrize("make", OLD_SPELLINGS)
def test_deprecation_warnings_point_at_the_caller(make):
    """Attributed to the first frame outside refnpr, so Python's default filters show them in a
    user's script (and for the `refnpr` command, whose frames are refnpr's, at its entry point)."""
    with pytest.warns(DeprecationWarning, match=r"is deprecated, use") as record:
        make()
    assert {w.filename for w in record} == {__file__}


@pytest.mark.parametrize(
    "name", ["smooth", "toon", "threshold", "halftone", "xtoon", "tam", "tamiss", "contoured"]
)
def test_unknown_parameter_lists_the_valid_ones(name):
    cls = type(get_style(name))
    valid = cls.parameters()
    assert valid and "bogus" not in valid
    with pytest.raises(
        TypeError,
        match=rf"style '{name}': unknown parameter\(s\) \['bogus'\]; valid parameters: \[",
    ):
        get_style(name, bogus=1)
    with pytest.raises(TypeError, match=r"unknown parameter\(s\) \['bogus'\]"):
        cls(bogus=1)  # direct construction too
    for param in valid:  # every listed name is accepted at all (its default or None is valid)
        assert param.isidentifier()


def test_threshold_directions_accept_arrays_and_single_values():
    assert ThresholdStyle(directions=np.array([0.0, 90.0])).p.directions == (0.0, 90.0)
    assert ThresholdStyle(directions=45).p.directions == (45.0,)
    with pytest.warns(DeprecationWarning):
        assert ThresholdStyle(angles=np.array([30, -60])).p.directions == (30.0, -60.0)


def test_contour_layer_color_attribute_and_pickles():
    layer = ContourLayer(ink=(0.0, 0.0, 1.0))
    with pytest.warns(DeprecationWarning, match=r"attribute 'color' is deprecated, use 'ink'"):
        assert layer.color == (0.0, 0.0, 1.0)
    assert ContourLayer(**{**layer.params(), "width": 3.0}).ink == (0.0, 0.0, 1.0)
    assert layer == pickle.loads(pickle.dumps(layer))


def test_halftone_params_use_current_screen_keys():
    with pytest.warns(DeprecationWarning):
        old = HalftoneStyle(screen={"kind": "dither", "texture": "brick", "uniform": False})
    new = HalftoneStyle(screen={"kind": "dither", "texture": "brick", "rank_equalize": False})
    assert old.params() == new.params()


@pytest.mark.parametrize("name", ["items", "replace", "as_dict", "given"])
def test_a_parameter_may_not_take_the_name_of_a_values_attribute(name):
    from refnpr.styles._declare import Param, Params

    with pytest.raises(ValueError, match=rf"\['{name}'\] are attributes of Values"):
        Params("x", Param(name, 1, "doc"), module="m")
