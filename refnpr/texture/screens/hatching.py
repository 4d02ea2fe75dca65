"""The built-in ``hatching`` stroke set: parallel hatching at several angles, calibrated per level
so that the binary threshold reproduces tone (sec. 4.2)."""

from __future__ import annotations

import numpy as np

from refnpr.formulas import halftone

from ._checks import _int, _pow2, _real
from .lines import _band, _centred, _line_distance, _wave_vector
from .stroke_set import StrokeSet, _box_half, level_sizes

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
