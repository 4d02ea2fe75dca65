"""The built-in ``hatching`` stroke set: parallel hatching at several angles, calibrated per level
so that the binary threshold reproduces tone (sec. 4.2)."""

from __future__ import annotations

import math

import numpy as np

from refnpr.formulas import halftone

from .._checks import _int, _pow2, _real
from .lines import _band, _centred, _line_distance, _wave_vector
from .stroke_set import StrokeSet, _box_half, level_sizes

#: Orientation order of the built-in hatching layers (degrees in the texture): one direction,
#: cross-hatching, the two diagonals, then both axis directions again between the first lines.
HATCH_ANGLES = (0.0, 90.0, 45.0, 135.0, 0.0, 90.0, 45.0, 135.0)
_HATCH_PHASES = (0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.5, 0.5)


def _layer_coverage(m: int, i: int) -> float:
    """Coverage layer i must add to what layers 0..i-1 left white so that the union covers
    ``(i + 1/2) / m``: ``1 - (1 - (i + 1/2)/m) / (1 - (i - 1/2)/m)`` (``1/(2m)`` for layer 0)."""
    return 1.0 - (1.0 - (i + 0.5) / m) / (1.0 - (i - 0.5) / m if i else 1.0)


def _hatch_lines(size: int, m: int, i: int, width: float) -> tuple[int, float]:
    """Lines per tile of layer i at a level of ``size`` texels (a power of two, 1 .. size / 2)
    and the first guess of its stroke width: lines about ``width`` texels wide at the coverage
    :func:`_layer_coverage`, so strokes keep their texel width at every level and layer (their
    screen width at every mip level) and tone comes from their density."""
    cov = _layer_coverage(m, i)
    ideal = cov * size / width  # lines of the exact width
    n = 1 << max(0, round(math.log2(max(ideal, 1.0))))
    n = min(n, max(1, size // 2))
    return n, max(cov * size / n, 1e-3)


def _calibrated_layers(size: int, m: int, width: float) -> np.ndarray:
    """m hatching layers of one level whose binary-threshold tone halfway between consecutive
    layer onsets equals the intensity there: two Gauss-Seidel sweeps over the layers, each
    solving for one layer's width (Illinois false position) with the others fixed."""
    levels = halftone.stroke_levels(m)
    plan = [_hatch_lines(size, m, i, width) for i in range(m)]
    widths = [w for _, w in plan]

    geometry = []
    for i, (n, _) in enumerate(plan):
        a, b = _wave_vector(HATCH_ANGLES[i % 8], n)
        phase = _HATCH_PHASES[i % 8] + _centred(a, b, size)
        geometry.append(_line_distance(size, size, a, b, phase))

    alphas = [_band(geometry[i], widths[i]).astype(np.float64) for i in range(m)]
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
                a = _band(geometry[i], width)
                screen = top + through * (below + a * (levels[i] - below))
                # binary-threshold tone (sec. 3.1, white iff screen + I > 1) minus the target;
                # it decreases with the width
                return float(np.mean(screen + i_mid > 1.0)) - i_mid

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
            alphas[i] = _band(geometry[i], w).astype(np.float64)
    return np.stack(alphas).astype(np.float32)


def hatching_set(
    size: int = 256, *, layers: int = 6, lines: int = 16, min_width: float = 1.0
) -> StrokeSet:
    """Built-in hatching stroke set: ``layers`` hatching directions, drawn at every mip level
    as a tonal art map (Praun et al. 2001, the mip-mapping Freudenberg sec. 4.2 refers to).

    Layer i runs at ``HATCH_ANGLES[i % 8]`` (0, 90, 45, 135 degrees, then the same directions
    between the earlier lines), ink grey ``i / layers`` (:func:`stroke_levels`). Every stroke of
    every layer and level is about ``w = max(size / (2 m lines), min_width)`` texels wide (layer
    0's coverage ``1/(2m)`` with ``lines`` lines at level 0): a layer that covers more has more
    lines (a power of two per tile, widths within a factor sqrt(2) of w), a coarser level half
    as many lines of the same texel width, so strokes keep their screen width at any distance
    and tone comes from their density (sec. 4). Each width is then calibrated per level so that
    the binary threshold reproduces the tone halfway between consecutive layer onsets: in layer
    i's interval ``(1 - (i+1)/m, 1 - i/m]`` the white fraction is ``1 - (i + 1/2)/m``, within
    ``1/(2m)`` of the intensity. A level too small for strokes of width w gets narrower ones.

    Parameters
    ----------
    size : int
        Level-0 size in texels (a power of two, 16..2048).
    layers : int
        Number of layers m (1..8).
    lines : int
        Lines per tile of layer 0 (the sparsest) at level 0 (a power of two >= 2); it sets the
        stroke width w above.
    min_width : float
        Narrowest target stroke width w in texels (0.5..8).

    Returns
    -------
    StrokeSet
    """
    size = _pow2("size", size, 16, 2048)
    m = _int("layers", layers, 1, 8)
    lines = _pow2("lines", lines, 2, size // 2)
    min_width = _real("min_width", min_width, 0.5, 8.0)
    width = max(_layer_coverage(m, 0) * size / lines, min_width)
    per_level: list[np.ndarray] = []
    for s in level_sizes(size):
        if s < 4:  # a 2x2 or 1x1 level cannot hold strokes: the mean of the level above
            per_level.append(_box_half(per_level[-1]))
        else:
            per_level.append(_calibrated_layers(s, m, width))
    return StrokeSet(tuple(per_level), halftone.stroke_levels(m), None, name="hatching")
