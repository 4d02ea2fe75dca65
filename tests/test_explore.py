"""``refnpr.explore``: ipywidgets controls for every registered style and the camera.

Oracles: the style's own validation (every slider end is a value the style accepts), the
rendered PNG bytes (a change re-renders a different picture) and the camera matrices.
"""

from __future__ import annotations

import subprocess
import sys
import warnings

import ipywidgets  # the `notebook` extra; the `test` extra installs it too
import numpy as np
import pytest

import refnpr
from refnpr.explore import Explorer, explore, orbit_camera, orbit_of
from refnpr.raster import Camera
from refnpr.styles import get_style, get_style_class, list_styles

W, H = 40, 30


@pytest.fixture(scope="module")
def explorers():
    return {name: explore("sphere", name, width=W, height=H) for name in list_styles()}


@pytest.mark.parametrize("name", sorted(list_styles()))
def test_widget_for_every_registered_style(explorers, name):
    e = explorers[name]
    assert isinstance(e, Explorer)
    assert isinstance(e.widget, ipywidgets.Box) and isinstance(e.image, ipywidgets.Image)
    assert e.image.value[:8] == b"\x89PNG\r\n\x1a\n", e.status.value
    assert set(e.camera_controls) == {"azimuth", "elevation", "distance", "fov_y"}
    values = get_style(name).params() if name != "contoured" else get_style("toon").params()
    for pname, control in e.controls.items():
        assert pname in values
        v = values[pname]
        if isinstance(v, bool):
            assert isinstance(control, ipywidgets.Checkbox)
        elif isinstance(v, int):
            assert isinstance(control, ipywidgets.IntSlider)
        elif isinstance(v, float):
            assert isinstance(control, ipywidgets.FloatSlider)
        if isinstance(control, (ipywidgets.IntSlider, ipywidgets.FloatSlider)):
            assert control.min <= v <= control.max
            style = name if name != "contoured" else "toon"
            with warnings.catch_warnings():  # advice on unused values is not a refusal
                warnings.simplefilter("ignore", UserWarning)
                for end in (control.min, control.max):
                    get_style(style, **{pname: end})  # the style accepts both ends
        if isinstance(control, ipywidgets.Dropdown):
            assert v in control.options
    # every numeric, boolean and listed-choice parameter got a control
    numeric = {k for k, v in values.items() if isinstance(v, (bool, int, float))}
    assert numeric <= set(e.controls)


def test_sliders_checkboxes_and_dropdowns_by_type(explorers):
    c = explorers["toon"].controls
    assert isinstance(c["n"], ipywidgets.IntSlider) and (c["n"].min, c["n"].max) == (1, 10)
    assert isinstance(c["t"], ipywidgets.FloatSlider) and (c["t"].min, c["t"].max) == (0, 1)
    assert isinstance(c["specular"], ipywidgets.Checkbox)
    assert isinstance(c["mode"], ipywidgets.Dropdown)
    assert tuple(c["mode"].options) == ("step", "lake")
    x = explorers["xtoon"].controls["texture"]
    assert isinstance(x, ipywidgets.Dropdown) and "loa_blur" in x.options


def test_changing_a_slider_re_renders():
    e = explore("sphere", "toon", width=W, height=H)
    before = e.image.value
    e.controls["n"].value = 5
    assert e.style.params()["n"] == 5
    assert e.image.value != before
    e.controls["mode"].value = "lake"
    assert e.style.mode == "lake"
    after = e.image.value
    e.controls["specular"].value = not e.controls["specular"].value
    assert e.image.value == after  # lake mode has no specular term: the same picture


def test_camera_sliders_move_the_camera():
    e = explore("sphere", "toon", width=W, height=H)
    cam0 = e.camera
    d0 = np.linalg.norm(cam0.eye - cam0.target)
    before = e.image.value
    e.camera_controls["azimuth"].value = 90.0
    assert e.image.value != before  # the lights stay in the world: the shading moves
    np.testing.assert_allclose(e.camera.target, cam0.target)
    np.testing.assert_allclose(np.linalg.norm(e.camera.eye - e.camera.target), d0, rtol=1e-9)
    assert np.linalg.norm(e.camera.eye - cam0.eye) > 0.5 * d0
    e.camera_controls["distance"].value = 2.0 * d0
    np.testing.assert_allclose(np.linalg.norm(e.camera.eye - e.camera.target), 2 * d0, 1e-6)
    small = e.image.value
    e.camera_controls["fov_y"].value = 20.0
    assert e.camera.fov_y == 20.0 and e.image.value != small


def test_orbit_round_trip_and_elevation():
    cam = Camera.look_at((3.0, 2.0, 4.0), (0.5, 0.0, 0.0), (0, 1, 0), 40.0, 0.1, 50.0)
    orbit = orbit_of(cam)
    again = orbit_camera(cam, orbit)
    np.testing.assert_allclose(again.view_matrix(), cam.view_matrix(), atol=1e-12)
    up = orbit_camera(cam, type(orbit)(**{**orbit.__dict__, "elevation": 89.0}))
    offset = up.eye - up.target
    assert offset[1] / np.linalg.norm(offset) == pytest.approx(np.sin(np.radians(89.0)))


def test_a_refused_value_keeps_the_picture_and_says_why():
    e = explore("sphere", "xtoon", width=W, height=H)
    before = e.image.value
    e.controls["light"].value = 7  # the scene has fewer lights
    assert e.image.value == before
    assert "light" in e.status.value


def test_refnpr_explore_is_the_function_and_lazy():
    assert refnpr.explore is explore or callable(refnpr.explore)
    code = "import sys, refnpr; print('ipywidgets' in sys.modules, 'refnpr.render' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


def test_missing_ipywidgets_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)  # import fails
    with pytest.raises(ImportError, match=r"optional extra `notebook`.*refnpr\[notebook\]"):
        explore("sphere", "toon", width=W, height=H)


def assert_within_declared_ranges(style_name, controls):
    """Every slider end lies in the range the style declares for its parameter."""
    params = get_style_class(style_name).PARAMS
    for pname, c in controls.items():
        p = params.by_name[pname]
        if not isinstance(c, (ipywidgets.IntSlider, ipywidgets.FloatSlider)):
            continue
        if p.lo is not None:
            assert c.min > p.lo if p.lo_open else c.min >= p.lo, (pname, c.min, p.bounds_text())
        if p.hi is not None:
            assert c.max < p.hi if p.hi_open else c.max <= p.hi, (pname, c.max, p.bounds_text())


@pytest.mark.parametrize("name", sorted(list_styles()))
def test_slider_ends_lie_in_the_declared_ranges(explorers, name):
    declared = name if name != "contoured" else "toon"  # its controls are its base style's
    assert_within_declared_ranges(declared, explorers[name].controls)


@pytest.fixture(scope="module")
def room():
    """The room's threshold style, source 'image': lines and stipple parameters unread."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return explore("veryovka_room", width=16, height=12)


def test_sliders_of_parameters_the_mode_ignores_keep_their_declared_ranges(room):
    c = room.controls
    assert room.spec["source"] == "image"
    assert (c["noise"].min, c["noise"].max) == (0.0, 1.0)
    assert (c["jitter"].min, c["jitter"].max) == (0.0, 0.4)
    assert 0.0 < c["period"].min < c["period"].value
    assert_within_declared_ranges("threshold", c)


def test_a_slider_end_stays_valid_in_the_mode_that_reads_it(room):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the mode ignores the first changes
        room.controls["jitter"].value = room.controls["jitter"].max
        room.controls["period"].value = room.controls["period"].min
        room.controls["source"].value = "stipple"
        room.controls["n"].value = 2
    assert "color:#b00" not in room.status.value, room.status.value
    assert room.style.p.jitter == 0.4 and room.style.p.period == room.controls["period"].min


def test_a_declared_choice_gets_a_dropdown_where_its_mode_ignores_it(explorers):
    c = explorers["threshold"].controls  # source 'lines': mip is read with images only
    assert isinstance(c["mip"], ipywidgets.Dropdown)
    assert tuple(c["mip"].options) == ("per_level", "trilinear")


def test_an_integer_slider_reaches_its_declared_minimum():
    e = explore("sphere", {"name": "toon", "n": 3}, width=8, height=8)
    assert (e.controls["n"].min, e.controls["n"].value) == (1, 3)


def test_numpy_scalars_in_the_table_hold_for_the_probes():
    # flow_max has no declared lower bound; the style refuses flow_max <= flow_min
    spec = {"name": "xtoon", "detail": "flow", "flow_min": np.float64(4.0)}
    e = explore("sphere", spec, width=8, height=8)
    low = e.controls["flow_max"].min
    assert 4.0 < low < e.controls["flow_max"].value
    get_style("xtoon", detail="flow", flow_min=4.0, flow_max=low)  # accepted
