"""Procedural halftone screens and stroke layers (Freudenberg et al. 2002, sec. 4).

* :func:`engraving_pyramid` -- the 1D grey ramp of sec. 4.1 as a mip-mapped ``(1, size)``
  texture (Fig. 2, Fig. 5).
* :class:`StrokeSet` -- ordered stroke layers (ink coverage, layer 0 darkest) per mip level, their
  ink greys and optionally a DOT3 normal map per level (sec. 5.2). :func:`stroke_map_pyramid`
  encodes each level with :func:`refnpr.formulas.halftone.encode_stroke_map` (sec. 4.2, Fig. 3).
* Built-in sets drawn procedurally at every mip level: :func:`hatching_set` (parallel hatching at
  several angles, calibrated so that the binary threshold reproduces tone) and :func:`brick_set`
  (brick outlines with a bevel normal map, plus hatching inside the bricks; Fig. 7, Fig. 8).
* :func:`load_stroke_layers` reads layers drawn in a paint program (black ink on a transparent
  or white background, one PNG per layer).

Texture convention as in :mod:`refnpr.texture.pyramid`: u along columns, v along rows, texel
centres at ``(i + 0.5) / size``, GL_REPEAT. Stroke layers are drawn *per mip level* with a stroke
width that never falls below about one texel (as in Praun et al.'s tonal art maps and Freudenberg
et al. 2001): a box-filtered pyramid would blur thin strokes to grey, which the threshold turns
into blotches.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from refnpr.formulas import halftone

from .pyramid import MipPyramid, as_texture, build_pyramid

__all__ = [
    "StrokeSet",
    "line_coverage",
    "hatching_layer",
    "hatching_set",
    "brick_set",
    "load_stroke_layers",
    "stroke_set_from_layers",
    "stroke_map_pyramid",
    "normal_pyramid",
    "engraving_pyramid",
    "level_sizes",
]


# ---------------------------------------------------------------------------------------------
# validation helpers (messages name the parameter, the value, and what is expected)
# ---------------------------------------------------------------------------------------------
def _int(name: str, value, lo: int, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if value < lo or (hi is not None and value > hi):
        rng = f"[{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise ValueError(f"{name}: expected an integer {rng}, got {value}")
    return int(value)


def _real(name: str, value, lo: float, hi: float | None = None, *, lo_open: bool = False):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__} {value!r}")
    v = float(value)
    if not math.isfinite(v) or (v <= lo if lo_open else v < lo) or (hi is not None and v > hi):
        lo_s = f"> {lo}" if lo_open else f">= {lo}"
        hi_s = f" and <= {hi}" if hi is not None else ""
        raise ValueError(f"{name}: expected a finite number {lo_s}{hi_s}, got {value!r}")
    return v


def level_sizes(size: int) -> list[int]:
    """GL mip sizes of a square ``size`` texture: ``size, size // 2, ..., 1``."""
    out = [size]
    while out[-1] > 1:
        out.append(out[-1] // 2)
    return out


# ---------------------------------------------------------------------------------------------
# antialiased lines
# ---------------------------------------------------------------------------------------------
def _box_overlap(d: np.ndarray, w: float, fw: float) -> np.ndarray:
    """Fraction of a box of width ``fw`` centred at distance ``d`` from a line's axis that the line
    (a band of width ``w``) covers: the exact box-filtered coverage of a straight band."""
    lo = np.maximum(d - fw / 2, -w / 2)
    hi = np.minimum(d + fw / 2, w / 2)
    return np.clip(hi - lo, 0.0, None) / fw


def line_coverage(
    size: int, a: int, b: int, width: float, *, phase: float = 0.0, rows: int | None = None
) -> np.ndarray:
    """Antialiased parallel lines that tile a ``(rows, size)`` texture.

    The lines are the iso-lines ``a u + b v = k + phase`` (k integer), so the pattern repeats
    over the unit uv square for integer ``(a, b)``; their spacing is ``1 / |(a, b)|`` in uv.
    Each texel holds the coverage of a band ``width`` texels wide, box-filtered over the texel's
    footprint projected on the line normal (exact for axis-aligned lines; the mean coverage is
    ``width / period`` for any angle while the bands do not overlap).

    Parameters
    ----------
    size : int >= 1
        Texture columns (and rows unless ``rows`` is given).
    a, b : int
        Lines per unit of u and of v (not both 0): ``(0, n)`` gives n lines of constant v
        ("horizontal" in the texture), ``(n, 0)`` n lines of constant u, ``(n, n)`` diagonals.
    width : float > 0
        Band width in texels (of the column axis).
    phase : float
        Offset of the lines in periods.
    rows : int, optional
        Texture rows (default ``size``).

    Returns
    -------
    (rows, size) float32 coverage in [0, 1]
    """
    size = _int("size", size, 1)
    rows = size if rows is None else _int("rows", rows, 1)
    a, b = _int("a", a, -(2**20)), _int("b", b, -(2**20))
    if a == 0 and b == 0:
        raise ValueError("a, b: got (0, 0); give the number of lines per unit u and v, e.g. (0, 8)")
    width = _real("width", width, 0.0, lo_open=True)
    phase = _real("phase", phase, -1e9)
    return _band(_line_distance(size, rows, a, b, phase), width)


def _line_distance(size: int, rows: int, a: int, b: int, phase: float):
    """(distance to the nearest line in texels, period in texels, projected texel footprint)."""
    u = (np.arange(size) + 0.5) / size
    v = (np.arange(rows) + 0.5) / rows
    s = a * u[None, :] + b * v[:, None] - phase  # line coordinate, lines at integers
    gu, gv = abs(a) / size, abs(b) / rows  # d s per texel along columns and rows
    g = math.hypot(gu, gv)
    return np.abs(s - np.round(s)) / g, 1.0 / g, (gu + gv) / g


def _band(geometry, width: float) -> np.ndarray:
    d, period, fw = geometry
    cov = _box_overlap(d, width, fw) + _box_overlap(period - d, width, fw)
    return np.clip(cov, 0.0, 1.0).astype(np.float32)


def hatching_layer(size: int, angle_deg: float, lines: int, width: float, *, phase=0.0):
    """One hatching layer: ``lines`` parallel lines per tile at ``angle_deg`` in the texture.

    The wave vector is ``(a, b) = round(lines (-sin, cos))``: 0 deg gives ``lines`` lines of
    constant v (running along u), 90 deg lines of constant u, 45 and 135 deg diagonals. The
    lines pass through texel centres (shifted by half a texel), so a stroke one texel wide is
    solid ink on one texel instead of half ink on two.

    Returns
    -------
    (size, size) float32 coverage in [0, 1]
    """
    a, b = _wave_vector(angle_deg, lines)
    return line_coverage(size, a, b, width, phase=phase + _centred(a, b, size))


def _centred(a: int, b: int, size: int) -> float:
    """Phase that puts the lines through texel centres (a band 1 texel wide is then solid ink
    on one texel column instead of half ink on two)."""
    return 0.5 * (a + b) / size


def _wave_vector(angle_deg: float, lines: int) -> tuple[int, int]:
    """Integer line normal (a, b) in uv for lines running at ``angle_deg`` (along (cos, sin))."""
    lines = _int("lines", lines, 1)
    t = math.radians(_real("angle_deg", angle_deg, -360.0, 360.0))
    a, b = round(-math.sin(t) * lines), round(math.cos(t) * lines)
    return (a, b) if (a, b) != (0, 0) else (0, 1)


# ---------------------------------------------------------------------------------------------
# stroke sets
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StrokeSet:
    """Ordered stroke layers per mip level, ready to encode as a stroke map (sec. 4.2).

    Attributes
    ----------
    layers : tuple of (m, rows_k, cols_k) float32 arrays
        Ink coverage of the m layers at mip level k (level 0 first, GL sizes down to 1x1);
        layer 0 is the darkest, drawn first (already in the lightest regions).
    levels : (m,) float64
        Ink grey g_i of each layer (increasing in [0, 1)); layer i shows where the target
        intensity is at most ``1 - g_i`` (binary threshold).
    normals : tuple of (rows_k, cols_k, 3) float32 arrays or None
        DOT3 normal map per level, RGB-encoded ``(n + 1) / 2`` in the texture frame (x along +u,
        y along +v, z out of the surface), for individual stroke lighting (sec. 5.2).
    name : str
    """

    layers: tuple[np.ndarray, ...]
    levels: np.ndarray
    normals: tuple[np.ndarray, ...] | None = None
    name: str = "strokes"

    @property
    def m(self) -> int:
        """Number of layers."""
        return int(self.layers[0].shape[0])

    @property
    def size(self) -> tuple[int, int]:
        """(cols, rows) of level 0."""
        return (int(self.layers[0].shape[2]), int(self.layers[0].shape[1]))


def stroke_map_pyramid(strokes: StrokeSet) -> MipPyramid:
    """The stroke map of every level: ``encode_stroke_map(layers_k, levels)`` (sec. 4.2).

    Returns
    -------
    MipPyramid of (rows_k, cols_k) float32 screens in [0, 1]
    """
    if not isinstance(strokes, StrokeSet):
        raise TypeError(f"strokes: expected a StrokeSet, got {type(strokes).__name__}")
    levels = tuple(
        np.asarray(halftone.encode_stroke_map(lay, levels=strokes.levels), dtype=np.float32)
        for lay in strokes.layers
    )
    return MipPyramid(levels)


def normal_pyramid(strokes: StrokeSet) -> MipPyramid | None:
    """The encoded normal maps as a 3-channel pyramid (None when the set has none)."""
    if not isinstance(strokes, StrokeSet):
        raise TypeError(f"strokes: expected a StrokeSet, got {type(strokes).__name__}")
    if strokes.normals is None:
        return None
    return MipPyramid(tuple(np.asarray(n, dtype=np.float32) for n in strokes.normals))


#: Orientation order of the built-in hatching layers (degrees in the texture): one direction,
#: cross-hatching, the two diagonals, then both axis directions again between the first lines.
HATCH_ANGLES = (0.0, 90.0, 45.0, 135.0, 0.0, 90.0, 45.0, 135.0)
_HATCH_PHASES = (0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.5, 0.5)


def _binary_tone(screen: np.ndarray, intensity: float) -> float:
    return float(np.mean(screen + intensity > 1.0))  # sec. 3.1, white iff screen + I > 1


def _hatch_lines(size: int, m: int, i: int, lines: int, min_width: float) -> tuple[int, float]:
    """Lines per tile of layer i at a level of ``size`` texels (halved while the strokes would be
    thinner than ``min_width``), and the first guess of its width (texels) from the union
    coverage ``(i + 1/2) / m`` the layers 0..i should reach."""
    target_cov = 1.0 - (1.0 - (i + 0.5) / m) / (1.0 - (i - 0.5) / m if i else 1.0)
    n = lines
    while n > 1 and target_cov * size / n < min_width:
        n //= 2
    return n, max(target_cov * size / n, 1e-3)


def _calibrated_layers(size: int, m: int, lines: int, min_width: float) -> np.ndarray:
    """m hatching layers of one level whose binary-threshold tone halfway between consecutive
    layer onsets equals the intensity there: two Gauss-Seidel sweeps over the layers, each
    solving for one layer's width (Illinois false position) with the others fixed."""
    levels = halftone.stroke_levels(m)
    plan = [_hatch_lines(size, m, i, lines, min_width) for i in range(m)]
    widths = [w for _, w in plan]

    geometry = []
    for i, (n, _) in enumerate(plan):
        a, b = _wave_vector(HATCH_ANGLES[i % 8], n)
        phase = _HATCH_PHASES[i % 8] + _centred(a, b, size)
        geometry.append(_line_distance(size, size, a, b, phase))

    def draw(i: int, width: float) -> np.ndarray:
        return _band(geometry[i], width)

    alphas = [draw(i, widths[i]).astype(np.float64) for i in range(m)]
    for _ in range(2):
        for i in range(m):
            # screen = top + through * (below + alpha_i (g_i - below))  (sec. 4.2, "over")
            top, through = np.zeros((size, size)), np.ones((size, size))
            for j in range(i):
                top, through = top + through * alphas[j] * levels[j], through * (1 - alphas[j])
            below = np.ones((size, size))
            for j in range(m - 1, i, -1):
                below = (1 - alphas[j]) * below + alphas[j] * levels[j]
            i_mid = 1.0 - (i + 0.5) / m  # halfway through layer i's interval

            def excess(width: float, i=i, top=top, through=through, below=below, i_mid=i_mid):
                a = draw(i, width)
                screen = top + through * (below + a * (levels[i] - below))
                return _binary_tone(screen, i_mid) - i_mid  # decreases with the width

            period = size / plan[i][0]
            lo, hi = 0.05 * widths[i], min(4.0 * widths[i], period)
            f_lo, f_hi = excess(lo), excess(hi)
            w, side = widths[i], 0
            for _ in range(10):
                if f_lo <= 0 or f_hi >= 0:  # not bracketed: take the better end
                    w = lo if abs(f_lo) < abs(f_hi) else hi
                    break
                w = hi - f_hi * (hi - lo) / (f_hi - f_lo)
                f = excess(w)
                if abs(f) < 3e-3:
                    break
                if f > 0:
                    lo, f_lo = w, f
                    f_hi = f_hi / 2 if side == 1 else f_hi
                    side = 1
                else:
                    hi, f_hi = w, f
                    f_lo = f_lo / 2 if side == -1 else f_lo
                    side = -1
            widths[i] = w
            alphas[i] = draw(i, w).astype(np.float64)
    return np.stack(alphas).astype(np.float32)


def hatching_set(
    size: int = 256, *, layers: int = 6, lines: int = 16, min_width: float = 1.0
) -> StrokeSet:
    """Built-in hatching stroke set: ``layers`` hatching directions, drawn at every mip level.

    Layer i runs at ``HATCH_ANGLES[i % 8]`` (0, 90, 45, 135 degrees, then the same directions
    between the earlier lines). Its ink grey is ``i / layers`` (:func:`stroke_levels`) and its
    line width is calibrated per level so that the binary threshold reproduces the tone halfway
    between consecutive layer onsets: for an intensity I in layer i's interval
    ``(1 - (i+1)/m, 1 - i/m]`` the white fraction is ``1 - (i + 1/2)/m``, within ``1/(2m)`` of I
    (the staircase a stroke map gives). Lines are never thinner than ``min_width`` texels: at
    coarse levels every other line is dropped instead (the coarse lines are a subset of the
    fine ones), which keeps the tone.

    Parameters
    ----------
    size : int
        Level-0 size in texels (a power of two, 16..2048).
    layers : int
        Number of layers m (1..8).
    lines : int
        Lines per tile of each layer at level 0 (a power of two >= 2).
    min_width : float
        Narrowest stroke in texels (0.5..8).

    Returns
    -------
    StrokeSet
    """
    size = _pow2("size", size, 16, 2048)
    m = _int("layers", layers, 1, 8)
    lines = _pow2("lines", lines, 2, size // 2)
    min_width = _real("min_width", min_width, 0.5, 8.0)
    per_level: list[np.ndarray] = []
    for s in level_sizes(size):
        if s < 4:  # a 2x2 or 1x1 level cannot hold strokes: the mean of the level above
            per_level.append(_box_half(per_level[-1]))
        else:
            per_level.append(_calibrated_layers(s, m, min(lines, s // 2), min_width))
    return StrokeSet(tuple(per_level), halftone.stroke_levels(m), None, name="hatching")


def _pow2(name: str, value, lo: int, hi: int) -> int:
    v = _int(name, value, lo, hi)
    if v & (v - 1):
        raise ValueError(f"{name}: expected a power of two in [{lo}, {hi}], got {v}")
    return v


def _box_half(stack: np.ndarray) -> np.ndarray:
    """2x2 box downsampling of an (m, rows, cols[, C]) stack (GL sizes: at least 1)."""
    m, r, c = stack.shape[:3]
    r2, c2 = max(1, r // 2), max(1, c // 2)
    a = stack[:, : r2 * (r // r2), : c2 * (c // c2)]
    a = a.reshape(m, r2, r // r2, c2, c // c2, *stack.shape[3:])
    return a.mean(axis=(2, 4), dtype=np.float64).astype(np.float32)


# ---------------------------------------------------------------------------------------------
# bricks (Figure 7, Figure 8)
# ---------------------------------------------------------------------------------------------
BRICK_LEVELS = (0.3, 0.45, 0.6, 0.75)


def _brick_fields(s: int, rows: int, per_row: int, seed: int):
    """Per texel: distance (texels) to the brick cell's border, the outward unit direction of
    the nearest border in (u, v), and the brick index; running bond (odd rows shifted half a
    brick)."""
    u = (np.arange(s) + 0.5) / s
    v = (np.arange(s) + 0.5) / s
    uu, vv = np.meshgrid(u, v)  # (rows=v, cols=u)
    row = np.floor(vv * rows).astype(np.int64)
    shift = np.where(row % 2 == 1, 0.5 / per_row, 0.0)
    uc = (uu + shift) * per_row
    col = np.floor(uc).astype(np.int64) % per_row
    x = (uc - np.floor(uc)) * (s / per_row)  # texels from the brick's left border
    y = (vv * rows - row) * (s / rows)  # texels from the brick's v = low border
    bw, bh = s / per_row, s / rows
    dl, dr, dlo, dhi = x, bw - x, y, bh - y
    dx = np.minimum(dl, dr)
    dy = np.minimum(dlo, dhi)
    dist = np.minimum(dx, dy)
    horiz = dx < dy  # nearest border is a left/right one
    du = np.where(horiz, np.where(dl < dr, -1.0, 1.0), 0.0)
    dv = np.where(horiz, 0.0, np.where(dlo < dhi, -1.0, 1.0))
    brick = row * per_row + col
    rng = np.random.default_rng(seed)
    rand = rng.random(rows * per_row)
    return dist, du, dv, rand[brick]


def brick_set(
    size: int = 256,
    *,
    rows: int = 4,
    per_row: int = 2,
    mortar: float = 0.025,
    outline: float = 0.02,
    tilt_deg: float = 50.0,
    hatch_lines: int = 32,
    seed: int = 2002,
) -> StrokeSet:
    """Built-in brick stroke set (after Winkenbach and Salesin's bricks, Freudenberg Fig. 7/8).

    Layers (ink greys :data:`BRICK_LEVELS`): 0 the brick outlines, 1 horizontal hatching in a
    random third of the bricks, 2 horizontal hatching in the other bricks, 3 diagonal hatching
    over everything. The normal map tilts each outline stroke outwards from its brick by
    ``tilt_deg`` (a bevelled, raised brick), flat elsewhere: with individual stroke lighting
    (sec. 5.2) a light from the upper right thins the upper and right outlines away and keeps
    the lower and left ones. Running bond: odd rows are shifted by half a brick.

    Parameters
    ----------
    size : int
        Level-0 size in texels (power of two, 32..2048).
    rows, per_row : int
        Brick rows per tile (even, so the bond tiles) and bricks per row.
    mortar, outline : float
        Mortar gap and outline stroke width as fractions of the tile (0..0.2).
    tilt_deg : float
        Outward tilt of the outline normals (0..85 degrees).
    hatch_lines : int
        Hatching lines per tile at level 0 (power of two).
    seed : int
        Which bricks get the first hatching layer.

    Returns
    -------
    StrokeSet with normals.
    """
    size = _pow2("size", size, 32, 2048)
    rows = _int("rows", rows, 2, 64)
    if rows % 2:
        raise ValueError(
            f"rows: expected an even number of brick rows (the bond tiles), got {rows}"
        )
    per_row = _int("per_row", per_row, 1, 64)
    mortar = _real("mortar", mortar, 0.0, 0.2)
    outline = _real("outline", outline, 0.0, 0.2, lo_open=True)
    tilt = math.radians(_real("tilt_deg", tilt_deg, 0.0, 85.0))
    hatch_lines = _pow2("hatch_lines", hatch_lines, 2, size // 2)
    seed = _int("seed", seed, 0)
    layers_k, normals_k = [], []
    for s in level_sizes(size):
        if s < 4:
            layers_k.append(_box_half(layers_k[-1]))
            normals_k.append(_box_half(normals_k[-1][None])[0])
            continue
        dist, du, dv, rand = _brick_fields(s, rows, per_row, seed)
        half_mortar = max(mortar * s / 2, 0.0)
        w = max(outline * s, 1.0)
        # outline band: distance to the cell border in [half_mortar, half_mortar + w]
        band = _box_overlap(dist - (half_mortar + w / 2), w, 1.0)
        # the bevel (tilted normals) spans the outline band and its antialiased fringe, so a lit
        # stroke vanishes whole; no other layer draws on it (it would show where the bevel is dark)
        bevel = (dist > half_mortar - 0.5) & (dist < half_mortar + w + 0.5)
        inside = np.clip(dist - half_mortar - w + 0.5, 0.0, 1.0) * ~bevel  # the brick's face
        n_h = hatch_lines
        while n_h > 1 and s / n_h < 3.0:
            n_h //= 2
        horiz = hatching_layer(s, 0.0, n_h, max(0.3 * s / n_h, 1.0))
        diag = hatching_layer(s, 45.0, n_h, max(0.35 * s / n_h, 1.0)) * ~bevel
        lay = np.stack(
            [
                band,
                horiz * inside * (rand < 1 / 3),
                horiz * inside * (rand >= 1 / 3),
                diag,
            ]
        ).astype(np.float32)
        layers_k.append(np.clip(lay, 0.0, 1.0))
        st, ct = math.sin(tilt), math.cos(tilt)
        n = np.stack(
            [
                np.where(bevel, st * du, 0.0),
                np.where(bevel, st * dv, 0.0),
                np.where(bevel, ct, 1.0),
            ],
            axis=-1,
        )
        normals_k.append(((n + 1.0) / 2.0).astype(np.float32))
    return StrokeSet(
        tuple(layers_k), np.asarray(BRICK_LEVELS, dtype=np.float64), tuple(normals_k), "bricks"
    )


# ---------------------------------------------------------------------------------------------
# layers drawn by hand (PNG files)
# ---------------------------------------------------------------------------------------------
def _ink(image: np.ndarray, name: str) -> np.ndarray:
    """Ink coverage of a layer image: alpha of an RGBA/LA image (black ink on transparent), else
    1 - luminance (black ink on white)."""
    tex = as_texture(image, name=name)
    if tex.ndim == 2:
        return 1.0 - tex
    c = tex.shape[2]
    if c in (2, 4):
        return tex[..., -1].astype(np.float32)
    if c == 3:
        return (1.0 - (0.2126 * tex[..., 0] + 0.7152 * tex[..., 1] + 0.0722 * tex[..., 2])).astype(
            np.float32
        )
    raise ValueError(f"{name}: expected 1 to 4 channels, got {c}")


def stroke_set_from_layers(
    layers: Sequence[np.ndarray],
    *,
    levels: Sequence[float] | None = None,
    normal_map: np.ndarray | None = None,
    name: str = "layers",
) -> StrokeSet:
    """A :class:`StrokeSet` from level-0 layer images (darkest first); coarser levels are the
    box-filtered coverages (:func:`build_pyramid`), encoded per level.

    Parameters
    ----------
    layers : sequence of (rows, cols[, C]) images
        Ink of each layer: the alpha channel if the image has one, else 1 - luminance.
    levels : (m,) increasing values in [0, 1), optional
        Ink greys (default ``i / m``).
    normal_map : (rows, cols, 3) image, optional
        RGB-encoded DOT3 normals in the texture frame.
    """
    if isinstance(layers, np.ndarray) or not isinstance(layers, Sequence) or not layers:
        raise ValueError("layers: expected a non-empty list of layer images (darkest first)")
    inks = [_ink(np.asarray(img), f"layers[{i}]") for i, img in enumerate(layers)]
    shape = inks[0].shape
    for i, ink in enumerate(inks):
        if ink.shape != shape:
            raise ValueError(
                f"layers[{i}]: expected the shape of layers[0] {shape}, got {ink.shape}; "
                "all layers of a stroke map must have one size"
            )
    g = halftone.stroke_levels(len(inks)) if levels is None else np.asarray(levels, float)
    halftone.layer_onsets(g)  # validates the levels (strictly increasing in [0, 1))
    if g.shape != (len(inks),):
        raise ValueError(f"levels: expected {len(inks)} grey levels (one per layer), got {g.shape}")
    pyrs = [build_pyramid(ink) for ink in inks]
    per_level = tuple(
        np.stack([p.levels[k] for p in pyrs]).astype(np.float32) for k in range(pyrs[0].n_levels)
    )
    normals = None
    if normal_map is not None:
        nm = as_texture(np.asarray(normal_map), name="normal_map")
        if nm.ndim != 3 or nm.shape[2] < 3 or nm.shape[:2] != shape:
            raise ValueError(
                f"normal_map: expected an RGB image of the layers' size {shape}, got {nm.shape}"
            )
        normals = build_pyramid(nm[..., :3]).levels
    return StrokeSet(per_level, g.astype(np.float64), normals, name)


def load_stroke_layers(
    paths: Sequence[str | Path],
    *,
    levels: Sequence[float] | None = None,
    normal_map: str | Path | None = None,
) -> StrokeSet:
    """Read stroke layers from image files (darkest layer first), see
    :func:`stroke_set_from_layers`."""
    import imageio.v3 as iio

    if isinstance(paths, (str, Path)):
        raise TypeError(
            f"paths: expected a list of layer files (darkest first), got the single path {paths!r}"
        )
    images = []
    for i, p in enumerate(paths):
        path = Path(p)
        if not path.is_file():
            raise ValueError(f"paths[{i}]: {str(p)!r} is not an existing image file")
        images.append(iio.imread(path))
    nm = None
    if normal_map is not None:
        path = Path(normal_map)
        if not path.is_file():
            raise ValueError(f"normal_map: {str(normal_map)!r} is not an existing image file")
        nm = iio.imread(path)
    return stroke_set_from_layers(images, levels=levels, normal_map=nm, name="layers")


# ---------------------------------------------------------------------------------------------
# engraving (sec. 4.1)
# ---------------------------------------------------------------------------------------------
def engraving_pyramid(size: int = 256, *, profile: str = "triangle") -> MipPyramid:
    """The 1D engraving screen (sec. 4.1) as a ``(1, size)`` mip-mapped texture along u.

    Every level ``k`` is the profile sampled at its own texel centres,
    :func:`refnpr.formulas.halftone.engraving_ramp` ``(size_k)``: the profile drawn at each
    level, as the stroke layers are. For the ramp this equals the box-filtered pyramid; for the
    triangle it keeps the full trough and peak that a box filter would flatten where the kink
    falls inside a texel. Each level is as uniform as its texel count allows, so thresholding
    keeps the tone at every level (up to the bilinear interpolation near the kinks) and the
    lines stay centred where they were. The 1-texel level is 0.5.

    Returns
    -------
    MipPyramid of (1, size_k) float32
    """
    size = _pow2("size", size, 2, 1 << 16)
    levels = [
        halftone.engraving_ramp(s, profile=profile).astype(np.float32)[None, :]
        for s in level_sizes(size)[:-1]
    ]
    return MipPyramid(tuple(levels) + (np.full((1, 1), 0.5, dtype=np.float32),))
