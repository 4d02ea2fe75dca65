"""Threshold-texture shading (Veryovka 2002, *Animation with threshold textures*).

Eq. 2 with the n-level step T_n of eq. 4 applied to the diffuse and specular terms of eq. 1, the
thresholds coming from a constant (the toon step), an image threshold texture (a mip pyramid with
CLAHE on every level, sampled at the pixel's LOD, sec. 3.1), procedural multi-scale lines (single
lines, cross-hatching, noise-modulated lines, sec. 3.2) or multi-scale dots (stippling, Fig. 4).
Thresholding is filtered (sec. 4) with several threshold samples per shading sample (the
percentage-closer analogue; two mip levels each for images) or, for lines, analytically over the
footprint; both combine with supersampling (``spp``). The strength of the effect can fade with
orientation and illumination (sec. 5, Fig. 5). Add ``contours = {...}`` to the style table for
Figure 7's outlines.

Scene files and the CLI reach every parameter::

    [style]
    name = "threshold"
    source = "lines"
    directions = [45.0, -45.0]
    filter = "analytic"
    contours = { width = 1.5 }

    refnpr render --scene vase --style threshold --param source='"lines"' --param directions=[0,90]
"""

from __future__ import annotations

from .style import ThresholdStyle

__all__ = ["ThresholdStyle"]
