"""Rendered images: linear float RGBA in memory, 8-bit sRGB PNG on disk (written atomically)."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Image", "check_png_path", "linear_to_srgb", "srgb_to_linear", "write_png_atomic"]


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB transfer function (linear [0, 1] -> encoded [0, 1]), float64."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """Inverse of :func:`linear_to_srgb`, float64."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def check_png_path(path: str | os.PathLike) -> Path:
    """Validate an output path before any work: ``.png`` suffix, not a directory, and a parent
    directory that exists or can be created and is writable."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"path: expected a .png file name, got {str(path)!r}")
    if path.is_dir():
        raise ValueError(f"path: {str(path)!r} is a directory; give a file name ending in .png")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK):
        raise ValueError(
            f"path: cannot write {str(path)!r} (directory {str(parent)!r} is not writable)"
        )
    return path


def write_png_atomic(path: str | os.PathLike, pixels: np.ndarray) -> Path:
    """Write a uint8 (H, W[, C]) array as PNG through a temporary file and an atomic rename, so an
    interrupted write never leaves a corrupted file behind."""
    import imageio.v3 as iio

    path = check_png_path(path)
    if pixels.dtype != np.uint8:
        raise TypeError(f"pixels: expected uint8, got {pixels.dtype}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".png", dir=path.parent)
    os.close(fd)
    try:
        iio.imwrite(tmp, pixels, extension=".png")
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual file mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


@dataclass(frozen=True, eq=False)
class Image:
    """A rendered image.

    Attributes
    ----------
    rgba : (H, W, 4) float32
        Linear RGB with straight (not premultiplied) alpha, already composited over the scene
        background (so alpha is 1 wherever the background is opaque).
    timings : dict of str to float
        Seconds per phase (rasterize, shade, resolve, ...).
    """

    rgba: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        a = np.asarray(self.rgba)
        if a.ndim != 3 or a.shape[2] != 4:
            raise ValueError(f"rgba: expected shape (H, W, 4), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError("rgba: image contains NaN or inf; a style produced invalid values")

    @property
    def width(self) -> int:
        return int(self.rgba.shape[1])

    @property
    def height(self) -> int:
        return int(self.rgba.shape[0])

    def to_srgb8(self) -> np.ndarray:
        """(H, W, 4) uint8: sRGB-encoded colour, linear alpha, rounded to nearest."""
        out = np.empty(self.rgba.shape, dtype=np.uint8)
        out[..., :3] = np.rint(linear_to_srgb(self.rgba[..., :3]) * 255.0)
        out[..., 3] = np.rint(np.clip(self.rgba[..., 3], 0.0, 1.0) * 255.0)
        return out

    def save(self, path: str | os.PathLike) -> Path:
        """Save as 8-bit sRGB PNG with alpha (atomic write)."""
        return write_png_atomic(path, self.to_srgb8())
