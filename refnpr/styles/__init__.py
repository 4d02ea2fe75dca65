"""Shading styles: each composes formulas on a G-buffer and declares the channels it requires."""

from .base import (
    ShadeContext,
    Style,
    get_style,
    get_style_class,
    list_styles,
    register,
    style_from_spec,
)

__all__ = [
    "ShadeContext",
    "Style",
    "get_style",
    "get_style_class",
    "list_styles",
    "register",
    "style_from_spec",
]
