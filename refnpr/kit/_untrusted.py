"""Reading files of an untrusted kit: relative paths kept inside their directory, regular files
read with a size cap, and the sizes in PNG, OpenEXR and ``.npy`` headers read before any pixel
is decoded.

Every function raises ``ValueError`` with a message that starts with ``what`` (the role of the
file) and quotes paths and values with ``repr`` (so control characters arrive escaped). The
limits are the caller's (``refnpr.kit.check`` holds the documented ones).
"""

from __future__ import annotations

import io
import os
import stat
import struct
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

import numpy as np

from ..image import png_size

__all__ = [
    "ExrHeader",
    "NpyHeader",
    "exr_header",
    "inside",
    "npy_array",
    "npy_header",
    "png_size",
    "printable",
    "read_regular",
]


def printable(text: object) -> str:
    """``str(text)`` with every non-printable character (control characters such as ESC,
    format characters such as the bidi overrides, line separators, lone surrogates) written as
    a Python escape (``\\x1b``, ``\\u202e``); idempotent, so it may be applied more than once."""
    s = str(text)
    if s.isprintable():
        return s
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in s)


def _short(value: Any, limit: int = 120) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def inside(root: Path, rel: Any, *, what: str, root_name: str, base: Path | None = None) -> Path:
    """The path ``rel`` (relative, ``/``-separated) under ``base``, resolved and inside ``root``.

    Parameters
    ----------
    root : Path
        A resolved directory (``Path.resolve(strict=True)``).
    rel : Any
        The path as the kit gives it, relative to ``base``.
    what : str
        The key that holds it (``"expected.png"``), the start of every message.
    root_name : str
        What ``root`` is (``"the kit"``), for messages.
    base : Path, optional
        A resolved directory inside ``root`` that ``rel`` is relative to (default ``root``).

    Returns
    -------
    Path
        Absolute, with every symbolic link resolved, inside ``root`` (it need not exist).

    Raises
    ------
    ValueError
        ``rel`` is not a non-empty string; is absolute; has a ``..`` component, a backslash or a
        NUL; or resolves outside ``root`` (a symbolic link out, or a link loop).
    """
    if not isinstance(rel, str) or not rel:
        raise ValueError(
            f"{what}: expected a relative file path (a non-empty string), got {_short(rel)}"
        )
    if "\x00" in rel or "\\" in rel:
        raise ValueError(
            f"{what}: {_short(rel)} holds a NUL or a backslash; use '/' between path parts"
        )
    p = PurePosixPath(rel)
    if p.is_absolute() or (len(rel) > 1 and rel[1] == ":"):
        raise ValueError(
            f"{what}: {_short(rel)} is an absolute path; expected a path relative to {root_name}"
        )
    if ".." in p.parts:
        raise ValueError(
            f"{what}: {_short(rel)} has a '..' component; expected a path inside {root_name}"
        )
    try:
        resolved = ((root if base is None else base) / p).resolve()
    except (OSError, RuntimeError) as exc:  # a symbolic link loop
        raise ValueError(f"{what}: {_short(rel)} cannot be resolved ({exc})") from None
    if not resolved.is_relative_to(root):
        raise ValueError(
            f"{what}: {_short(rel)} leads outside {root_name} (to {_short(str(resolved))}, "
            "through a symbolic link); files must lie inside it"
        )
    return resolved


def read_regular(path: Path, *, what: str, max_bytes: int, head: int | None = None) -> bytes:
    """The contents of a regular file (at most ``max_bytes`` of it exist), or its first
    ``head`` bytes.

    Devices (``/dev/zero``), FIFOs, sockets and directories are refused before they are
    opened, so a read never blocks or runs forever; the file is opened without following a
    symbolic link and checked again once open.

    Parameters
    ----------
    path : Path
        The file (resolved).
    what : str
        The file as messages name it (``"render 'x.png'"``).

    Raises
    ------
    ValueError
        The file does not exist, is not a regular file, is larger than ``max_bytes`` or
        cannot be read.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ValueError(f"{what} does not exist") from None
    except OSError as exc:
        raise ValueError(f"{what}: cannot read it: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
        raise ValueError(f"{what} is {kind}; expected a regular file")
    if st.st_size > max_bytes:
        raise ValueError(f"{what} has {st.st_size} bytes, more than the {max_bytes} bytes allowed")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise ValueError(f"{what}: cannot open it: {exc.strerror}") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise ValueError(f"{what} is not a regular file; expected a regular file")
        # never ask for more than the file holds (+1 to see growth): read(n) allocates n bytes
        n = min(st.st_size, max_bytes) + 1
        n = n if head is None else min(head, n)
        try:
            data = f.read(n)
        except OSError as exc:
            raise ValueError(f"{what}: cannot read it: {exc.strerror}") from None
    if len(data) > max_bytes:  # the file grew since the stat
        raise ValueError(f"{what} has more than the {max_bytes} bytes allowed")
    return data


# -- PNG ---------------------------------------------------------------------------------------

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
        raise ValueError(f"{what}: not a readable .npy file ({_short(first)})") from None
    if dtype.hasobject or dtype.fields is not None or dtype.kind not in "biuf":
        raise ValueError(
            f"{what}: .npy dtype {_short(str(dtype))}; expected a boolean, integer or float array"
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
