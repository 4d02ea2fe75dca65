"""Stroke sets: ordered stroke layers per mip level, encoded as a stroke map (sec. 4.2, Fig. 3)
and, when the set has one, a DOT3 normal map per level (sec. 5.2)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refnpr.formulas import halftone

from ..pyramid import MipPyramid


def level_sizes(size: int) -> list[int]:
    """GL mip sizes of a square ``size`` texture: ``size, size // 2, ..., 1``."""
    return [size >> k for k in range(size.bit_length())]


def _box_half(stack: np.ndarray) -> np.ndarray:
    """2x2 box downsampling of an (m, rows, cols[, C]) stack (GL sizes: at least 1)."""
    m, r, c = stack.shape[:3]
    r2, c2 = max(1, r // 2), max(1, c // 2)
    a = stack[:, : r2 * (r // r2), : c2 * (c // c2)]
    a = a.reshape(m, r2, r // r2, c2, c // c2, *stack.shape[3:])
    return a.mean(axis=(2, 4), dtype=np.float64).astype(np.float32)


@dataclass(frozen=True, eq=False)
class StrokeSet:
    """Ordered stroke layers per mip level, ready to encode as a stroke map (sec. 4.2).

    Attributes
    ----------
    layers : tuple of (m, rows_k, cols_k) float32 arrays
        Ink coverage of the m layers at mip level k (level 0 first, GL sizes down to 1x1);
        layer 0 is the darkest, drawn first (already in the lightest regions).
    levels : (m,) float64
        Ink grey g_i of each layer (increasing in [0, 1)); layer i shows where the target
        intensity is at most ``1 - g_i`` (binary threshold).
    normals : tuple of (rows_k, cols_k, 3) float32 arrays or None
        DOT3 normal map per level, RGB-encoded ``(n + 1) / 2`` in the texture frame (x along +u,
        y along +v, z out of the surface), for individual stroke lighting (sec. 5.2).
    name : str
    """

    layers: tuple[np.ndarray, ...]
    levels: np.ndarray
    normals: tuple[np.ndarray, ...] | None = None
    name: str = "strokes"

    @property
    def m(self) -> int:
        """Number of layers."""
        return int(self.layers[0].shape[0])

    @property
    def size(self) -> tuple[int, int]:
        """(cols, rows) of level 0."""
        return (int(self.layers[0].shape[2]), int(self.layers[0].shape[1]))


def _check(strokes) -> None:
    if not isinstance(strokes, StrokeSet):
        raise TypeError(f"strokes: expected a StrokeSet, got {type(strokes).__name__}")


def stroke_map_pyramid(strokes: StrokeSet) -> MipPyramid:
    """The stroke map of every level: ``encode_stroke_map(layers_k, levels)`` (sec. 4.2).

    Returns
    -------
    MipPyramid of (rows_k, cols_k) float32 screens in [0, 1]
    """
    _check(strokes)
    levels = tuple(
        np.asarray(halftone.encode_stroke_map(lay, levels=strokes.levels), dtype=np.float32)
        for lay in strokes.layers
    )
    return MipPyramid(levels)


def normal_pyramid(strokes: StrokeSet) -> MipPyramid | None:
    """The encoded normal maps as a 3-channel pyramid (None when the set has none)."""
    _check(strokes)
    if strokes.normals is None:
        return None
    return MipPyramid(tuple(np.asarray(n, dtype=np.float32) for n in strokes.normals))
