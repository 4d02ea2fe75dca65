"""Fuzzing every style's parameters: a hostile value gives a clear error or a finite image.

For each registered style, hypothesis draws a parameter (from ``parameters()``) and a hostile
value (finite extremes, NaN, inf, wrong types, empty and huge sequences, tables) and renders a
tiny image of a scene that suits the style. The outcome owed is either a ``ValueError`` or
``TypeError`` whose message names the parameter, or an image whose RGBA is finite: never
another exception, a message about an internal variable, or a NaN image.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.render import render
from refnpr.styles import get_style, list_styles

#: A scene that suits each style (textured where the style reads uv).
SCENES = {
    "contoured": "sphere",
    "halftone": "halftone_sphere",
    "smooth": "sphere",
    "tam": "tamiss_sphere",
    "tamiss": "tamiss_sphere",
    "threshold": "room",
    "toon": "sphere",
    "xtoon": "sphere",
}

#: Modes whose own parameters are only read there (drawn as a base for the parameter).
MODES: dict[str, list[dict[str, Any]]] = {
    "contoured": [{}],
    "halftone": [{}, {"threshold": "binary"}, {"c": "auto"}, {"mip": "per_level"}],
    "smooth": [{}],
    "tam": [{}, {"density_mode": "clip"}],
    "tamiss": [{}, {"aggregation": "hashed"}, {"extent": "overdraw"}],
    "threshold": [
        {},
        {"source": "image"},
        {"source": "stipple"},
        {"filter": "pcf"},
        {"filter": "analytic"},
        {"noise": 0.5, "directions": [0, 90]},
    ],
    "toon": [{}, {"mode": "lake"}],
    "xtoon": [
        {},
        {"detail": "focus", "focus_point": [0.0, 0.0, 0.0]},
        {"detail": "orientation"},
        {"detail": "highlight"},
        {"shape": "smoothed", "shape_blend": "pixel"},
    ],
}

NAN, INF = float("nan"), float("inf")
HUGE_LIST = [0.5] * 10_000
HOSTILE: list[Any] = [
    0,
    -1,
    1e300,
    -1e300,
    1e-300,
    10**400,  # an integer beyond the float range
    [10**400, 0, 0],
    NAN,
    INF,
    -INF,
    True,
    "",
    "x",
    None,
    [],
    [NAN],
    HUGE_LIST,
    {},
    {"a": {"b": 1}},
]

values = st.one_of(
    st.sampled_from(HOSTILE),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.text(max_size=4),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=5),
)


def test_every_style_is_fuzzed():
    assert set(SCENES) == set(list_styles()) == set(MODES)


def _params(style: str) -> tuple[str, ...]:
    return type(get_style(style)).parameters()


def check_outcome(style: str, params: dict[str, Any], named: set[str]) -> None:
    """Render ``params`` with ``style`` at 16x16: a ValueError/TypeError naming one of ``named``,
    or a finite image."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # parameters a mode ignores
            warnings.simplefilter("ignore", RuntimeWarning)
            image = render(SCENES[style], {"name": style, **params}, 16, 16)
    except (ValueError, TypeError) as exc:
        msg = str(exc)
        assert any(n in msg for n in named), f"{style} {params!r}: message names none of {named}"
        return
    assert np.all(np.isfinite(image.rgba)), f"{style} {params!r}: non-finite image"


@pytest.mark.parametrize("style", sorted(SCENES))
@given(data=st.data())
def test_one_hostile_parameter(style: str, data: st.DataObject) -> None:
    param = data.draw(st.sampled_from(_params(style)), label="param")
    value = data.draw(values, label="value")
    check_outcome(style, {param: value}, {param})


@pytest.mark.parametrize("style", sorted(SCENES))
@given(data=st.data())
def test_one_hostile_parameter_in_each_mode(style: str, data: st.DataObject) -> None:
    mode = data.draw(st.sampled_from(MODES[style]), label="mode")
    param = data.draw(st.sampled_from(_params(style)), label="param")
    value = data.draw(values, label="value")
    # a mode key overridden by the drawn value, or refused because of it, may be the one named
    check_outcome(style, {**mode, param: value}, {param, *mode})


@pytest.mark.stress
@pytest.mark.parametrize("style", sorted(SCENES))
@given(data=st.data())
def test_several_hostile_parameters(style: str, data: st.DataObject) -> None:
    mode = data.draw(st.sampled_from(MODES[style]), label="mode")
    names = data.draw(
        st.lists(st.sampled_from(_params(style)), min_size=2, max_size=4, unique=True),
        label="params",
    )
    params = {**mode, **{n: data.draw(values, label=n) for n in names}}
    check_outcome(style, params, set(params))
