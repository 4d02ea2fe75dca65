"""Minimal 8-bit PNG reading and writing with zlib alone (no imaging library needed).

Reads non-interlaced 8-bit greyscale, grey+alpha, RGB and RGBA PNGs (every filter type);
writes RGBA (or any 1-4 channel) uint8 arrays. Arrays are in array layout: row 0 is the top.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

__all__ = ["read_png", "write_png"]

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4}  # colour type -> channels


def _unfilter(raw: bytes, h: int, w: int, c: int) -> np.ndarray:
    stride = w * c
    out = np.zeros((h, stride), dtype=np.uint8)
    src = np.frombuffer(raw, dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int32)
    pos = 0
    for y in range(h):
        ftype = src[pos]
        line = src[pos + 1 : pos + 1 + stride].astype(np.int32)
        pos += 1 + stride
        if ftype == 0:
            cur = line
        elif ftype == 2:
            cur = (line + prev) & 0xFF
        else:  # 1 sub, 3 average, 4 Paeth: sequential along the row
            cur = np.zeros(stride, dtype=np.int32)
            for i in range(stride):
                a = cur[i - c] if i >= c else 0
                b = prev[i]
                if ftype == 1:
                    p = a
                elif ftype == 3:
                    p = (a + b) >> 1
                elif ftype == 4:
                    cc = prev[i - c] if i >= c else 0
                    pa, pb, pc = abs(b - cc), abs(a - cc), abs(a + b - 2 * cc)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else cc)
                else:
                    raise ValueError(f"png: unknown filter type {ftype} in row {y}")
                cur[i] = (line[i] + p) & 0xFF
        out[y] = cur
        prev = cur
    return out.reshape(h, w, c)


def read_png(path: str | Path) -> np.ndarray:
    """Read an 8-bit PNG: (H, W) for greyscale, else (H, W, C) uint8, row 0 = top."""
    data = Path(path).read_bytes()
    if not data.startswith(_SIGNATURE):
        raise ValueError(f"png: {str(path)!r} is not a PNG file")
    pos, idat, hdr = 8, [], None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    if hdr is None:
        raise ValueError(f"png: {str(path)!r} has no IHDR chunk")
    w, h, depth, ctype, _, _, interlace = hdr
    if depth != 8 or ctype not in _CHANNELS or interlace != 0:
        raise ValueError(
            f"png: {str(path)!r}: only non-interlaced 8-bit grey/GA/RGB/RGBA PNGs are supported "
            f"(bit depth {depth}, colour type {ctype}, interlace {interlace})"
        )
    img = _unfilter(zlib.decompress(b"".join(idat)), h, w, _CHANNELS[ctype])
    return img[..., 0] if img.shape[2] == 1 else img


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def write_png(path: str | Path, pixels: np.ndarray) -> Path:
    """Write (H, W) or (H, W, C) uint8 (C in 1..4) as a PNG (filter 0, zlib level 6)."""
    px = np.asarray(pixels)
    if px.dtype != np.uint8:
        raise TypeError(f"pixels: expected uint8, got {px.dtype}")
    if px.ndim == 2:
        px = px[..., None]
    if px.ndim != 3 or not 1 <= px.shape[2] <= 4:
        raise ValueError(f"pixels: expected (H, W) or (H, W, C<=4), got shape {pixels.shape}")
    h, w, c = px.shape
    ctype = {1: 0, 2: 4, 3: 2, 4: 6}[c]
    raw = np.concatenate([np.zeros((h, 1), np.uint8), px.reshape(h, w * c)], axis=1)
    out = Path(path)
    out.write_bytes(
        _SIGNATURE
        + _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, ctype, 0, 0, 0))
        + _chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
        + _chunk(b"IEND", b"")
    )
    return out
