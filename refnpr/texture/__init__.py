"""Textures: mip pyramids, CLAHE pyramids, sampling at an explicit LOD, built-in images (all
tileable), encoded images in memory (glTF embedded images), periodic plus smooth decomposition
for images that do not tile."""

from .brickwork import brick_texture
from .builtin import BUILTIN_TEXTURES, builtin_image, load_texture
from .clahe import periodic_clahe
from .embedded import EmbeddedImage
from .periodic import TILINGS, check_tiling, periodic_component, smooth_component
from .pyramid import MipPyramid, as_texture, build_pyramid, clahe_pyramid, rank_equalize
from .sample import level_weights, sample_level, sample_trilinear, texture_lod
from .screens import (
    StrokeSet,
    brick_set,
    engraving_pyramid,
    hatching_set,
    load_stroke_layers,
    normal_pyramid,
    stroke_map_pyramid,
    stroke_set_from_layers,
)

__all__ = [
    "BUILTIN_TEXTURES",
    "EmbeddedImage",
    "TILINGS",
    "MipPyramid",
    "StrokeSet",
    "brick_set",
    "engraving_pyramid",
    "hatching_set",
    "load_stroke_layers",
    "normal_pyramid",
    "stroke_map_pyramid",
    "stroke_set_from_layers",
    "as_texture",
    "brick_texture",
    "build_pyramid",
    "builtin_image",
    "check_tiling",
    "clahe_pyramid",
    "level_weights",
    "load_texture",
    "periodic_clahe",
    "periodic_component",
    "rank_equalize",
    "sample_level",
    "sample_trilinear",
    "smooth_component",
    "texture_lod",
]
