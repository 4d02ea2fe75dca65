"""Tone fidelity of the ``halftone`` style on a flat, evenly lit plane.

The plane faces the camera and the light, with no ambient term, so the target intensity is the
material's diffuse value I everywhere; the mean output over the plane should be I. Tolerances
(max |mean - I| over I in [0.05, 0.95]) are stated per screen; the paper's one-sided smooth
threshold drifts by +1/(2c) (lighter), the centred option does not.
"""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import rasterize
from refnpr.styles import ShadeContext, get_style

from .test_halftone_scenes import wall

INTENSITIES = np.linspace(0.05, 0.95, 10)


def _tone_errors(intensities=INTENSITIES, *, size: int = 96, **params) -> np.ndarray:
    """mean(output) - I over the plane's samples, for each I (one rasterization)."""
    style = get_style("halftone", specular=False, **params)
    scene = wall(0.5)
    gb = rasterize(scene, scene.camera, size, size, sorted(style.requires(scene)))
    covered = gb["mesh_id"] >= 0
    errs = []
    for intensity in intensities:
        out = style.shade(ShadeContext(gb, wall(float(intensity))))
        errs.append(float(out[..., 0][covered].mean()) - intensity)
    return np.array(errs)


@pytest.mark.parametrize("profile", ["triangle", "ramp"])
@pytest.mark.parametrize("threshold,centred", [("binary", False), ("smooth", True)])
def test_engraving_reproduces_tone(profile, threshold, centred):
    """Engraving (sec. 4.1): within 0.02 (texel quantization, bilinear peaks and wrap). Oblique
    lines (30 deg) so that pixel rows sample every phase of the ramp."""
    errs = _tone_errors(
        screen={"kind": "engraving", "profile": profile, "angle": 30.0},
        uv_scale=2.0,
        threshold=threshold,
        centred=centred,
    )
    assert np.abs(errs).max() < 0.02, errs


@pytest.mark.parametrize("texture", ["brick", "grass"])
def test_dither_screen_drifts_under_bilinear_filtering_and_equalize_fixes_it(texture):
    """CLAHE dither screens are uniform per level, but bilinear/trilinear filtering averages
    neighbouring texels: thresholding the filtered screen (the paper, the GPU) misses the tone
    by more than 0.05 near I = 0.2 / 0.8; ``tone_correct`` keeps it within 0.02."""
    paper = _tone_errors(screen=texture, uv_scale=2.0, threshold="binary")
    assert np.abs(paper).max() > 0.05, paper
    fixed = _tone_errors(screen=texture, uv_scale=2.0, threshold="binary", tone_correct=True)
    assert np.abs(fixed).max() < 0.02, fixed
    smooth = _tone_errors(
        screen=texture, uv_scale=2.0, threshold="smooth", centred=True, tone_correct=True
    )
    assert np.abs(smooth).max() < 0.025, smooth


def test_hatching_reproduces_tone_as_a_staircase():
    """Stroke maps give a staircase: m = 6 layers keep the tone within 1/(2m) (0.083) when each
    mip level is thresholded on its own (``mip = "per_level"``); thresholding the trilinear blend
    of two levels with different stroke sets drifts further."""
    kw = {"screen": {"kind": "strokes", "set": "hatching", "size": 128, "lines": 8}}
    per_level = _tone_errors(uv_scale=1.0, threshold="binary", mip="per_level", **kw)
    assert np.abs(per_level).max() < 1 / 12, per_level
    assert abs(per_level.mean()) < 0.02


@pytest.mark.parametrize("c", [4.0, 8.0])
def test_one_sided_smooth_threshold_lightens_by_one_over_2c(c):
    """Sec. 3.2 as printed: the grey ramp lies where the binary threshold is black, so the mean
    output is I + 1/(2c) for I in [0, 1 - 1/c] (a lightening, not a darkening); the centred
    variant has no bias. Triangle engraving screen magnified (LOD < 0): a uniform screen."""
    intensities = np.linspace(0.1, 1 - 1 / c - 0.05, 8)
    screen = {"kind": "engraving", "profile": "triangle", "size": 32, "angle": 30.0}
    one_sided = _tone_errors(intensities, screen=screen, uv_scale=2.0, threshold="smooth", c=c)
    np.testing.assert_allclose(one_sided, 1 / (2 * c), atol=0.01)
    centred = _tone_errors(
        intensities, screen=screen, uv_scale=2.0, threshold="smooth", c=c, centred=True
    )
    np.testing.assert_allclose(centred, 0.0, atol=0.01)
    binary = _tone_errors(intensities, screen=screen, uv_scale=2.0, threshold="binary")
    np.testing.assert_allclose(binary, 0.0, atol=0.01)
