"""Antialiased parallel lines that tile the unit uv square: the strokes of the procedural sets."""

from __future__ import annotations

import math

import numpy as np

from .._checks import _int, _real


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
    """Phase that puts the lines through texel centres."""
    return 0.5 * (a + b) / size


def _wave_vector(angle_deg: float, lines: int) -> tuple[int, int]:
    """Integer line normal (a, b) in uv for lines running at ``angle_deg`` (along (cos, sin))."""
    lines = _int("lines", lines, 1)
    t = math.radians(_real("angle_deg", angle_deg, -360.0, 360.0))
    a, b = round(-math.sin(t) * lines), round(math.cos(t) * lines)
    return (a, b) if (a, b) != (0, 0) else (0, 1)
