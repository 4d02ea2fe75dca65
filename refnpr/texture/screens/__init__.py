"""Procedural halftone screens and stroke layers (Freudenberg et al. 2002, sec. 4).

* :func:`engraving_pyramid` -- the 1D grey ramp of sec. 4.1 as a mip-mapped ``(1, size)``
  texture (Fig. 2, Fig. 5).
* :class:`StrokeSet` -- ordered stroke layers (ink coverage, layer 0 darkest) per mip level, their
  ink greys and optionally a DOT3 normal map per level (sec. 5.2). :func:`stroke_map_pyramid`
  encodes each level with :func:`refnpr.formulas.halftone.encode_stroke_map` (sec. 4.2, Fig. 3).
* Built-in sets drawn procedurally at every mip level: :func:`hatching_set` (parallel hatching at
  several angles, a tonal art map: strokes of one texel width at every level, the tone from
  their density, calibrated so that the binary threshold reproduces tone) and :func:`brick_set`
  (brick outlines with a bevel normal map, plus hatching inside the bricks; Fig. 7, Fig. 8).
* :func:`load_stroke_layers` reads layers drawn in a paint program (black ink on a transparent
  or white background, one PNG per layer).

Texture convention as in :mod:`refnpr.texture.pyramid`: u along columns, v along rows, texel
centres at ``(i + 0.5) / size``, GL_REPEAT. Stroke layers are drawn *per mip level* with a stroke
width that never falls below about one texel (as in Praun et al.'s tonal art maps and Freudenberg
et al. 2001): a box-filtered pyramid would blur thin strokes to grey, which the threshold turns
into blotches.
"""

from __future__ import annotations

from .bricks import BRICK_LEVELS, brick_set
from .engraving import engraving_pyramid
from .hatching import HATCH_ANGLES, hatching_set
from .layers import load_stroke_layers, stroke_set_from_layers
from .lines import hatching_layer, line_coverage
from .stroke_set import StrokeSet, level_sizes, normal_pyramid, stroke_map_pyramid

__all__ = [
    "StrokeSet",
    "line_coverage",
    "hatching_layer",
    "hatching_set",
    "brick_set",
    "load_stroke_layers",
    "stroke_set_from_layers",
    "stroke_map_pyramid",
    "normal_pyramid",
    "engraving_pyramid",
    "level_sizes",
    "HATCH_ANGLES",
    "BRICK_LEVELS",
]
