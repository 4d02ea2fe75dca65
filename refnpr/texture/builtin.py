"""Built-in textures (all tile seamlessly), image files or encoded images in memory (as given,
or made to tile)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..image import IMAGE_FORMATS, read_image_file
from .brickwork import brick_texture
from .embedded import EmbeddedImage
from .periodic import TILINGS, check_tiling, make_tileable, periodic_component
from .pyramid import as_texture

__all__ = ["BUILTIN_TEXTURES", "TILINGS", "builtin_image", "load_texture"]

#: Gray built-in textures, every one tileable: scikit-image's bundled images (usable offline),
#: ``brick`` procedural.
BUILTIN_TEXTURES = ("brick", "grass", "gravel", "camera", "text", "checkerboard", "page", "moon")


def _checkerboard(size: int = 200, squares: int = 8) -> np.ndarray:
    """scikit-image's checkerboard (8 x 8 squares of 25 texels, white at the top left) drawn
    with hard edges (the periodic component would smear squares whose edges lie on the border)."""
    cell = (np.arange(size) * squares) // size
    return np.where((cell[:, None] + cell[None, :]) % 2 == 0, 255, 0).astype(np.uint8)


def builtin_image(name: str) -> np.ndarray:
    """The tileable 8-bit image of a built-in texture name.

    Parameters
    ----------
    name : str
        One of ``BUILTIN_TEXTURES``: scikit-image's bundled images (no download) made to repeat.

    Returns
    -------
    (rows, cols) uint8
        ``brick``: :func:`refnpr.texture.brickwork.brick_texture` (512 x 512), procedural.
        ``checkerboard``: 8 x 8 squares of 25 texels with hard edges (scikit-image's layout).
        Others: scikit-image's image of that name replaced by its periodic component (Moisan
        2011), clipped to [0, 255] and rounded (pointwise, so it still tiles).
    """
    if name not in BUILTIN_TEXTURES:
        raise ValueError(f"name: expected one of {list(BUILTIN_TEXTURES)}, got {name!r}")
    if name == "brick":
        return brick_texture()
    if name == "checkerboard":
        return _checkerboard()
    import skimage.data

    photo = getattr(skimage.data, name)()
    return np.round(np.clip(periodic_component(photo), 0.0, 255.0)).astype(np.uint8)


def load_texture(
    name_or_path: str | Path,
    *,
    gray: bool = True,
    param: str = "texture",
    tiling: str | None = None,
) -> np.ndarray:
    """A texture as float32 in [0, 1]: a built-in name (``BUILTIN_TEXTURES``), an image file,
    or an encoded image in memory.

    Parameters
    ----------
    name_or_path : str, path or EmbeddedImage
        A name of ``BUILTIN_TEXTURES``, the path of a PNG, JPEG, TIFF or BMP image, or an
        :class:`~refnpr.texture.EmbeddedImage` (a glTF file's embedded PNG or JPEG), decoded
        from memory after its header's size is checked, then treated as an image file.
    gray : bool
        Convert colour images to gray (luminance, scikit-image ``rgb2gray``).
    param : str
        The user's parameter that named the texture (``"screen"``, ``"brush"``, ...), which
        error messages start with.
    tiling : {None, "none", "periodic"}
        How an image file (or embedded image) is made to repeat (GL_REPEAT). None or "none":
        as given, seams and all. "periodic": the image's periodic component (Moisan 2011, per
        channel, after the gray conversion), clipped to [0, 1], which removes the seam of an
        image whose opposite borders differ while keeping every local difference inside it.
        Built-in textures tile already and are returned as they are for every value.

    Returns
    -------
    (rows, cols) float32 (or (rows, cols, C) with ``gray=False``)

    Raises
    ------
    ValueError
        Naming the texture as given: neither a built-in name nor a file (listing the built-in
        names), a directory, a file that is not a readable image (with the reason), an
        embedded image that does not decode to the size its header gives; or
        ``tiling`` not among ``TILINGS`` (named ``<param>.tiling``).
    """
    tiling = check_tiling(tiling, param=f"{param}.tiling")
    if isinstance(name_or_path, EmbeddedImage):
        tex = as_texture(name_or_path.decode(what=param), name=f"texture {str(name_or_path)!r}")
    elif isinstance(name_or_path, str) and name_or_path in BUILTIN_TEXTURES:
        tex = as_texture(builtin_image(name_or_path), name=f"texture {name_or_path!r}")
        tiling = "none"  # built-in textures tile already
    else:
        if not isinstance(name_or_path, (str, os.PathLike)):
            raise TypeError(
                f"{param}: expected a built-in texture name {list(BUILTIN_TEXTURES)} or an image "
                f"path, got {type(name_or_path).__name__} {name_or_path!r}"
            )
        shown = str(name_or_path)
        if not Path(name_or_path).exists():
            raise ValueError(
                f"{param}: {shown!r} is neither a built-in texture {list(BUILTIN_TEXTURES)} "
                f"nor an existing image file (no such file; expected {IMAGE_FORMATS} file)"
            )
        tex = as_texture(read_image_file(name_or_path, what=param), name=f"texture {shown!r}")
    if gray and tex.ndim == 3:
        from skimage.color import rgb2gray

        if tex.shape[2] == 2:  # gray + alpha
            tex = np.ascontiguousarray(tex[..., 0])
        elif tex.shape[2] not in (3, 4):
            raise ValueError(
                f"{param} {str(name_or_path)!r}: expected 1 to 4 channels, got {tex.shape[2]}"
            )
        else:
            tex = rgb2gray(tex[..., :3]).astype(np.float32)
    return make_tileable(tex, tiling, param=f"{param}.tiling")
