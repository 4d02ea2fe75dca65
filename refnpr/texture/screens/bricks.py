"""The built-in ``bricks`` stroke set: brick outlines with a bevel normal map and hatching inside
the bricks (Figure 7, Figure 8)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from refnpr.formulas import halftone

from .._checks import _int, _pow2, _real
from .lines import _box_overlap, hatching_layer
from .stroke_set import StrokeSet, _box_half, level_sizes

BRICK_LEVELS = (0.3, 0.45, 0.6, 0.75)


def _brick_fields(s: int, rows: int, per_row: int, seed: int):
    """Per texel of a running bond (odd rows shifted half a brick): distance (texels) to the
    brick cell's border, the outward unit direction (u, v) of the nearest border, the brick's
    random number, and (distance, direction) to its own left or lower border."""
    t = (np.arange(s) + 0.5) / s
    uu, vv = np.meshgrid(t, t)  # (rows=v, cols=u)
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
    low = np.minimum(dl, dlo)
    low_u = dl < dlo
    return dist, du, dv, rand[brick], (low, np.where(low_u, -1.0, 0.0), np.where(low_u, 0.0, -1.0))


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
    levels: Sequence[float] = BRICK_LEVELS,
) -> StrokeSet:
    """Built-in brick stroke set (after Winkenbach and Salesin's bricks, Freudenberg Fig. 7/8).

    Layers (ink greys ``levels``): 0 the brick outlines, 1 horizontal hatching in a random third
    of the bricks, 2 horizontal hatching in the other bricks, 3 diagonal hatching over
    everything. With the default grey 0.3 the outlines show where the target intensity is at
    most 0.7, so indication maps (sec. 5.1) and stroke lighting (sec. 5.2) can fade them;
    ``levels = [0.0, ...]`` draws every outline at every intensity (the paper's first layer).

    Every level draws its outlines on whole texels (mortar gap and outline width rounded, the
    outline at least one texel), so the binary threshold keeps them whole instead of breaking
    partly covered texels into dots. Where the mortar gap is under a texel, each brick draws only
    its lower and left outline (one solid line per joint, not two that fill small bricks). The
    normal map tilts each outline stroke outwards from its brick by ``tilt_deg`` (a bevelled,
    raised brick): lit from the upper right, the upper and right outlines thin away. Running
    bond: odd rows are shifted by half a brick.

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
    levels : 4 increasing values in [0, 1)
        Ink grey of each layer (outlines first), default :data:`BRICK_LEVELS`.

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
    try:
        g = np.asarray(levels, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"levels: expected 4 ink greys (outlines first), got {levels!r}") from None
    if g.shape != (4,):
        raise ValueError(
            f"levels: expected 4 ink greys (outlines, two hatching layers, diagonals), "
            f"got {levels!r}"
        )
    halftone.layer_onsets(g)  # strictly increasing in [0, 1)
    layers_k, normals_k = [], []
    for s in level_sizes(size):
        if s < 4:
            layers_k.append(_box_half(layers_k[-1]))
            normals_k.append(_box_half(normals_k[-1][None])[0])
            continue
        dist, du, dv, rand, (low, low_du, low_dv) = _brick_fields(s, rows, per_row, seed)
        if mortar * s >= 1.0:  # the gap holds a texel: both bricks' outlines, on whole texels
            half_mortar = math.floor(mortar * s / 2 + 0.5)
            w = max(math.floor(outline * s + 0.5), 1)
        else:  # one solid one-texel line per joint: each brick's lower and left outline
            half_mortar, w = 0, 1
            dist, du, dv = low, low_du, low_dv
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
        lay = [band, horiz * inside * (rand < 1 / 3), horiz * inside * (rand >= 1 / 3), diag]
        layers_k.append(np.clip(np.stack(lay).astype(np.float32), 0.0, 1.0))
        st, ct = math.sin(tilt), math.cos(tilt)
        n = [np.where(bevel, st * du, 0.0), np.where(bevel, st * dv, 0.0), np.where(bevel, ct, 1.0)]
        normals_k.append(((np.stack(n, axis=-1) + 1.0) / 2.0).astype(np.float32))
    return StrokeSet(tuple(layers_k), g, tuple(normals_k), "bricks")
