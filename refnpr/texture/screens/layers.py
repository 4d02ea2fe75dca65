"""Stroke sets from layers drawn by hand (PNG files: black ink on a transparent or white
background, darkest layer first)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from refnpr.formulas import halftone

from ...image import read_image_file
from ..pyramid import as_texture, build_pyramid
from .stroke_set import StrokeSet


def _ink(image: np.ndarray, name: str) -> np.ndarray:
    """Ink coverage of a layer image: alpha of an RGBA/LA image (black ink on transparent), else
    1 - luminance (black ink on white)."""
    tex = as_texture(image, name=name)
    if tex.ndim == 2:
        return 1.0 - tex
    c = tex.shape[2]
    if c in (2, 4):
        return tex[..., -1].astype(np.float32)
    if c == 3:
        return (1.0 - (0.2126 * tex[..., 0] + 0.7152 * tex[..., 1] + 0.0722 * tex[..., 2])).astype(
            np.float32
        )
    raise ValueError(f"{name}: expected 1 to 4 channels, got {c}")


def stroke_set_from_layers(
    layers: Sequence[np.ndarray],
    *,
    levels: Sequence[float] | None = None,
    normal_map: np.ndarray | None = None,
    name: str = "layers",
) -> StrokeSet:
    """A :class:`StrokeSet` from level-0 layer images (darkest first); coarser levels are the
    box-filtered coverages (:func:`build_pyramid`), encoded per level.

    Parameters
    ----------
    layers : sequence of (rows, cols[, C]) images
        Ink of each layer: the alpha channel if the image has one, else 1 - luminance.
    levels : (m,) increasing values in [0, 1), optional
        Ink greys (default ``i / m``).
    normal_map : (rows, cols, 3) image, optional
        RGB-encoded DOT3 normals in the texture frame.
    """
    if isinstance(layers, np.ndarray) or not isinstance(layers, Sequence) or not layers:
        raise ValueError("layers: expected a non-empty list of layer images (darkest first)")
    inks = [_ink(np.asarray(img), f"layers[{i}]") for i, img in enumerate(layers)]
    shape = inks[0].shape
    for i, ink in enumerate(inks):
        if ink.shape != shape:
            raise ValueError(
                f"layers[{i}]: expected the shape of layers[0] {shape}, got {ink.shape}; "
                "all layers of a stroke map must have one size"
            )
    g = halftone.stroke_levels(len(inks)) if levels is None else np.asarray(levels, float)
    halftone.layer_onsets(g)  # validates the levels (strictly increasing in [0, 1))
    if g.shape != (len(inks),):
        raise ValueError(f"levels: expected {len(inks)} grey levels (one per layer), got {g.shape}")
    pyrs = [build_pyramid(ink) for ink in inks]
    per_level = tuple(
        np.stack([p.levels[k] for p in pyrs]).astype(np.float32) for k in range(pyrs[0].n_levels)
    )
    normals = None
    if normal_map is not None:
        nm = as_texture(np.asarray(normal_map), name="normal_map")
        if nm.ndim != 3 or nm.shape[2] < 3 or nm.shape[:2] != shape:
            raise ValueError(
                f"normal_map: expected an RGB image of the layers' size {shape}, got {nm.shape}"
            )
        normals = build_pyramid(nm[..., :3]).levels
    return StrokeSet(per_level, g.astype(np.float64), normals, name)


def load_stroke_layers(
    paths: Sequence[str | Path],
    *,
    levels: Sequence[float] | None = None,
    normal_map: str | Path | None = None,
) -> StrokeSet:
    """Read stroke layers from image files (darkest layer first), see
    :func:`stroke_set_from_layers`."""
    if isinstance(paths, (str, Path)):
        raise TypeError(
            f"paths: expected a list of layer files (darkest first), got the single path {paths!r}"
        )

    def read(path, what: str) -> np.ndarray:
        if not Path(path).is_file():
            raise ValueError(f"{what}: {str(path)!r} is not an existing image file")
        return read_image_file(path, what=what)

    images = [read(p, f"paths[{i}]") for i, p in enumerate(paths)]
    nm = None if normal_map is None else read(normal_map, "normal_map")
    return stroke_set_from_layers(images, levels=levels, normal_map=nm, name="layers")
