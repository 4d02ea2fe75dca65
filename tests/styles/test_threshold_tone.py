"""Tone fidelity of the threshold style (Veryovka 2002): a flat, evenly lit plane must render the
target intensity on average with every tone-preserving threshold source, and the paper's
multi-scale blend (eq. 8) visibly drifts where the corrected one (``uniform=True``) does not.

The oracle is the target itself: eq. 1 is x everywhere on the plane (n.l = x, no ambient or
specular term), so the mean of the rendered image must be x.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.raster import Camera
from refnpr.render import render
from refnpr.scenes import Light, Material, Scene, SceneObject
from refnpr.scenes.room import plane
from refnpr.styles.threshold import ThresholdStyle

SIZE = 160
FOV = 40.0
DIST = 5.0
#: pixels per world unit on the plane (fronto-parallel, so constant)
PPU = SIZE / (2 * DIST * math.tan(math.radians(FOV / 2)))
LEVELS = (0.1, 0.25, 0.5, 0.75, 0.9)


def flat_scene(x: float, *, distance: float = DIST, texture: str | None = None) -> Scene:
    """A plane y = 0 seen head-on from ``distance``; directional light with n.l = x."""
    th = math.acos(x)
    light = Light(direction=(math.sin(th), math.cos(th), 0.0))
    mat = Material(ambient=0.0, diffuse=1.0, specular=0.0, texture=texture)
    obj = SceneObject(plane(width=40.0, depth=40.0, segments=2), material=mat)
    cam = Camera.look_at((0.0, distance, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), FOV, 0.1, 50.0)
    return Scene(
        objects=(obj,),
        camera=cam,
        lights=(light,),
        ambient=(0.0, 0.0, 0.0),
        background=(1, 1, 1, 1),
    )


def line_scale(s: float, period: float, *, distance: float = DIST, size: int = SIZE) -> float:
    """The ``uv_scale`` that puts the plane's lines at dyadic scale ``s`` (eq. 5)."""
    ppu = size / (2 * distance * math.tan(math.radians(FOV / 2)))
    return ppu / (period * 2.0**s)


def mean_tone(style: ThresholdStyle, x: float, size: int = SIZE, spp: int = 1) -> float:
    img = render(flat_scene(x), style, size, size, spp)
    return float(img.rgba[..., 0].mean())


def tone_errors(style: ThresholdStyle) -> np.ndarray:
    return np.array([mean_tone(style, x) - x for x in LEVELS])


# Frac(s) = 0.37: an intermediate scale where eq. 8 is far from uniform.
LINES = dict(source="lines", period=4.0, uv_scale=line_scale(2.37, 4.0), specular=False)

TOLERANCES = [
    # (id, style parameters, tolerance on |mean - x|)
    ("lines-uniform", dict(LINES, uniform=True), 0.01),
    ("lines-uniform-analytic", dict(LINES, uniform=True, filter="analytic"), 0.005),
    ("lines-uniform-pcf4", dict(LINES, uniform=True, filter="pcf", samples=4), 0.01),
    ("cross-hatch-uniform", dict(LINES, uniform=True, directions=[30.0, -60.0]), 0.01),
    (
        "cross-hatch-onsets",
        dict(LINES, uniform=True, directions=[30.0, -60.0], onsets=[1.0, 0.5], filter="analytic"),
        0.01,
    ),
    ("lines-noise", dict(LINES, uniform=True, noise=0.3), 0.02),
    (
        "stipple-uniform",
        dict(source="stipple", period=6.0, uv_scale=1.7, specular=False, uniform=True),
        0.01,
    ),
    (
        "image-brick-mip-corrected",
        dict(
            source="image",
            texture="brick",
            uv_scale=1.0,
            specular=False,
            filter="pcf",
            samples=1,
            tone_correct=True,
        ),
        0.02,
    ),
    (
        "image-gravel-mip-corrected",
        dict(
            source="image",
            texture="gravel",
            uv_scale=1.0,
            specular=False,
            filter="pcf",
            samples=1,
            tone_correct=True,
        ),
        0.02,
    ),
]


@pytest.mark.parametrize("params, tol", [t[1:] for t in TOLERANCES], ids=[t[0] for t in TOLERANCES])
def test_flat_plane_reproduces_target_intensity(params, tol):
    err = tone_errors(ThresholdStyle(**params))
    assert np.max(np.abs(err)) <= tol, err


def test_paper_multiscale_blend_drifts_where_uniform_does_not():
    # eq. 8 at t = 0.5: F has density 2/(1+t) in the middle, so at x = 1/4 only 1/6 is white
    params = dict(LINES, uv_scale=line_scale(2.5, 4.0), filter="analytic")
    paper = mean_tone(ThresholdStyle(**params, uniform=False), 0.25)
    fixed = mean_tone(ThresholdStyle(**params, uniform=True), 0.25)
    assert paper == pytest.approx(1 / 6, abs=0.005)
    assert fixed == pytest.approx(0.25, abs=0.005)
    # at integer scales both are the sawtooth and agree with the target
    params0 = dict(LINES, uv_scale=line_scale(3.0, 4.0), filter="analytic")
    assert mean_tone(ThresholdStyle(**params0, uniform=False), 0.25) == pytest.approx(
        0.25, abs=0.005
    )


def test_paper_blend_drift_follows_the_design_cdf():
    # mean white fraction of the paper's F at Frac(s) = t is its CDF G(x, t) (DESIGN.md)
    for t in (0.25, 0.5, 0.75):
        params = dict(LINES, uv_scale=line_scale(2.0 + t, 4.0), filter="analytic", uniform=False)
        for x in (0.2, 0.6):
            lo, hi = (1 - t) / 2, (1 + t) / 2
            g = x / (1 + t) if x < lo else ((2 * x - lo) / (1 + t) if x < hi else (x + t) / (1 + t))
            assert mean_tone(ThresholdStyle(**params), x) == pytest.approx(g, abs=0.006), (t, x)


def test_image_tone_drifts_without_equalization_and_interpolation_correction():
    base = dict(
        source="image", texture="brick", uv_scale=1.0, specular=False, filter="pcf", samples=1
    )
    # CLAHE alone (no rank equalization): the brick texture's thresholds are not uniform (0.2
    # for scikit-image's photograph, about 0.1 for the tileable procedural brick)
    raw = tone_errors(ThresholdStyle(**base, rank_equalize=False))
    assert np.max(np.abs(raw)) > 0.05
    # uniform levels, but bilinear interpolation narrows the thresholds towards 0.5
    interp = tone_errors(ThresholdStyle(**base))
    assert interp[0] < -0.03 and interp[-1] > 0.03
    corrected = tone_errors(ThresholdStyle(**base, tone_correct=True))
    assert np.max(np.abs(corrected)) < np.max(np.abs(interp)) / 3


def test_paper_stipple_blend_drifts_where_tone_table_does_not():
    params = dict(source="stipple", period=6.0, uv_scale=1.7, specular=False)
    paper = tone_errors(ThresholdStyle(**params))
    assert np.max(np.abs(paper)) > 0.05
    assert np.max(np.abs(tone_errors(ThresholdStyle(**params, uniform=True)))) < 0.01


def test_constant_threshold_is_quantization_not_tone_preserving():
    # the classic toon step: the mean is T_n(x, t), a level, not x (excluded from the tone claim)
    style = ThresholdStyle(source="constant", n=2, t=0.5, specular=False)
    for x, level in ((0.1, 0.0), (0.3, 0.5), (0.6, 0.5), (0.8, 1.0)):
        assert mean_tone(style, x, size=16) == pytest.approx(level, abs=1e-6)
