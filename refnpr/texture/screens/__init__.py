"""Procedural halftone screens and stroke layers (Freudenberg et al. 2002, sec. 4).

:func:`engraving_pyramid` is the 1D grey ramp of sec. 4.1 as a mip-mapped texture. A
:class:`StrokeSet` holds ordered stroke layers (layer 0 darkest) per mip level, their ink greys
and optionally a DOT3 normal map per level (sec. 5.2); :func:`stroke_map_pyramid` encodes it
(sec. 4.2, Fig. 3). The built-in sets :func:`hatching_set` and :func:`brick_set` (Fig. 7, 8) are
drawn at every mip level with strokes never under about a texel wide (as Praun et al.'s tonal
art maps): a box-filtered pyramid would blur thin strokes to grey, which the threshold turns
into blotches. :func:`load_stroke_layers` reads layers drawn in a paint program. Texture
convention as in :mod:`refnpr.texture.pyramid`.
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
