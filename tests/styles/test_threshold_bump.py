"""Bump mapping of the threshold style (Veryovka Fig. 2, top centre): the surface-gradient
normal perturbation against a hand-derived plane, and its effect on a render."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.render import render
from refnpr.scenes import load_scene
from refnpr.styles.threshold import ThresholdStyle
from refnpr.styles.threshold.bump import bump_normals


@pytest.mark.parametrize("k", [0.0, 0.3, -1.2])
def test_bump_normals_tilt_against_the_height_gradient(k):
    # plane z = 0 seen from +z: x right, screen y downward = world -y; h = k x (world units)
    a = 0.01
    m = 5
    n = np.tile([0.0, 0.0, 1.0], (m, 1))
    dpdx = np.tile([a, 0.0, 0.0], (m, 1))
    dpdy = np.tile([0.0, -a, 0.0], (m, 1))
    got = bump_normals(n, dpdx, dpdy, np.full(m, k * a), np.zeros(m))
    want = np.array([-k, 0.0, 1.0]) / np.hypot(k, 1.0)  # normal of the surface z = k x
    np.testing.assert_allclose(got, np.tile(want, (m, 1)), atol=1e-12)
    # a height varying along world y tilts towards -y (screen y runs the other way)
    got = bump_normals(n, dpdx, dpdy, np.zeros(m), np.full(m, -k * a))
    np.testing.assert_allclose(got[0], [0.0, -k / np.hypot(k, 1), 1 / np.hypot(k, 1)], atol=1e-12)


def test_bump_moves_the_threshold_boundary_and_zero_height_does_not():
    scene = load_scene("sphere")
    base = dict(source="constant", uv_scale=[4.0, 2.0], specular=False)
    plain = render(scene, ThresholdStyle(**base), 128, 96, 1).rgba
    flat = render(scene, ThresholdStyle(**base, bump="gravel", bump_height=0.0), 128, 96, 1).rgba
    bumpy = render(scene, ThresholdStyle(**base, bump="gravel", bump_height=0.02), 128, 96, 1).rgba
    np.testing.assert_allclose(flat, plain, atol=1e-6)
    changed = np.mean(np.abs(bumpy[..., 0] - plain[..., 0]) > 0.1)
    assert changed > 0.004  # the terminator (a thin band at this size) breaks up into bumps
    with pytest.raises(TypeError, match="bump"):
        ThresholdStyle(bump=3)
