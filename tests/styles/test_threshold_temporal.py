"""Temporal coherence of procedural lines (Veryovka 2002 sec. 3.2): over a camera dolly the
dyadic scale (eq. 5) crosses an integer; with the multi-scale transition (eqs. 7-8) the lines
split smoothly, without it (eq. 6 alone) half of the lines appear at once.

Flipped pixels between consecutive binary frames are counted on a plane seen head-on, where the
whole image shares one dyadic scale, so the frame at which it crosses an integer is known.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.render import render
from refnpr.styles.threshold import ThresholdStyle

from .test_threshold_tone import FOV, flat_scene

SIZE = 96
PERIOD = 6.0


def _distance_for_scale(s: float) -> float:
    # eq. 5 on the plane: d = SIZE / (2 D tan(fov/2)) pixels per v unit, s = log2(d / w)
    return SIZE / (2 * math.tan(math.radians(FOV / 2)) * PERIOD * 2.0**s)


def flips_per_frame(scales, **params) -> np.ndarray:
    """Pixels whose binary value changes between consecutive frames of the dolly."""
    style = ThresholdStyle(source="lines", period=PERIOD, specular=False, **params)
    frames = []
    for s in scales:
        scene = flat_scene(0.3, distance=_distance_for_scale(s))
        frames.append(render(scene, style, SIZE, SIZE, 1).rgba[..., 0] > 0.5)
    return np.array(
        [np.count_nonzero(a != b) for a, b in zip(frames[:-1], frames[1:], strict=True)]
    )


# dyadic scale 1.9775 .. 2.0275 in steps of 0.005: the step 1.9975 -> 2.0025 crosses 2
SCALES = 2.0025 + 0.005 * (np.arange(11) - 5)
CROSSING = 4  # index of the step 1.9975 -> 2.0025


@pytest.mark.parametrize("uniform", [False, True])
def test_lines_do_not_pop_when_the_dyadic_scale_crosses_an_integer(uniform):
    smooth = flips_per_frame(SCALES, uniform=uniform, multiscale=True)
    popping = flips_per_frame(SCALES, uniform=uniform, multiscale=False)
    others = np.delete(smooth, CROSSING)
    # with the transition the crossing step is an ordinary step of the dolly
    assert smooth[CROSSING] <= 1.5 * np.median(others) + 5, smooth
    # without it the new lines appear at once: a pop far above the motion's flips
    assert popping[CROSSING] > 5 * np.median(np.delete(popping, CROSSING)), popping
    assert popping[CROSSING] > 0.1 * SIZE * SIZE
