"""Built-in textures: images bundled inside scikit-image's wheel (no download), or files."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..image import IMAGE_FORMATS, read_image_file
from .pyramid import as_texture

__all__ = ["BUILTIN_TEXTURES", "load_texture"]

#: Gray images that scikit-image ships in its wheel (usable offline).
BUILTIN_TEXTURES = ("brick", "grass", "gravel", "camera", "text", "checkerboard", "page", "moon")


def load_texture(
    name_or_path: str | Path, *, gray: bool = True, param: str = "texture"
) -> np.ndarray:
    """A texture as float32 in [0, 1]: a built-in name (``BUILTIN_TEXTURES``) or an image file.

    Parameters
    ----------
    name_or_path : str or path
        A name of ``BUILTIN_TEXTURES``, or the path of a PNG, JPEG, TIFF or BMP image.
    gray : bool
        Convert colour images to gray (luminance, scikit-image ``rgb2gray``).
    param : str
        The user's parameter that named the texture (``"screen"``, ``"brush"``, ...), which
        error messages start with.

    Returns
    -------
    (rows, cols) float32 (or (rows, cols, C) with ``gray=False``)

    Raises
    ------
    ValueError
        Naming the texture as given: neither a built-in name nor a file (listing the built-in
        names), a directory, or a file that is not a readable image (with the reason).
    """
    import skimage.data

    if isinstance(name_or_path, str) and name_or_path in BUILTIN_TEXTURES:
        img = getattr(skimage.data, name_or_path)()
        tex = as_texture(img, name=f"texture {name_or_path!r}")
    else:
        if not isinstance(name_or_path, (str, os.PathLike)):
            raise TypeError(
                f"{param}: expected a built-in texture name {list(BUILTIN_TEXTURES)} or an image "
                f"path, got {type(name_or_path).__name__} {name_or_path!r}"
            )
        shown = str(name_or_path)
        path = Path(name_or_path)
        if not path.exists():
            raise ValueError(
                f"{param}: {shown!r} is neither a built-in texture {list(BUILTIN_TEXTURES)} "
                f"nor an existing image file (no such file; expected {IMAGE_FORMATS} file)"
            )
        img = read_image_file(name_or_path, what=param)
        tex = as_texture(img, name=f"texture {shown!r}")
    if gray and tex.ndim == 3:
        from skimage.color import rgb2gray

        if tex.shape[2] == 2:  # gray + alpha
            return np.ascontiguousarray(tex[..., 0])
        if tex.shape[2] not in (3, 4):
            raise ValueError(
                f"{param} {str(name_or_path)!r}: expected 1 to 4 channels, got {tex.shape[2]}"
            )
        tex = rgb2gray(tex[..., :3]).astype(np.float32)
    return tex
