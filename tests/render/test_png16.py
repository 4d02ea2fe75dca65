"""16-bit RGB, RGBA and grey + alpha PNGs are read at 16 bits (``refnpr.image.decode_png16``):
textures, colour maps and compared images (``refnpr.image.decode_image``) and a backend's renders
in ``kit check``.

The files are written here by an encoder of the tests' own. It filters each row from the
original bytes (PNG sec. 9, vectorized). The decoder instead undoes the filters from the
reconstructed bytes, sample by sample. Interlaced files are written as the seven Adam7 sub-images
(sec. 8.2). Two oracles check the decoder:
- the array the file was written from;
- Pillow's 8-bit reading of the same file (the high bytes), a second decoder of every filter and
  of interlacing.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.compare import load_image
from refnpr.image import decode_image, decode_png16, read_image_file

COLOUR_TYPES = {3: 2, 2: 4, 4: 6}  # channels -> PNG colour type
#: Adam7 as the PNG specification draws it (sec. 8.2): the pass (1-7) of each pixel of an 8 x 8
#: tile; a form of its own, not the decoder's table of pass origins and steps.
ADAM7_TILE = np.array(
    [
        [1, 6, 4, 6, 2, 6, 4, 6],
        [7, 7, 7, 7, 7, 7, 7, 7],
        [5, 6, 5, 6, 5, 6, 5, 6],
        [7, 7, 7, 7, 7, 7, 7, 7],
        [3, 6, 4, 6, 3, 6, 4, 6],
        [7, 7, 7, 7, 7, 7, 7, 7],
        [5, 6, 5, 6, 5, 6, 5, 6],
        [7, 7, 7, 7, 7, 7, 7, 7],
    ]
)


def _paeth(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    p = a + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))


def _filtered(img: np.ndarray, kinds: list[int]) -> bytes:
    """The filtered scanlines of one (sub-)image: (h, w, C) uint16, a filter type per row."""
    h, w, c = img.shape
    rows = img.astype(">u2").view(np.uint8).reshape(h, w * c * 2).astype(np.int64)
    bpp = 2 * c
    out = []
    for y in range(h):
        x = rows[y]
        up = rows[y - 1] if y else np.zeros_like(x)
        left = np.concatenate([np.zeros(bpp, np.int64), x[:-bpp]])
        up_left = np.concatenate([np.zeros(bpp, np.int64), up[:-bpp]])
        kind = kinds[y % len(kinds)]
        pred = [0 * x, left, up, (left + up) // 2, _paeth(left, up, up_left)][kind]
        out.append(bytes([kind]) + ((x - pred) % 256).astype(np.uint8).tobytes())
    return b"".join(out)


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def encode_png16(img: np.ndarray, kinds: list[int], *, interlace: bool = False) -> bytes:
    """A 16-bit PNG of ``img (h, w, C)`` uint16, C in 2-4, rows filtered with ``kinds`` in turn."""
    h, w, c = img.shape
    if interlace:  # each pass: the rows and columns holding its pixels, an image of its own
        tile = ADAM7_TILE[np.arange(h)[:, None] % 8, np.arange(w)[None, :] % 8]
        passes = []
        for k in range(1, 8):
            mine = tile == k
            passes.append(img[np.ix_(mine.any(axis=1), mine.any(axis=0))])
        raw = b"".join(_filtered(p, kinds) for p in passes if p.size)
    else:
        raw = _filtered(img, kinds)
    ihdr = struct.pack(">IIBBBBB", w, h, 16, COLOUR_TYPES[c], 0, 0, int(interlace))
    return (
        b"\x89PNG\r\n\x1a\n"
        + _chunk(b"IHDR", ihdr)
        + _chunk(b"IDAT", zlib.compress(raw))
        + _chunk(b"IEND", b"")
    )


def _pillow8(path: Path, channels: int) -> np.ndarray:
    """Pillow's reading as (h, w, channels): grey + alpha comes back as RGBA."""
    a = np.asarray(iio.imread(path))
    return a[..., [0, 3]] if channels == 2 else a


@settings(max_examples=40, deadline=None)
@given(
    h=st.integers(1, 19),
    w=st.integers(1, 19),
    channels=st.sampled_from([2, 3, 4]),
    kinds=st.lists(st.integers(0, 4), min_size=1, max_size=5),
    interlace=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
)
def test_every_filter_and_interlacing_decode_to_the_written_values(
    tmp_path_factory, h, w, channels, kinds, interlace, seed
):
    img = np.random.default_rng(seed).integers(0, 65536, (h, w, channels), dtype=np.uint16)
    path = tmp_path_factory.mktemp("png16") / "x.png"
    path.write_bytes(encode_png16(img, kinds, interlace=interlace))
    got = decode_image(path)
    assert got.dtype == np.uint16 and got.shape == img.shape
    assert np.array_equal(got, img)
    assert np.array_equal(got >> 8, _pillow8(path, channels))
    assert np.array_equal(decode_image(path.read_bytes(), extension=".png"), img)


def test_paeth_ties_and_a_large_image(tmp_path):
    """A flat image with steps (Paeth ties a = b = c), and 300 x 200 RGBA with every filter."""
    img = np.zeros((40, 50, 3), np.uint16)
    img[:, 25:] = 0x1234
    img[20:] += 0x0101
    (tmp_path / "a.png").write_bytes(encode_png16(img, [4]))
    assert np.array_equal(read_image_file(tmp_path / "a.png"), img)
    big = np.random.default_rng(1).integers(0, 65536, (200, 300, 4), dtype=np.uint16)
    (tmp_path / "b.png").write_bytes(encode_png16(big, [0, 1, 2, 3, 4], interlace=True))
    assert np.array_equal(read_image_file(tmp_path / "b.png"), big)


def test_compared_images_keep_the_low_byte(tmp_path):
    img = np.random.default_rng(2).integers(0, 65536, (6, 7, 4), dtype=np.uint16)
    (tmp_path / "r.png").write_bytes(encode_png16(img, [1, 4]))
    assert np.array_equal(load_image(tmp_path / "r.png"), img / 65535.0)


def test_kit_check_reads_16_bit_renders_at_16_bits():
    """A backend's render written as a 16-bit PNG (``kit check``): RGBA as stored, grey + alpha
    spread to RGB."""
    from refnpr.kit.verdict import _decode_png

    rgba = np.random.default_rng(3).integers(0, 65536, (5, 6, 4), dtype=np.uint16)
    assert np.array_equal(_decode_png(encode_png16(rgba, [3]), "render"), rgba / 65535.0)
    la = rgba[..., :2].copy()
    want = (la[..., [0, 0, 0, 1]]) / 65535.0
    assert np.array_equal(_decode_png(encode_png16(la, [4], interlace=True), "render"), want)


def _damaged(tmp_path: Path, data: bytes) -> Path:
    path = tmp_path / "bad.png"
    path.write_bytes(data)
    return path


def test_damaged_files_are_errors_naming_the_file(tmp_path):
    img = np.arange(2 * 3 * 3, dtype=np.uint16).reshape(2, 3, 3) * 999
    good = encode_png16(img, [2])
    crc_at = 8 + 8 + 13  # the IHDR chunk's CRC
    cases = {
        "fails its CRC": good[:crc_at] + bytes([good[crc_at] ^ 1]) + good[crc_at + 1 :],
        "truncated": good[:-20],
    }
    ihdr = struct.pack(">IIBBBBB", 3, 2, 16, 2, 0, 0, 0)
    raw_bad_filter = b"".join(bytes([7]) + bytes(18) for _ in range(2))
    raw_long = b"".join(bytes([0]) + bytes(18) for _ in range(3))
    head = b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr)
    tail = _chunk(b"IEND", b"")
    cases["unknown filter type 7"] = head + _chunk(b"IDAT", zlib.compress(raw_bad_filter)) + tail
    cases["inflates to more bytes"] = head + _chunk(b"IDAT", zlib.compress(raw_long)) + tail
    cases["does not inflate"] = head + _chunk(b"IDAT", b"not zlib data") + tail
    for reason, data in cases.items():
        path = _damaged(tmp_path, data)
        with pytest.raises(ValueError, match="bad.png") as info:
            read_image_file(path, what="texture")
        assert reason in str(info.value), (reason, str(info.value))


def test_a_header_over_the_pixel_bound_is_refused_before_inflating():
    ihdr = struct.pack(">IIBBBBB", 70000, 70000, 16, 6, 0, 0, 0)
    data = (
        b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", b"x") + _chunk(b"IEND", b"")
    )
    with pytest.raises(ValueError, match=r"70000x70000 pixels; at most 1000 are decoded"):
        decode_png16(data, max_pixels=1000)


def test_other_pngs_still_go_to_imageio(tmp_path):
    grey16 = (np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000).astype(np.uint16)
    iio.imwrite(tmp_path / "g.png", grey16)
    assert np.array_equal(read_image_file(tmp_path / "g.png"), grey16)
    rgb8 = np.arange(36, dtype=np.uint8).reshape(3, 4, 3)
    iio.imwrite(tmp_path / "c.png", rgb8)
    got = read_image_file(tmp_path / "c.png")
    assert got.dtype == np.uint8 and np.array_equal(got, rgb8)


def test_an_animated_16_bit_png_is_refused_before_decoding(tmp_path):
    """A 16-bit colour APNG goes to the 16-bit decoder, which reads the default image only: its
    ``acTL`` frame count is checked first, as for every PNG."""
    img = np.arange(2 * 3 * 3, dtype=np.uint16).reshape(2, 3, 3) * 3000
    still = encode_png16(img, [0])
    actl = _chunk(b"acTL", struct.pack(">II", 2, 0))  # 2 frames, loop forever
    at = 8 + 25  # after the signature and IHDR (length, type, 13 bytes, CRC)
    path = tmp_path / "anim16.png"
    path.write_bytes(still[:at] + actl + still[at:])
    with pytest.raises(ValueError, match=r"anim16\.png': the file holds 2 images"):
        read_image_file(path)
    path.write_bytes(still[:at] + _chunk(b"acTL", struct.pack(">II", 1, 0)) + still[at:])
    np.testing.assert_array_equal(read_image_file(path), img)  # one frame: the image
