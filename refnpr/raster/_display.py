"""A G-buffer as a picture: one labelled tile per channel (component), for Jupyter's display.

Each channel becomes a small RGB tile at most ``max_tile`` pixels on its long side (nearest
sample, so ids stay crisp):

* ``depth``, ``ndc_z``: normalised over the covered samples, near = bright.
* ``normal``: ``0.5 n + 0.5`` as RGB; ``bary``: as RGB; ``uv``: (u, v) as (R, G), its
  fractional part (the texture repeats) when it leaves [0, 1].
* derivatives (``d*_dx``, ``d*_dy``, one tile per component), ``dyadic_scale`` and ``lod``: a
  symmetric (diverging) colour map, blue < 0 < red, white at 0, scaled by the 98th percentile
  of the magnitudes.
* ``tri_id``, ``mesh_id``: a colour from the id (golden-ratio hue steps, hashed shade), so
  neighbouring ids differ.
* ``coverage`` and other scalars: grey; other vectors: their first three components as RGB.

Samples where no triangle is (``tri_id`` or ``mesh_id`` < 0, else depth not finite) show a grey
checkerboard. Each tile carries its channel name, drawn with a built-in 3 x 5 bitmap font
(no matplotlib). Imports numpy and imageio only (the raster layer imports nothing else).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "channel_tiles",
    "compose_grid",
    "gbuffer_grid",
    "gbuffer_png",
    "hash_colors",
    "label_bitmap",
    "symmetric_colors",
]

# ---------------------------------------------------------------------------- bitmap font
#: 3 x 5 glyphs, five rows of three bits each (top row first); letters are drawn as capitals.
_GLYPHS: dict[str, str] = {
    "a": "010101111101101", "b": "110101110101110", "c": "011100100100011",
    "d": "110101101101110", "e": "111100110100111", "f": "111100110100100",
    "g": "011100101101011", "h": "101101111101101", "i": "111010010010111",
    "j": "001001001101010", "k": "101101110101101", "l": "100100100100111",
    "m": "101111111101101", "n": "110101101101101", "o": "010101101101010",
    "p": "110101110100100", "q": "010101101110011", "r": "110101110101101",
    "s": "011100010001110", "t": "111010010010010", "u": "101101101101111",
    "v": "101101101101010", "w": "101101111111101", "x": "101101010101101",
    "y": "101101010010010", "z": "111001010100111", "0": "111101101101111",
    "1": "010110010010111", "2": "110001010100111", "3": "110001010001110",
    "4": "101101111001001", "5": "111100110001110", "6": "011100111101111",
    "7": "111001010010010", "8": "111101111101111", "9": "111101111001110",
    "_": "000000000000111", ".": "000000000000010", "-": "000000111000000",
    " ": "000000000000000", "[": "110100100100110", "]": "011001001001011",
    "(": "010100100100010", ")": "010001001001010", "?": "110001010000010",
}  # fmt: skip
GLYPH_W, GLYPH_H = 3, 5


def label_bitmap(text: str, scale: int = 1) -> np.ndarray:
    """The text drawn with the 3 x 5 font: ``(5 s, (4 len - 1) s)`` bool, True where ink is.

    Parameters
    ----------
    text : str
        Any characters; those without a glyph are drawn as ``?`` (case is ignored).
    scale : int >= 1
        Each font pixel becomes ``scale x scale`` pixels.
    """
    if not isinstance(text, str):
        raise TypeError(f"text: expected a str, got {type(text).__name__} {text!r}")
    if isinstance(scale, bool) or not isinstance(scale, (int, np.integer)) or scale < 1:
        raise ValueError(f"scale: expected an integer >= 1, got {scale!r}")
    if not text:
        return np.zeros((GLYPH_H * scale, 0), dtype=bool)
    cols = []
    for i, ch in enumerate(text.lower()):
        bits = _GLYPHS.get(ch, _GLYPHS["?"])
        cols.append(np.array([b == "1" for b in bits], dtype=bool).reshape(GLYPH_H, GLYPH_W))
        if i < len(text) - 1:
            cols.append(np.zeros((GLYPH_H, 1), dtype=bool))  # one column between glyphs
    bitmap = np.concatenate(cols, axis=1)
    return np.repeat(np.repeat(bitmap, scale, axis=0), scale, axis=1)


# ---------------------------------------------------------------------------- colour maps
_NEG = np.array([0.19, 0.32, 0.78])  # blue end of the diverging map
_POS = np.array([0.75, 0.10, 0.13])  # red end
#: Percentile of |value| that the symmetric map's ends stand for when no scale is given.
ROBUST_PERCENTILE = 98.0
_CHECKER = (np.array([0.30, 0.30, 0.30]), np.array([0.42, 0.42, 0.42]))


def symmetric_colors(values: np.ndarray, scale: float | None = None) -> np.ndarray:
    """A diverging colour map symmetric about 0: ``(...,)`` float -> ``(..., 3)`` float64 in
    [0, 1]; -scale blue, 0 white, +scale red, clipped beyond. ``scale``: when None, the 98th
    percentile of the finite ``|values|`` (a few grazing-angle samples do not wash the rest
    out); non-finite values take the colour of their sign's end (NaN white)."""
    v = np.asarray(values, dtype=np.float64)
    if scale is None:
        finite = np.abs(v[np.isfinite(v)])
        scale = float(np.percentile(finite, ROBUST_PERCENTILE)) if finite.size else 1.0
    scale = scale if scale > 0 else 1.0
    t = np.clip(np.nan_to_num(v / scale, nan=0.0, posinf=1.0, neginf=-1.0), -1.0, 1.0)
    end = np.where((t < 0)[..., None], _NEG, _POS)
    a = np.abs(t)[..., None]
    return (1.0 - a) * 1.0 + a * end


def hash_colors(ids: np.ndarray) -> np.ndarray:
    """Integer ids -> ``(..., 3)`` float64 colours in [0, 1] that tell neighbours apart.

    Hue steps by the golden ratio per id (consecutive ids, such as the triangles of one strip,
    are 137 degrees apart), saturation and value come from a 32-bit integer hash of the id
    (the "lowbias32" mixer), so ids whose hues nearly repeat still differ in shade.
    """
    i = np.asarray(ids).astype(np.int64)
    x = i.astype(np.uint32)
    x = x ^ (x >> np.uint32(16))
    x = x * np.uint32(0x7FEB352D)
    x = x ^ (x >> np.uint32(15))
    x = x * np.uint32(0x846CA68B)
    x = x ^ (x >> np.uint32(16))
    hue = np.mod(i * 0.6180339887498949 + 0.11, 1.0)
    sat = 0.55 + 0.45 * (x & np.uint32(0xFF)).astype(np.float64) / 255.0
    val = 0.60 + 0.40 * ((x >> np.uint32(8)) & np.uint32(0xFF)).astype(np.float64) / 255.0
    return _hsv_to_rgb(hue, sat, val)


def _hsv_to_rgb(h: np.ndarray, s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """HSV in [0, 1] -> ``(..., 3)`` RGB (the hexcone model)."""
    k = np.mod(np.asarray(h)[..., None] * 6.0 + np.array([5.0, 3.0, 1.0]), 6.0)
    f = np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)
    return np.asarray(v)[..., None] * (1.0 - np.asarray(s)[..., None] * f)


def _normalise(v: np.ndarray, covered: np.ndarray) -> np.ndarray:
    """Min-max over the covered, finite samples (per last axis when ``v`` is (h, w, C))."""
    v = np.asarray(v, dtype=np.float64)
    ok = covered & np.all(np.isfinite(v), axis=-1) if v.ndim == 3 else covered & np.isfinite(v)
    if not ok.any():
        return np.zeros_like(v)
    sel = v[ok]
    lo, hi = sel.min(axis=0), sel.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return np.clip(np.nan_to_num((v - lo) / span), 0.0, 1.0)


# ---------------------------------------------------------------------------- tiles
_VECTOR_SUFFIX = {2: ("u", "v"), 3: ("x", "y", "z")}
_SIGNED = ("dyadic_scale", "lod")
_FIRST = (
    "depth", "ndc_z", "tri_id", "mesh_id", "coverage", "coverage_count", "normal", "position",
    "bary", "uv", "duv_dx", "duv_dy", "lod", "dyadic_scale", "dposition_dx", "dposition_dy",
)  # fmt: skip


def _is_derivative(name: str) -> bool:
    return name.startswith("d") and (name.endswith("_dx") or name.endswith("_dy"))


def _tile_shape(height: int, width: int, max_tile: int) -> tuple[int, int]:
    s = min(1.0, max_tile / max(height, width))
    return max(1, int(round(height * s))), max(1, int(round(width * s)))


def _resample(a: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Nearest sample of ``a`` (h, w[, C]) at the centres of a ``shape`` grid."""
    rows = ((np.arange(shape[0]) + 0.5) * a.shape[0] / shape[0]).astype(np.int64)
    cols = ((np.arange(shape[1]) + 0.5) * a.shape[1] / shape[1]).astype(np.int64)
    return a[np.minimum(rows, a.shape[0] - 1)][:, np.minimum(cols, a.shape[1] - 1)]


def _covered(channels: Mapping[str, np.ndarray], shape: tuple[int, int]) -> np.ndarray:
    """(h, w) bool at tile resolution: samples a triangle covers (all True if unknown)."""
    for name in ("tri_id", "mesh_id"):
        if name in channels:
            return _resample(np.asarray(channels[name]), shape) >= 0
    if "depth" in channels:
        return np.isfinite(_resample(np.asarray(channels["depth"], dtype=np.float64), shape))
    return np.ones(shape, dtype=bool)


def _checker(shape: tuple[int, int], cell: int = 4) -> np.ndarray:
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    odd = ((yy // cell + xx // cell) % 2).astype(bool)
    return np.where(odd[..., None], _CHECKER[1], _CHECKER[0])


def _channel_colors(name: str, v: np.ndarray, covered: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """(label, (h, w, 3) float64) tiles of one channel already resampled to tile size."""
    comps = 1 if v.ndim == 2 else v.shape[2]
    if name in ("tri_id", "mesh_id"):
        return [(name, hash_colors(v))]
    if name in ("depth", "ndc_z"):
        g = 1.0 - _normalise(v, covered)  # near = bright
        return [(name, np.repeat(g[..., None], 3, axis=2))]
    if name in _SIGNED or (_is_derivative(name) and comps == 1):
        return [(name, symmetric_colors(np.where(covered, v, 0.0)))]
    if _is_derivative(name):
        suffix = _VECTOR_SUFFIX.get(comps, tuple(str(i) for i in range(comps)))
        masked = np.where(covered[..., None], v, 0.0)
        return [(f"{name}.{s}", symmetric_colors(masked[..., i])) for i, s in enumerate(suffix)]
    if name == "normal" and comps == 3:
        return [(name, np.clip(0.5 * v + 0.5, 0.0, 1.0))]
    if name == "bary" and comps == 3:
        return [(name, np.clip(v, 0.0, 1.0))]
    if name == "uv" and comps == 2:
        sel = v[covered] if covered.any() else v.reshape(-1, 2)
        inside = sel.size == 0 or (np.nanmin(sel) >= 0.0 and np.nanmax(sel) <= 1.0)
        rg = np.clip(v, 0.0, 1.0) if inside else np.mod(np.nan_to_num(v), 1.0)  # repeats
        return [(name, np.concatenate([rg, np.zeros(v.shape[:2] + (1,))], axis=2))]
    if comps == 1:
        g = _normalise(v, covered) if name != "coverage" else np.clip(v, 0.0, 1.0)
        return [(name, np.repeat(g[..., None], 3, axis=2))]
    rgb = _normalise(v[..., :3], covered)
    if rgb.shape[2] < 3:
        rgb = np.concatenate([rgb, np.zeros(rgb.shape[:2] + (3 - rgb.shape[2],))], axis=2)
    return [(name, rgb)]


def channel_tiles(
    channels: Mapping[str, Any], height: int, width: int, *, max_tile: int = 256
) -> list[tuple[str, np.ndarray]]:
    """One labelled tile per channel (per component for vector derivatives).

    Parameters
    ----------
    channels : mapping of str to array
        G-buffer channels, each ``(h, w)`` or ``(h, w, C)`` (sample grid or pixel grid).
    height, width : int
        The image size in pixels (tiles keep its aspect).
    max_tile : int
        Longest side of a tile in pixels (buffers are shown downscaled, nearest sample).

    Returns
    -------
    list of (label, (th, tw, 3) uint8)
        Built-in channels in a fixed order, then the others sorted by name.
    """
    if isinstance(max_tile, bool) or not isinstance(max_tile, (int, np.integer)) or max_tile < 8:
        raise ValueError(f"max_tile: expected an integer >= 8 (pixels), got {max_tile!r}")
    shape = _tile_shape(int(height), int(width), int(max_tile))
    covered = _covered(channels, shape)
    background = _checker(shape)
    names = [n for n in _FIRST if n in channels] + sorted(set(channels) - set(_FIRST))
    tiles = []
    for name in names:
        v = _resample(np.asarray(channels[name]), shape)
        if v.dtype.kind in "iub" and name not in ("tri_id", "mesh_id"):
            v = v.astype(np.float64)
        shown = v > 0 if name == "coverage" else covered  # coverage: partial pixels too
        for label, rgb in _channel_colors(name, v, shown):
            rgb = np.where(shown[..., None], rgb, background)
            tiles.append((label, np.rint(np.clip(rgb, 0.0, 1.0) * 255.0).astype(np.uint8)))
    return tiles


#: Grid layout: gap between tiles, label strip padding, colours of the frame and the text.
GAP, PAD = 2, 2
FRAME = np.array([24, 24, 24], dtype=np.uint8)
INK = np.array([235, 235, 235], dtype=np.uint8)


def label_scale(label: str, tile_width: int) -> int:
    """2 where the label fits the tile at double size, else 1."""
    return 2 if (4 * len(label) - 1) * 2 + 2 * PAD <= tile_width else 1


def compose_grid(tiles: Sequence[tuple[str, np.ndarray]], *, columns: int = 4) -> np.ndarray:
    """Tiles of one size in rows of ``columns``, each under a strip with its label: ``(H, W, 3)``
    uint8, cell k at ``(GAP + (k // columns) (strip + th + GAP), GAP + (k % columns) (tw + GAP))``
    with ``strip = 5 * 2 + 2 PAD`` pixels of label above the tile."""
    if not tiles:
        return np.full((16, 16, 3), FRAME, dtype=np.uint8)
    th, tw = tiles[0][1].shape[:2]
    strip = GLYPH_H * 2 + 2 * PAD
    ncol = min(columns, len(tiles))
    nrow = -(-len(tiles) // ncol)
    out = np.empty((GAP + nrow * (strip + th + GAP), GAP + ncol * (tw + GAP), 3), np.uint8)
    out[:] = FRAME
    for k, (label, tile) in enumerate(tiles):
        y0 = GAP + (k // ncol) * (strip + th + GAP)
        x0 = GAP + (k % ncol) * (tw + GAP)
        bits = label_bitmap(label, label_scale(label, tw))[:, : max(0, tw - 2 * PAD)]
        ly = y0 + PAD + (GLYPH_H * 2 - bits.shape[0]) // 2
        region = out[ly : ly + bits.shape[0], x0 + PAD : x0 + PAD + bits.shape[1]]
        region[bits] = INK
        out[y0 + strip : y0 + strip + th, x0 : x0 + tw] = tile
    return out


def gbuffer_grid(gb: Any, *, max_tile: int = 256, columns: int = 4) -> np.ndarray:
    """``(H, W, 3)`` uint8: every channel of the G-buffer ``gb`` as a labelled tile grid."""
    tiles = channel_tiles(gb.channels, gb.height, gb.width, max_tile=max_tile)
    return compose_grid(tiles, columns=columns)


def gbuffer_png(gb: Any, *, max_tile: int = 256, columns: int = 4) -> bytes:
    """The :func:`gbuffer_grid` picture as PNG bytes (what Jupyter shows for a G-buffer)."""
    import imageio.v3 as iio

    grid = gbuffer_grid(gb, max_tile=max_tile, columns=columns)
    return bytes(iio.imwrite("<bytes>", grid, extension=".png"))
