"""Rendered images: linear float RGBA in memory, 8-bit sRGB PNG on disk (written atomically)."""

from __future__ import annotations

import io
import math
import os
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._atomic import atomic_file, check_output_file

__all__ = [
    "IMAGE_FORMATS",
    "Image",
    "atomic_file",
    "decode_image",
    "decode_png16",
    "is_png16_colour",
    "png_size",
    "PNG_SIGNATURE",
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

    shown = str(path)
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{what}: {shown!r} is a directory; expected {IMAGE_FORMATS} file")
    if not p.exists():
        raise ValueError(f"{what}: file {shown!r} does not exist; expected {IMAGE_FORMATS} file")
    if p.stat().st_size == 0:
        raise ValueError(f"{what}: {shown!r} is an empty file; expected {IMAGE_FORMATS}")
    try:
        return decode_image(p)
    except Exception as exc:  # noqa: BLE001 -- imageio and its plugins raise many types
        reason = _decode_reason(exc)
    raise ValueError(f"{what}: cannot read {shown!r}: {reason}; expected {IMAGE_FORMATS}") from None


#: The most values (rows x cols x channels, over every frame) an image file may decode to:
#: Pillow's decompression-bomb bound (2 x its ``MAX_IMAGE_PIXELS``) of four channels, about
#: 716 M values (2.9 GB as float32); a TIFF declares any size, and imageio decodes it whole.
MAX_DECODED_VALUES = 4 * 2 * 89_478_485

#: Colour modes whose channels are not RGB: decoded as RGB (a CMYK JPEG's four channels would
#: otherwise read as RGBA).
_CONVERTED_MODES = ("CMYK", "YCbCr", "LAB", "HSV")


def decode_image(source: Any, *, extension: str | None = None) -> np.ndarray:
    """Decode an image (a path or the encoded bytes, ``extension`` naming the format of bytes)
    as the array imageio gives, with these exceptions:

    - an image in a colour model other than grey or RGB (a CMYK JPEG) is converted to RGB;
    - a PNG with a ``tRNS`` chunk (palette alphas, or the colour key of an 8-bit RGB or an 8-
      or 1-bit grey image) is decoded with its alpha, as RGBA or grey + alpha (imageio drops
      it; Pillow cannot apply the key of other bit depths, which keep their pixels, opaque);
    - a 16-bit RGB, RGBA or grey + alpha PNG is decoded at 16 bits by :func:`decode_png16`
      (``uint16``, grey + alpha as two channels), where imageio (Pillow) gives 8 bits;
    - a TIFF with planar colour is returned as (rows, cols, C), where imageio gives (C, rows,
      cols).

    An image of more than :data:`MAX_DECODED_VALUES` values (a TIFF declares any size; a PNG
    or JPEG is bounded by Pillow) is refused from its header with a ``ValueError``, and so is
    a file of several images (an animated PNG, GIF or WebP; a multi-page TIFF), counted from
    its header before any is decoded, whose frames would otherwise read as rows or channels.
    Decoder errors propagate."""
    import imageio.v3 as iio

    if isinstance(source, (bytes, bytearray)):
        head = bytes(source[:26])
    else:
        with open(source, "rb") as f:
            head = f.read(26)
    chunks = _png_chunks(source) if head[:8] == PNG_SIGNATURE else {}
    tiff = _tiff_series(source) if head[:4] in _TIFF_MAGIC else None
    frames = _frame_count(source, extension, head, chunks, tiff)
    if frames > 1:
        raise _Refused(_several_images(frames))
    if is_png16_colour(head):
        from PIL import Image

        data = (
            bytes(source) if isinstance(source, (bytes, bytearray)) else Path(source).read_bytes()
        )
        limit = Image.MAX_IMAGE_PIXELS  # Pillow's decompression-bomb bound, as for other files
        return decode_png16(data, max_pixels=2 * limit if limit else 1 << 62)
    props = iio.improps(source, extension=extension)
    shape = tuple(props.shape)
    if math.prod(shape) > MAX_DECODED_VALUES:
        raise _Refused(
            f"the image is too large: {' x '.join(map(str, shape))} values, more than the "
            f"{MAX_DECODED_VALUES:,} refnpr decodes; use a smaller image"
        )
    one: dict[str, Any] = {"extension": extension}
    if props.is_batch:  # a one-frame GIF or APNG: its frame, not a stack of one
        one["index"], shape = 0, shape[1:]
    if b"tRNS" in chunks and _keyed(head):  # the transparency imageio drops
        mode = "LA" if head[25] == 0 else "RGBA"  # grey, else RGB or palette (colour types)
        return np.asarray(iio.imread(source, mode=mode, **one))
    pixels = np.asarray(iio.imread(source, **one))
    if pixels.shape != shape and pixels.shape[1:] == shape:  # pages the header count missed
        raise _Refused(_several_images(pixels.shape[0]))
    if tiff is not None and tiff[2] == "SYX" and pixels.ndim == 3:  # planar: samples first
        pixels = np.ascontiguousarray(np.moveaxis(pixels, 0, -1))
    if pixels.ndim == 3 and pixels.shape[2] in (3, 4):
        mode = iio.immeta(source, **one).get("mode")
        if mode in _CONVERTED_MODES:
            pixels = np.asarray(iio.imread(source, mode="RGB", **one))
    return pixels


def _frame_count(
    source: Any, extension: str | None, head: bytes, chunks: dict, tiff: tuple | None
) -> int:
    """How many images the file holds, from its header: an animated PNG's frames (its
    ``acTL`` chunk), a GIF's or WebP's as imageio's plugin counts them, a TIFF's pages in the
    series imageio decodes (``tiff``, :func:`_tiff_series`); 1 for other formats (a camera JPEG
    whose MPF header lists a large thumbnail is one image) and where the header does not say."""
    import imageio.v3 as iio

    if head[:8] == PNG_SIGNATURE:
        actl = chunks.get(b"acTL", b"")
        return max(1, struct.unpack(">I", actl[:4])[0]) if len(actl) >= 4 else 1
    if tiff is not None:
        return max(1, math.prod(tiff[0]) // max(1, math.prod(tiff[1])))
    if head[:6] in (b"GIF87a", b"GIF89a") or (head[:4] == b"RIFF" and head[8:12] == b"WEBP"):
        try:
            props = iio.improps(source, index=..., extension=extension)
        except Exception:  # noqa: BLE001 -- the decode that follows reports a bad file
            return 1
        return int(props.n_images or 1) if props.is_batch else 1
    return 1


def _tiff_series(source: Any) -> tuple | None:
    """The first series of a TIFF (what imageio decodes), from its header: its shape, the
    shape of one page, and its axes (``"YXS"`` for interleaved colour, ``"SYX"`` for planar);
    None where tifffile cannot say (the decode that follows reports a bad file)."""
    try:
        import tifffile

        f = io.BytesIO(bytes(source)) if isinstance(source, (bytes, bytearray)) else source
        with tifffile.TiffFile(f) as tif:
            series = tif.series[0]
            return tuple(series.shape), tuple(series.keyframe.shape), series.axes
    except Exception:  # noqa: BLE001 -- tifffile raises many types on damaged files
        return None


#: The first four bytes of a TIFF or BigTIFF file (little- and big-endian).
_TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")


class _Refused(ValueError):
    """A file :func:`decode_image` decodes but refuses (its message is the whole reason)."""


def _several_images(n: int) -> str:
    return (
        f"the file holds {n} images (an animation or a multi-page file); refnpr reads a "
        "single image: save the one you want as its own file"
    )


def _keyed(head: bytes) -> bool:
    """Whether a PNG of this header is of a kind whose ``tRNS`` transparency Pillow turns into
    alpha: a palette PNG, an 8-bit RGB or an 8- or 1-bit grey PNG."""
    depth, colour = head[24], head[25]
    return colour == 3 or (colour == 2 and depth == 8) or (colour == 0 and depth in (1, 8))


def _png_chunks(source: Any) -> dict[bytes, bytes]:
    """The chunks of a PNG (a path or bytes) before its first ``IDAT``: type -> the first 8
    bytes of its data (``tRNS``: transparency; ``acTL``: an animation and its frame count)."""
    if isinstance(source, (bytes, bytearray)):
        f: Any = io.BytesIO(source)
    else:
        f = open(source, "rb")  # noqa: SIM115 (closed below)
    found: dict[bytes, bytes] = {}
    with f:
        f.seek(8)
        while True:
            chunk = f.read(8)
            if len(chunk) < 8:
                return found
            length, kind = struct.unpack(">I4s", chunk)
            if kind in (b"IDAT", b"IEND"):
                return found
            data = f.read(min(length, 8))
            found.setdefault(kind, data)
            f.seek(length - len(data) + 4, os.SEEK_CUR)  # the rest of the data and the CRC


#: The eight bytes every PNG file starts with.
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: Valid (colour type: bit depths) pairs of the PNG specification, and the channels they give.
_PNG_TYPES = {0: ((1, 2, 4, 8, 16), 1), 2: ((8, 16), 3), 3: ((1, 2, 4, 8), 3), 4: ((8, 16), 2),
              6: ((8, 16), 4)}  # fmt: skip
#: Channels of the colour types :func:`decode_png16` reads: RGB, grey + alpha, RGBA.
_PNG16_CHANNELS = {colour: _PNG_TYPES[colour][1] for colour in (2, 4, 6)}
#: Adam7 passes (sec. 8.2): (x0, y0, dx, dy).
_ADAM7 = (
    (0, 0, 8, 8),
    (4, 0, 8, 8),
    (0, 4, 4, 8),
    (2, 0, 4, 4),
    (0, 2, 2, 4),
    (1, 0, 2, 2),
    (0, 1, 1, 2),
)


def png_size(data: bytes, *, what: str) -> tuple[int, int]:
    """``(width, height)`` from a PNG's IHDR chunk (nothing is decoded); ``what`` starts the
    messages.

    Raises
    ------
    ValueError
        No PNG signature, no IHDR chunk first, a zero size, or an invalid colour type / bit
        depth pair.
    """
    if data[:8] != PNG_SIGNATURE:
        raise ValueError(f"{what}: cannot read: not a PNG file (no PNG signature); expected a PNG")
    if len(data) < 33 or data[12:16] != b"IHDR" or struct.unpack(">I", data[8:12])[0] != 13:
        raise ValueError(f"{what}: cannot read: no IHDR chunk first (truncated or corrupt PNG)")
    width, height, depth, colour = struct.unpack(">IIBB", data[16:26])
    if width == 0 or height == 0:
        raise ValueError(f"{what}: the PNG header gives a size of {width}x{height}")
    depths = _PNG_TYPES.get(colour, ((), 0))[0]
    if depth not in depths:
        raise ValueError(
            f"{what}: the PNG header gives colour type {colour} with bit depth {depth}, which "
            "PNG does not define"
        )
    return width, height


def is_png16_colour(head: bytes) -> bool:
    """Whether ``head`` (the first 26 bytes or more of a file) is the start of a 16-bit RGB,
    RGBA or grey + alpha PNG: the types :func:`decode_png16` reads."""
    if len(head) < 26 or head[:8] != PNG_SIGNATURE or head[12:16] != b"IHDR":
        return False
    return head[24] == 16 and head[25] in _PNG16_CHANNELS


def decode_png16(data: bytes, *, max_pixels: int) -> np.ndarray:
    """The pixels of a 16-bit RGB, RGBA or grey + alpha PNG, at 16 bits.

    Pillow, and so imageio, reads those types as 8-bit (grey + alpha even as RGBA): a threshold
    texture, a colour map or a backend's render written at 16 bits would lose its low byte
    without a word. Here (the PNG specification, 3rd ed.) the IDAT chunks are joined, each
    chunk's CRC checked; the stream is inflated, bounded by the size the header implies; each
    row is unfiltered (sec. 7.3 and 9); and the seven Adam7 passes of an interlaced image are
    scattered to their pixels (sec. 8.2).

    Parameters
    ----------
    data : bytes
        The whole file.
    max_pixels : int
        Largest width x height decoded (a larger header is refused before anything is inflated).

    Returns
    -------
    (H, W, C) uint16, C = 3 (RGB), 2 (grey, alpha) or 4 (RGBA).

    Raises
    ------
    ValueError
        Saying what is wrong: not such a PNG, a chunk that runs past the end or fails its CRC, no
        IDAT or IEND, an unknown compression, filter or interlace method, an image over
        ``max_pixels``, a stream that does not inflate to the size the header implies, or an
        unknown row filter.
    """
    if not is_png16_colour(data[:26]):
        raise ValueError("not a 16-bit RGB, RGBA or grey + alpha PNG")
    idat, header, pos, ended = [], None, 8, False
    while pos + 12 <= len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        end = pos + 12 + length
        if end > len(data):
            raise ValueError(f"chunk {kind!r} runs past the end of the file (truncated)")
        body = data[pos + 8 : end - 4]
        (crc,) = struct.unpack(">I", data[end - 4 : end])
        if zlib.crc32(body, zlib.crc32(kind)) != crc:  # no copy of the chunk
            raise ValueError(f"chunk {kind!r} fails its CRC (corrupt)")
        if header is None:
            if kind != b"IHDR" or length != 13:
                raise ValueError("no IHDR chunk first")
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            ended = True
            break
        pos = end
    if not ended or not idat:
        raise ValueError("no IDAT or no IEND chunk (truncated)")
    width, height, _, colour, compression, filtering, interlace = header
    if compression != 0 or filtering != 0 or interlace not in (0, 1):
        raise ValueError(
            f"unknown compression, filter or interlace method ({compression}, {filtering}, "
            f"{interlace})"
        )
    if width == 0 or height == 0 or width * height > max_pixels:
        raise ValueError(
            f"the header gives {width}x{height} pixels; at most {max_pixels} are decoded"
        )
    from ._kernels import png_unfilter  # numba is imported for a 16-bit PNG only

    channels = _PNG16_CHANNELS[colour]
    bpp = 2 * channels  # bytes per pixel
    passes = []
    for x0, y0, dx, dy in _ADAM7 if interlace else ((0, 0, 1, 1),):
        pw, ph = -(-(width - x0) // dx), -(-(height - y0) // dy)
        if pw > 0 and ph > 0:  # an empty pass has no rows, not even filter bytes
            passes.append((x0, y0, dx, dy, pw, ph))
    size = sum(ph * (1 + pw * bpp) for *_, pw, ph in passes)
    inflater = zlib.decompressobj()
    try:
        raw = inflater.decompress(b"".join(idat), size + 1)
    except zlib.error as exc:
        raise ValueError(f"the image data does not inflate ({exc})") from None
    if len(raw) != size:
        raise ValueError(
            f"the image data inflates to {'more' if len(raw) > size else len(raw)} bytes where "
            f"the header implies {size}"
        )
    out = np.empty((height, width, channels), dtype=np.uint16)
    at = 0
    for x0, y0, dx, dy, pw, ph in passes:
        rows = np.frombuffer(raw, dtype=np.uint8, count=ph * (1 + pw * bpp), offset=at)
        rows = rows.reshape(ph, 1 + pw * bpp).copy()
        at += rows.size
        bad = png_unfilter(rows, bpp)
        if bad >= 0:
            raise ValueError(f"row {bad} of the image data has unknown filter type {rows[bad, 0]}")
        out[y0::dy, x0::dx] = rows[:, 1:].view(">u2").reshape(ph, pw, channels)
    return out


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
    if isinstance(exc, _Refused):  # decode_image's own refusal
        return first
    if isinstance(exc, MemoryError) or type(exc).__name__ == "DecompressionBombError":
        return f"the image is too large to decode ({type(exc).__name__}: {first})"
    return f"the file is corrupt or not an image ({type(exc).__name__}: {first})"


def check_png_path(path: str | os.PathLike, what: str = "path") -> Path:
    """``path`` as a Path, validated before any work (:func:`refnpr._atomic.check_output_file`):
    not empty, not a directory, a ``.png`` suffix, and a parent directory that exists (or can
    be created) and is writable; else a ValueError naming ``what`` (the parameter or option),
    the path as given and what to give instead."""
    return check_output_file(path, what, ".png", "; refnpr writes 8-bit PNG only")


def write_png_atomic(path: str | os.PathLike, pixels: np.ndarray) -> Path:
    """Write an 8-bit image as PNG through a temporary file and an atomic rename
    (:func:`atomic_file`: an interrupted write leaves neither a partial target nor the temporary).

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
    passes : dict of str to array, or None
        Per-pixel G-buffer channels, ``(H, W)`` or ``(H, W, C)`` of the channel's dtype, keyed
        by channel name (``depth``, ``normal``, ``uv``, ``position``, ``tri_id``, ...), one
        sample per pixel (:func:`refnpr.exr.pixel_passes`): what ``render(..., passes=True)``
        attaches and :meth:`save` writes to an EXR. None: an image without passes.
    """

    rgba: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)
    passes: dict[str, np.ndarray] | None = None

    def __post_init__(self) -> None:
        a = np.asarray(self.rgba)
        if a.ndim != 3 or a.shape[2] != 4:
            raise ValueError(f"rgba: expected shape (H, W, 4), got {a.shape}")
        if a.dtype.kind != "f":  # 128 as uint8 would be a value of 128, not 0.5
            raise TypeError(
                f"rgba: expected float linear RGBA in [0, 1], got dtype {a.dtype}; divide 8-bit "
                "sRGB by 255 and decode it with srgb_to_linear"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError("rgba: image contains NaN or inf; a style produced invalid values")
        if self.passes is not None:
            if not isinstance(self.passes, dict):
                raise TypeError(
                    f"passes: expected a dict of channel name to array or None, got "
                    f"{type(self.passes).__name__}"
                )
            for name, p in self.passes.items():
                shape = np.shape(p)
                if len(shape) not in (2, 3) or tuple(shape[:2]) != a.shape[:2]:
                    raise ValueError(
                        f"passes: {name!r} has shape {shape}; expected ({a.shape[0]}, "
                        f"{a.shape[1]}) or ({a.shape[0]}, {a.shape[1]}, C), the image's size"
                    )

    @classmethod
    def _of_finite(
        cls,
        rgba: np.ndarray,
        timings: dict[str, float],
        passes: dict[str, np.ndarray] | None = None,
    ) -> Image:
        """An Image of pixels already known to be finite (H, W, 4) float32, without the
        full-image scan of ``__post_init__`` (~4 ms at 1920x1080): for ``render``, whose
        ``composite_resolve`` checked every sample and every pixel it wrote."""
        image = object.__new__(cls)
        object.__setattr__(image, "rgba", rgba)
        object.__setattr__(image, "timings", timings)
        object.__setattr__(image, "passes", passes)
        return image

    width = property(lambda self: int(self.rgba.shape[1]), doc="Pixels per row.")
    height = property(lambda self: int(self.rgba.shape[0]), doc="Rows of pixels.")

    def to_srgb8(self) -> np.ndarray:
        """(H, W, 4) uint8: sRGB-encoded colour, linear alpha, rounded to nearest."""
        out = np.empty(self.rgba.shape, dtype=np.uint8)
        out[..., :3] = np.rint(linear_to_srgb(self.rgba[..., :3]) * 255.0)
        out[..., 3] = np.rint(np.clip(self.rgba[..., 3], 0.0, 1.0) * 255.0)
        return out

    def save(self, path: str | os.PathLike) -> Path:
        """Save as 8-bit sRGB PNG with alpha, or (a ``.exr`` name) as a linear float OpenEXR
        file with the image's passes (atomic write either way).

        The EXR is one part: ``R``, ``G``, ``B`` (linear, premultiplied by ``A``), ``A`` and
        each of :attr:`passes` named as compositing tools expect (``depth.Z``,
        ``normal.X/Y/Z``, ``uv.U/V``, ``position.X/Y/Z``, ``tri_id``, ``mesh_id``, ...; the
        layout: :mod:`refnpr.exr`). An image without passes writes RGBA only.

        Parameters
        ----------
        path : str or path
            Ending in ``.png`` or ``.exr`` (the EXR needs the OpenEXR package).

        Returns
        -------
        Path
        """
        if Path(path).suffix.lower() == ".exr":
            from .exr import check_exr_path, image_channels, write_exr_channels

            target = check_exr_path(path)
            return write_exr_channels(target, image_channels(self.rgba, self.passes))
        if Path(path).suffix.lower() != ".png" and not Path(path).is_dir():
            raise ValueError(
                f"path: expected a .png file name (8-bit sRGB) or a .exr one (linear float with "
                f"the G-buffer passes), got {os.fspath(path)!r}"
            )
        return write_png_atomic(path, self.to_srgb8())

    def to_png_bytes(self) -> bytes:
        """The image as an 8-bit sRGB PNG with alpha, in memory: the bytes :meth:`save` writes
        (decoded: :meth:`to_srgb8`, ``(H, W, 4)`` uint8)."""
        import imageio.v3 as iio

        return bytes(iio.imwrite("<bytes>", self.to_srgb8(), extension=".png"))

    def _repr_png_(self) -> bytes:
        """Jupyter's rich display: the image shows itself as its sRGB PNG."""
        return self.to_png_bytes()
