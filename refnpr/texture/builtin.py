"""Built-in textures: images bundled inside scikit-image's wheel (no download), or files."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .pyramid import as_texture

__all__ = ["BUILTIN_TEXTURES", "load_texture"]

#: Gray images that scikit-image ships in its wheel (usable offline).
BUILTIN_TEXTURES = ("brick", "grass", "gravel", "camera", "text", "checkerboard", "page", "moon")


def load_texture(name_or_path: str | Path, *, gray: bool = True) -> np.ndarray:
    """A texture as float32 in [0, 1]: a built-in name (``BUILTIN_TEXTURES``) or an image file.

    Parameters
    ----------
    name_or_path : str or path
    gray : bool
        Convert colour images to gray (luminance, scikit-image ``rgb2gray``).

    Returns
    -------
    (rows, cols) float32 (or (rows, cols, C) with ``gray=False``)
    """
    import skimage.data

    if isinstance(name_or_path, str) and name_or_path in BUILTIN_TEXTURES:
        img = getattr(skimage.data, name_or_path)()
    else:
        path = Path(name_or_path)
        if not path.is_file():
            raise ValueError(
                f"texture: {str(name_or_path)!r} is neither a built-in texture "
                f"{list(BUILTIN_TEXTURES)} nor an existing image file"
            )
        import imageio.v3 as iio

        img = iio.imread(path)
    tex = as_texture(img, name="texture")
    if gray and tex.ndim == 3:
        from skimage.color import rgb2gray

        tex = rgb2gray(tex[..., :3]).astype(np.float32)
    return tex
