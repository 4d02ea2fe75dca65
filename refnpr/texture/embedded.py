"""Encoded images held in memory (a glTF file's embedded PNG or JPEG) as material textures.

An :class:`EmbeddedImage` is a ``str`` whose text names the image and its content
(``"model.glb#images[0]@sha256:1a2b3c4d5e6f7a8b"``) and which carries the encoded bytes. Being a
string, it goes wherever a texture name or path goes (``Material.texture``, caches keyed by the
texture's text, the kit's JSON), and :func:`refnpr.texture.load_texture` decodes it from memory.

The bytes are untrusted: the image size is read from the PNG ``IHDR`` chunk or the JPEG ``SOFn``
segment and checked against :data:`MAX_IMAGE_SIDE` and :data:`MAX_IMAGE_PIXELS` before anything
is decoded.
"""

from __future__ import annotations

import hashlib
import struct
from typing import Any

import numpy as np

from ..image import PNG_SIGNATURE, decode_image, png_size

__all__ = [
    "EmbeddedImage",
    "IMAGE_MIME_TYPES",
    "MAX_IMAGE_PIXELS",
    "MAX_IMAGE_SIDE",
    "probe_image",
]

#: The encodings an embedded image may have (the glTF 2.0 core image types).
IMAGE_MIME_TYPES = ("image/png", "image/jpeg")
#: The largest width or height of an image a glTF file names (pixels).
MAX_IMAGE_SIDE = 8192
#: The most pixels (width x height) of an image a glTF file names: 16 Mi, e.g. 4096 x 4096 (its
#: mip pyramid as a colour map takes about 1 s and 0.7 GB to build).
MAX_IMAGE_PIXELS = 1 << 24

_JPEG_SOI = b"\xff\xd8"
#: JPEG start-of-frame markers (SOF0-SOF15 but DHT, JPG and DAC, which share the range).
_JPEG_SOF = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}
_JPEG_STANDALONE = frozenset({0x01, *range(0xD0, 0xD8)})  # TEM, RST0-7: no length field
_EXTENSIONS = {"image/png": ".png", "image/jpeg": ".jpg"}


def _jpeg_size(data: bytes) -> tuple[int, int]:
    i, n = 2, len(data)
    while True:
        while i < n and data[i] != 0xFF:  # bytes between segments: skip, as decoders do
            i += 1
        while i < n and data[i] == 0xFF:  # a marker and its fill bytes
            i += 1
        if i >= n:
            raise ValueError("the JPEG data ends before its frame header (SOF segment)")
        marker = data[i]
        i += 1
        if marker in _JPEG_STANDALONE or marker == 0xD8:
            continue
        if marker in (0xD9, 0xDA):
            raise ValueError("the JPEG data has no frame header (SOF segment) before its scan")
        if i + 2 > n:
            raise ValueError("the JPEG data is truncated inside a segment header")
        (length,) = struct.unpack_from(">H", data, i)
        if length < 2 or i + length > n:
            raise ValueError(f"the JPEG segment 0xFF{marker:02X} is truncated or malformed")
        if marker in _JPEG_SOF:
            if length < 8:
                raise ValueError(f"the JPEG frame header (0xFF{marker:02X}) is too short")
            height, width = struct.unpack_from(">HH", data, i + 3)
            if height == 0:
                raise ValueError(
                    "the JPEG frame header gives height 0 (a height set later by a DNL "
                    "marker); re-encode the image"
                )
            return width, height
        i += length


def probe_image(data: bytes, mime_type: str | None = None) -> tuple[str, int, int]:
    """The encoding and size of an encoded image, read from its header only.

    Parameters
    ----------
    data : bytes
        PNG or JPEG file contents.
    mime_type : str, optional
        The declared encoding (one of :data:`IMAGE_MIME_TYPES`); the data must be of that kind.
        None: taken from the data's signature.

    Returns
    -------
    (mime_type, width, height) : (str, int, int)

    Raises
    ------
    ValueError
        A ``mime_type`` not in :data:`IMAGE_MIME_TYPES`, data that is neither PNG nor JPEG or
        not of the declared kind, a truncated header, a size of 0 or one above
        :data:`MAX_IMAGE_SIDE` a side or :data:`MAX_IMAGE_PIXELS` in all. The message names
        no file: callers prefix what the image is.
    """
    if mime_type is not None and mime_type not in IMAGE_MIME_TYPES:
        raise ValueError(
            f"mimeType {mime_type!r} is not an image type refnpr reads; expected one of "
            f"{list(IMAGE_MIME_TYPES)} (re-encode the image as PNG or JPEG)"
        )
    if data[:8] == PNG_SIGNATURE:
        kind = "image/png"
    elif data[:2] == _JPEG_SOI:
        kind = "image/jpeg"
    else:
        raise ValueError(
            f"the data is neither a PNG nor a JPEG image (it starts with {bytes(data[:8])!r})"
        )
    if mime_type is not None and kind != mime_type:
        raise ValueError(
            f"declared {mime_type!r} but the data is {'a PNG' if kind == 'image/png' else 'a JPEG'}"
            " image; correct the mimeType"
        )
    if kind == "image/png":
        width, height = png_size(data, what="the PNG data")
    else:
        width, height = _jpeg_size(data)
    if width == 0 or height == 0:
        raise ValueError(f"the image header gives a size of {width} x {height} pixels")
    if max(width, height) > MAX_IMAGE_SIDE or width * height > MAX_IMAGE_PIXELS:
        raise ValueError(
            f"the image header gives {width} x {height} pixels, more than refnpr decodes "
            f"({MAX_IMAGE_SIDE} a side, {MAX_IMAGE_PIXELS} pixels in all); scale the image down"
        )
    return kind, width, height


class EmbeddedImage(str):
    """An encoded PNG or JPEG image in memory, usable as a texture name.

    The string value is ``"<name>@sha256:<the 64 hex digits of the SHA-256 of the bytes>"``,
    so that equal strings mean the same name and the same content, and every cache keyed by
    the texture's text tells different images apart. Immutable; pickles
    with its bytes.

    Parameters
    ----------
    name : str
        What the image is, for messages, e.g. ``"model.glb#images[0]"``.
    data : bytes-like
        The encoded image as stored (PNG or JPEG).
    mime_type : str, optional
        The declared encoding, one of :data:`IMAGE_MIME_TYPES`; None: from the data.

    Attributes
    ----------
    name : str
    data : bytes
    mime_type : str
    width, height : int
        The size its header gives (checked against :data:`MAX_IMAGE_SIDE` and
        :data:`MAX_IMAGE_PIXELS`).
    sha256 : str
        The hex SHA-256 digest of ``data``.

    Raises
    ------
    TypeError
        ``name`` not a non-empty str, ``data`` not bytes-like.
    ValueError
        As :func:`probe_image`, the message starting with ``name``.
    """

    name: str
    data: bytes
    mime_type: str
    width: int
    height: int
    sha256: str

    def __new__(cls, name: str, data: Any, mime_type: str | None = None) -> EmbeddedImage:
        if not isinstance(name, str) or not name:
            raise TypeError(f"name: expected a non-empty str, got {name!r}")
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise TypeError(
                f"{name}: data: expected the encoded image as bytes, got {type(data).__name__}"
            )
        data = bytes(data)
        try:
            kind, width, height = probe_image(data, mime_type)
        except ValueError as exc:
            raise ValueError(f"{name}: {exc}") from None
        digest = hashlib.sha256(data).hexdigest()
        self = super().__new__(cls, f"{name}@sha256:{digest}")
        values = {"name": name, "data": data, "mime_type": kind, "width": width, "height": height}
        self.__dict__.update(values, sha256=digest)
        return self

    def __setattr__(self, key: str, value: Any) -> None:
        raise AttributeError(f"EmbeddedImage is immutable (cannot set {key!r})")

    def __delattr__(self, key: str) -> None:
        raise AttributeError(f"EmbeddedImage is immutable (cannot delete {key!r})")

    def __reduce__(self) -> tuple:
        return (EmbeddedImage, (self.name, self.data, self.mime_type))

    def __repr__(self) -> str:
        return (
            f"EmbeddedImage({self.name!r}, {self.mime_type}, {self.width}x{self.height}, "
            f"sha256={self.sha256[:16]})"
        )

    def decode(self, *, what: str = "texture") -> np.ndarray:
        """The decoded pixels.

        Parameters
        ----------
        what : str
            The parameter the image came from, which error messages start with.

        Returns
        -------
        (height, width) or (height, width, C) uint8 or uint16
            As :func:`refnpr.image.decode_image` gives them (C = 2, 3 or 4: gray + alpha, RGB,
            RGBA; a CMYK JPEG as RGB; a 16-bit PNG as uint16): the same values as the image read
            from a file.

        Raises
        ------
        ValueError
            Data that does not decode, or decodes to another size than its header gives.
        """
        try:
            pixels = decode_image(self.data, extension=_EXTENSIONS[self.mime_type])
        except Exception as exc:  # decoders raise many types; report them as a bad image
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ValueError(
                f"{what}: cannot decode {str(self)!r} ({self.mime_type}): {reason}; re-encode "
                "the image"
            ) from None
        if pixels.shape[:2] != (self.height, self.width):
            raise ValueError(
                f"{what}: {str(self)!r} decodes to {pixels.shape[1]} x {pixels.shape[0]} pixels "
                f"but its header gives {self.width} x {self.height}; re-encode the image"
            )
        return pixels
