"""Rendered images: linear float RGBA in memory, 8-bit sRGB PNG on disk (written atomically)."""

from __future__ import annotations

import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "IMAGE_FORMATS",
    "Image",
    "atomic_file",
    "check_png_path",
    "linear_to_srgb",
    "read_image_file",
    "srgb_to_linear",
    "write_png_atomic",
]


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB transfer function (linear [0, 1] -> encoded [0, 1]), float64."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """Inverse of :func:`linear_to_srgb`, float64."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


#: What a texture, screen or compared image file may be (what imageio reads without plugins).
IMAGE_FORMATS = "a PNG, JPEG, TIFF or BMP image"


def read_image_file(path: str | os.PathLike, *, what: str = "image") -> np.ndarray:
    """Read an image file (PNG, JPEG, TIFF, BMP, ...) as the array imageio decodes.

    Parameters
    ----------
    path : str or path
        The file, as the user gave it (messages quote it as given).
    what : str
        What the file is for, the start of every message (``"texture"``, ``"reference image"``).

    Returns
    -------
    (rows, cols) or (rows, cols, C) array of the file's pixel type (uint8, uint16, bool, float).

    Raises
    ------
    ValueError
        Naming ``what`` and the file: it does not exist, is a directory, is empty, or cannot be
        decoded (truncated, corrupt, or not an image), with the decoder's reason.
    """
    import imageio.v3 as iio

    shown = str(path)
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{what}: {shown!r} is a directory; expected {IMAGE_FORMATS} file")
    if not p.exists():
        raise ValueError(f"{what}: file {shown!r} does not exist; expected {IMAGE_FORMATS} file")
    try:
        if p.stat().st_size == 0:
            raise ValueError(f"{what}: {shown!r} is an empty file; expected {IMAGE_FORMATS}")
        return np.asarray(iio.imread(p))
    except ValueError as exc:
        if str(exc).startswith(f"{what}: "):
            raise
        reason = _decode_reason(exc)
    except Exception as exc:  # noqa: BLE001 -- imageio and its plugins raise many types
        reason = _decode_reason(exc)
    raise ValueError(f"{what}: cannot read {shown!r}: {reason}; expected {IMAGE_FORMATS}") from None


def _decode_reason(exc: BaseException) -> str:
    """One line on why a file did not decode, without imageio's plugin install hints."""
    text = str(exc).strip()
    first = text.splitlines()[0] if text else type(exc).__name__
    if first.startswith("Could not find a backend"):
        return "its contents are not an image format that can be read"
    if "truncated" in first.lower():
        return f"the file is truncated ({first})"
    if isinstance(exc, PermissionError):
        return "permission denied"
    return f"the file is corrupt or not an image ({type(exc).__name__}: {first})"


def check_png_path(path: str | os.PathLike) -> Path:
    """Validate an output path before any work: not a directory, a ``.png`` suffix, and a parent
    directory that exists (or can be created) and is writable.

    Parameters
    ----------
    path : str or path

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        Naming the path as given and what to give instead.
    """
    shown = os.fspath(path)
    p = Path(path)
    if isinstance(shown, str) and shown.endswith(("/", os.sep)):
        raise ValueError(
            f"path: {shown!r} names a directory (it ends with a slash); give a file name "
            f"ending in .png, such as {shown + 'out.png'!r}"
        )
    if p.is_dir():
        raise ValueError(f"path: {shown!r} is a directory; give a file name ending in .png")
    if p.suffix.lower() != ".png":
        raise ValueError(
            f"path: expected a .png file name, got {shown!r}; refnpr writes 8-bit PNG only "
            f"(such as {str(p.with_suffix('.png'))!r})"
        )
    parent = p.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        raise ValueError(
            f"path: cannot write {shown!r}: {str(parent)!r} is a file, not a directory"
        )
    if not os.access(parent, os.W_OK):
        raise ValueError(
            f"path: cannot write {shown!r} (directory {str(parent)!r} is not writable)"
        )
    return p


#: Signals whose default action ends the process: while an atomic write runs (main thread),
#: they first remove the temporary file (unless a Python handler is installed for them).
_TERMINATING = tuple(
    getattr(signal, n) for n in ("SIGTERM", "SIGHUP", "SIGINT") if hasattr(signal, n)
)


@contextmanager
def _signals_remove(tmp: list[str]) -> Iterator[None]:
    """While the block runs, a terminating signal whose handler is the default one removes the
    files named in ``tmp`` and then ends the process as the default action would (re-raised with
    the default handler, so the exit status is the conventional one). Handlers set from Python
    (KeyboardInterrupt for SIGINT, a caller's own) are left alone: those that raise unwind
    through the caller's cleanup. Outside the main thread, where handlers cannot be set, this
    does nothing (the caller's ``try``/``except`` still cleans up)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    installed: dict[int, Any] = {}

    def restore() -> None:
        while installed:
            signum, previous = installed.popitem()
            signal.signal(signum, previous)

    def handler(signum: int, frame: Any) -> None:
        for name in tmp:
            with suppress(OSError):
                os.unlink(name)
        restore()
        os.kill(os.getpid(), signum)  # the default action: terminate with this signal
        raise SystemExit(128 + signum)  # only if the signal was blocked

    for signum in _TERMINATING:
        with suppress(ValueError, OSError):
            if signal.getsignal(signum) == signal.SIG_DFL:
                installed[signum] = signal.signal(signum, handler)
    try:
        yield
    finally:
        restore()


@contextmanager
def atomic_file(path: str | os.PathLike, *, suffix: str = "") -> Iterator[Path]:
    """A temporary file beside ``path`` that replaces ``path`` (atomic rename) when the block
    ends normally, and is removed on every other exit: an exception, KeyboardInterrupt, or a
    SIGTERM/SIGHUP while it is written (see ``write_png_atomic``). ``path`` is never partial.

    Parameters
    ----------
    path : str or path
        The target; its parent directory is created.
    suffix : str
        Suffix of the temporary file (some writers choose the format by it, ``".npz"``).

    Yields
    ------
    Path
        The temporary file to write (it exists, empty, mode 0600 until the rename).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    names: list[str] = []
    with _signals_remove(names):
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=suffix, dir=path.parent)
        names.append(tmp)
        os.close(fd)
        try:
            yield Path(tmp)
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual file mode
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        finally:
            names.clear()


def write_png_atomic(path: str | os.PathLike, pixels: np.ndarray) -> Path:
    """Write an 8-bit image as PNG through a temporary file and an atomic rename.

    An interrupted write never leaves a corrupted target nor the temporary file: it is removed
    on errors, on KeyboardInterrupt, and on SIGTERM/SIGHUP (when called from the main thread;
    the process then ends with the signal's conventional status).

    Parameters
    ----------
    path : str or path
        Output file ending in ``.png`` (see :func:`check_png_path`).
    pixels : (H, W) or (H, W, C) uint8, C in 1-4
        Gray, gray + alpha, RGB or RGBA.

    Returns
    -------
    Path
        ``path``.
    """
    import imageio.v3 as iio

    path = check_png_path(path)
    pixels = np.asarray(pixels)
    if pixels.dtype != np.uint8:
        raise TypeError(f"pixels: expected uint8, got {pixels.dtype}")
    if (
        not (pixels.ndim == 2 or (pixels.ndim == 3 and 1 <= pixels.shape[2] <= 4))
        or min(pixels.shape[:2], default=0) < 1
    ):
        raise ValueError(
            f"pixels: expected shape (H, W) or (H, W, C) with C in 1-4 (gray, gray + alpha, "
            f"RGB, RGBA), got {pixels.shape}"
        )
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[..., 0]
    with atomic_file(path, suffix=".png") as tmp:
        iio.imwrite(tmp, pixels, extension=".png")
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
