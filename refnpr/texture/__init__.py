"""Textures: mip pyramids, CLAHE pyramids, sampling at an explicit LOD, built-in images."""

from .builtin import BUILTIN_TEXTURES, load_texture
from .pyramid import MipPyramid, as_texture, build_pyramid, clahe_pyramid, rank_equalize
from .sample import level_weights, sample_level, sample_trilinear
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
    "build_pyramid",
    "clahe_pyramid",
    "level_weights",
    "load_texture",
    "rank_equalize",
    "sample_level",
    "sample_trilinear",
]
