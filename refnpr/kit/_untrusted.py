"""The headers of an untrusted kit's files: the sizes in PNG, OpenEXR and ``.npy`` headers read
before any pixel is decoded. Paths and regular files are read by :mod:`refnpr._reading`
(``inside``, ``read_regular``), which the scene readers share.

Every function raises ``ValueError`` with a message that starts with ``what`` (the role of the
file) and quotes values with ``repr`` (so control characters arrive escaped). The limits are
the caller's (``refnpr.kit.check`` holds the documented ones).
"""

from __future__ import annotations

import io
import struct
from dataclasses import dataclass

import numpy as np

from .._reading import short_repr
from ..image import png_size

__all__ = [
    "ExrHeader",
    "NpyHeader",
    "exr_header",
    "npy_array",
    "npy_header",
    "png_size",
]


# -- OpenEXR -----------------------------------------------------------------------------------

_EXR_MAGIC = b"\x76\x2f\x31\x01"


@dataclass(frozen=True)
class ExrHeader:
    """What :func:`exr_header` reads: the data window's size and the channels."""

    width: int
    height: int
    channels: tuple[str, ...]


class _Cursor:
    def __init__(self, data: bytes, what: str) -> None:
        self.data, self.pos, self.what = data, 0, what

    def take(self, n: int) -> bytes:
        if n < 0 or self.pos + n > len(self.data):
            raise ValueError(f"{self.what}: the OpenEXR header is truncated or corrupt")
        out = self.data[self.pos : self.pos + n]
        self.pos += n
        return out

    def cstring(self, limit: int) -> bytes:
        end = self.data.find(b"\x00", self.pos, self.pos + limit + 1)
        if end < 0:
            raise ValueError(f"{self.what}: the OpenEXR header is truncated or corrupt")
        out = self.data[self.pos : end]
        self.pos = end + 1
        return out


def exr_header(data: bytes, *, what: str, max_channels: int) -> ExrHeader:
    """The data window and channel names from the start of an OpenEXR file (nothing decoded).

    Parameters
    ----------
    data : bytes
        The file's first bytes (the whole header must be among them).
    max_channels : int
        More channels than this are refused (each costs a full-size decode).

    Raises
    ------
    ValueError
        Not OpenEXR, a multi-part or deep file, a header that is truncated or lacks
        ``dataWindow`` / ``channels``, an empty data window, subsampled channels or too many.
    """
    if data[:4] != _EXR_MAGIC:
        raise ValueError(f"{what}: not an OpenEXR file (no OpenEXR magic number)")
    cur = _Cursor(data, what)
    cur.take(4)
    version = struct.unpack("<I", cur.take(4))[0]
    if version & 0xFF != 2 or version & 0x1800:
        raise ValueError(
            f"{what}: OpenEXR version/flags {version:#x}; expected a single-part scanline or "
            "tiled image (version 2, not deep, not multi-part)"
        )
    name_limit = 255 if version & 0x400 else 31
    window = channels = None
    while True:
        name = cur.cstring(name_limit)
        if not name:
            break
        kind = cur.cstring(name_limit)
        size = struct.unpack("<i", cur.take(4))[0]
        value = cur.take(size)
        if name == b"dataWindow" and kind == b"box2i" and size == 16:
            window = struct.unpack("<iiii", value)
        elif name == b"channels" and kind == b"chlist":
            channels = _exr_channels(value, what, max_channels)
    if window is None or channels is None:
        raise ValueError(f"{what}: the OpenEXR header lacks 'dataWindow' or 'channels'")
    x0, y0, x1, y1 = window
    width, height = x1 - x0 + 1, y1 - y0 + 1
    if width < 1 or height < 1:
        raise ValueError(f"{what}: the OpenEXR data window {window} is empty")
    return ExrHeader(width, height, channels)


def _exr_channels(value: bytes, what: str, max_channels: int) -> tuple[str, ...]:
    cur = _Cursor(value, what)
    names = []
    while True:
        name = cur.cstring(255)
        if not name:
            break
        _pixel_type, _linear, _reserved, xs, ys = struct.unpack("<iB3sii", cur.take(16))
        if (xs, ys) != (1, 1):
            raise ValueError(
                f"{what}: OpenEXR channel {name.decode('latin-1')!r} is subsampled ({xs}, {ys}); "
                "expected full-resolution channels"
            )
        names.append(name.decode("latin-1"))
        if len(names) > max_channels:
            raise ValueError(
                f"{what}: the OpenEXR file has more than {max_channels} channels; expected R, "
                "G, B and A"
            )
    return tuple(names)


# -- .npy --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NpyHeader:
    """What :func:`npy_header` reads: shape, dtype, order and where the data starts."""

    shape: tuple[int, ...]
    dtype: np.dtype
    fortran_order: bool
    offset: int


def npy_header(data: bytes, *, what: str) -> NpyHeader:
    """Shape and dtype from a ``.npy`` header (no array is built).

    Raises
    ------
    ValueError
        Not a ``.npy`` file, a header that cannot be parsed, or a dtype that is not a plain
        boolean, integer or float (object and structured arrays are refused).
    """
    f = io.BytesIO(data)
    try:
        major, _minor = np.lib.format.read_magic(f)
        if major == 1:
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(f)
        elif major == 2:
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(f)
        else:
            raise ValueError(f"format version {major} (this reader takes 1 and 2)")
    except Exception as exc:  # noqa: BLE001 -- numpy raises ValueError and others on bad headers
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ValueError(f"{what}: not a readable .npy file ({short_repr(first)})") from None
    if dtype.hasobject or dtype.fields is not None or dtype.kind not in "biuf":
        raise ValueError(
            f"{what}: .npy dtype {short_repr(str(dtype))}; expected a boolean, integer or float array"
        )
    return NpyHeader(tuple(int(s) for s in shape), dtype, bool(fortran), f.tell())


def npy_array(data: bytes, header: NpyHeader, *, what: str) -> np.ndarray:
    """The array of a ``.npy`` file's bytes (read-only, no copy) as its header describes it.

    Raises
    ------
    ValueError
        The data is shorter or longer than the header's shape and dtype need.
    """
    count = int(np.prod(header.shape, dtype=object))
    need = count * header.dtype.itemsize
    have = len(data) - header.offset
    if have != need:
        raise ValueError(
            f"{what}: the .npy file holds {have} bytes of data, its header {header.shape} "
            f"{header.dtype} needs {need} (truncated or corrupt)"
        )
    a = np.frombuffer(data, dtype=header.dtype, count=count, offset=header.offset)
    order = "F" if header.fortran_order else "C"
    return a.reshape(header.shape, order=order)
