"""A still render of an animated scene is its frame 0 (DESIGN: a still is frame 0 of a one-frame
sequence), whatever the file's static values say."""

from __future__ import annotations

import numpy as np

from refnpr.render import RenderContext, render, required_channels
from refnpr.scenes.toml_format import parse_scene, parse_toml_bytes

_SCENE = b"""
name = "moving"
[camera]
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
[[object]]
name = "ball"
mesh = "uv_sphere"
[style]
name = "toon"
n = 3
[animation]
frames = 4
[[animation.track]]
target = "camera.eye"
keys = [{ frame = 0, value = [1.5, 0.0, 4.0] }, { frame = 3, value = [-1.5, 0.0, 4.0] }]
[[animation.track]]
target = "style.n"
keys = [{ frame = 0, value = 2 }, { frame = 3, value = 5 }]
"""


def _scene():
    return parse_scene(parse_toml_bytes(_SCENE, "moving.toml"), source="moving.toml")


def test_render_of_an_animated_scene_is_frame_0():
    scene = _scene()
    assert scene.animation is not None
    frame0 = scene.at(0)
    assert not np.allclose(frame0.camera.eye, scene.camera.eye)  # the case is not trivial
    a = render(scene, None, 48, 32)
    b = render(frame0, None, 48, 32)
    static = render(frame0, None, 48, 32, camera=scene.camera)
    assert np.array_equal(a.rgba, b.rgba)
    assert not np.array_equal(a.rgba, static.rgba)
    ctx = RenderContext(scene, None, 48, 32)
    assert np.array_equal(ctx.render().rgba, b.rgba)
    assert ctx.style.params()["n"] == 2  # the style table of frame 0
    assert required_channels(scene) == required_channels(frame0)
