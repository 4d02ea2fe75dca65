"""What the ``kit check`` report shows of one case, computed from its arrays.

Pure numpy on the arrays :class:`refnpr.kit.check.Visual` carries (``(H, W, 4)`` float64 sRGB
values composited over black, alpha last, or a gray G-buffer preview, and the ``(H, W)`` bool
verdict): the worst pixels, the signed difference heatmaps and their scale, the magnified crop
around the worst pixel, thumbnails that keep single failing pixels visible, the tolerance margin
(through :func:`refnpr.kit.check.position_tolerant_mismatch`, the compare that decides) and
FLIP when the optional ``flip-evaluator`` package is installed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..image import srgb_to_linear
from .check import position_tolerant_mismatch

__all__ = [
    "CROP_SIDE",
    "CROP_ZOOM",
    "DIVERGING",
    "FRAME_RGB",
    "GAP_RGB",
    "SCALE_STEPS",
    "Flip",
    "Margin",
    "WorstPixel",
    "crop_window",
    "diff_scale",
    "diverging_rgb",
    "flip_error",
    "magnified_crop",
    "mask_rgb",
    "pool_factor",
    "pooled_diff",
    "pooled_mask",
    "signed_diff",
    "signed_diff_heatmap",
    "straight_linear",
    "straight_srgb",
    "tolerance_margin",
    "worst_pixels",
]

#: The diverging colour map of the difference heatmaps: (t, (r, g, b) uint8) control points,
#: piecewise linear in sRGB. Blue below zero (result lower than reference), red above,
#: near-black at zero; brightness grows with |t| on both sides.
DIVERGING = (
    (-1.0, (170, 225, 255)),
    (-0.5, (40, 110, 230)),
    (0.0, (24, 24, 24)),
    (0.5, (225, 60, 30)),
    (1.0, (255, 225, 160)),
)

#: The heatmap scales: the smallest k / 255 that holds the largest |difference|.
SCALE_STEPS = (1, 2, 4, 8, 16, 32, 64, 128, 255)

#: Side (pixels) of the window around the worst pixel and its magnification in the crop file.
CROP_SIDE = 24
CROP_ZOOM = 8

#: The frame drawn around the worst pixel in the crop, and the gap between its panels (RGB).
FRAME_RGB = (255, 230, 0)
GAP_RGB = (60, 60, 60)

_MASK_PASS = (0, 255, 0)
_MASK_FAIL = (255, 0, 0)
_MASK_EMPTY = (0, 0, 0)


def _pair(reference: np.ndarray, result: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.nan_to_num(np.asarray(reference, dtype=np.float64))
    b = np.nan_to_num(np.asarray(result, dtype=np.float64))
    if a.ndim != 3 or a.shape != b.shape or a.shape[2] < 1:
        raise ValueError(
            f"reference, result: expected two (H, W, C) arrays of one shape, got "
            f"{a.shape} and {b.shape}"
        )
    return a, b


def _bool_plane(x: np.ndarray | None, shape: tuple[int, int], what: str) -> np.ndarray | None:
    if x is None:
        return None
    x = np.asarray(x, dtype=bool)
    if x.shape != shape:
        raise ValueError(f"{what}: expected an (H, W) bool array of shape {shape}, got {x.shape}")
    return x


# -- worst pixels ------------------------------------------------------------------------------


@dataclass(frozen=True)
class WorstPixel:
    """One pixel of the worst-pixel list.

    Attributes
    ----------
    x, y : int
        Column and row (row 0 on top).
    fails : bool
        The deciding verdict fails the pixel.
    diff : float
        Largest per-channel ``|result - reference|`` of the compared values.
    reference, result : tuple of float
        The compared values at the pixel (sRGB composited over black, alpha last; or the
        normalised G-buffer preview).
    """

    x: int
    y: int
    fails: bool
    diff: float
    reference: tuple[float, ...]
    result: tuple[float, ...]


def worst_pixels(
    reference: np.ndarray,
    result: np.ndarray,
    *,
    bad: np.ndarray | None = None,
    count: int = 10,
) -> list[WorstPixel]:
    """The ``count`` worst pixels: failing ones first, each group by largest per-channel
    ``|result - reference|``, ties in reading order (row, then column).

    Pixels that neither fail nor differ are never listed, so two equal images give ``[]``.

    Parameters
    ----------
    reference, result : (H, W, C) float
        The compared values.
    bad : (H, W) bool, optional
        The deciding per-pixel verdict (True: fails).
    count : int
        At most this many pixels (>= 0).

    Returns
    -------
    list of WorstPixel
    """
    a, b = _pair(reference, result)
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
        raise ValueError(f"count: expected an integer >= 0, got {count!r}")
    h, w = a.shape[:2]
    bad = _bool_plane(bad, (h, w), "bad")
    d = np.abs(b - a).max(axis=-1)
    fails = np.zeros((h, w), dtype=bool) if bad is None else bad
    score = (d + 2.0 * fails).ravel()  # |d| <= 1 on [0, 1] values: failing pixels rank first
    score[(d.ravel() == 0) & ~fails.ravel()] = -1.0
    order = np.argsort(-score, kind="stable")[:count]
    out = []
    for i in order:
        if score[i] < 0:
            break
        y, x = divmod(int(i), w)
        out.append(
            WorstPixel(
                x=x,
                y=y,
                fails=bool(fails[y, x]),
                diff=float(d[y, x]),
                reference=tuple(float(v) for v in a[y, x]),
                result=tuple(float(v) for v in b[y, x]),
            )
        )
    return out


def straight_srgb(rgba: tuple[float, ...] | np.ndarray) -> np.ndarray:
    """(4,) float64: the straight-alpha sRGB values of a pixel composited over black (colour
    divided by alpha where alpha > 0; where alpha is 0 the colour is lost and reads 0)."""
    p = np.asarray(rgba, dtype=np.float64).reshape(4)
    out = p.copy()
    out[:3] = p[:3] / p[3] if p[3] > 0 else 0.0
    return out


def straight_linear(rgba: tuple[float, ...] | np.ndarray) -> np.ndarray:
    """(4,) float64: :func:`straight_srgb` decoded to linear (IEC 61966-2-1), alpha kept."""
    s = straight_srgb(rgba)
    return np.concatenate([srgb_to_linear(s[:3]), s[3:]])


# -- signed differences ------------------------------------------------------------------------


def diff_scale(max_abs: float) -> float:
    """The heatmap scale: the smallest k / 255, k in 1, 2, 4, ..., 128, 255, at least
    ``max_abs`` (1.0 beyond 128 / 255)."""
    if not math.isfinite(max_abs) or max_abs < 0:
        raise ValueError(f"max_abs: expected a finite number >= 0, got {max_abs!r}")
    for k in SCALE_STEPS:
        if k / 255 >= max_abs:
            return k / 255
    return 1.0


def diverging_rgb(t: np.ndarray) -> np.ndarray:
    """(..., 3) uint8: :data:`DIVERGING` at ``t`` (clipped to [-1, 1])."""
    t = np.clip(np.nan_to_num(np.asarray(t, dtype=np.float64)), -1.0, 1.0)
    xs = [p for p, _ in DIVERGING]
    cols = [np.interp(t, xs, [c[i] for _, c in DIVERGING]) for i in range(3)]
    return np.rint(np.stack(cols, axis=-1)).astype(np.uint8)


def signed_diff(reference: np.ndarray, result: np.ndarray) -> np.ndarray:
    """(H, W) float64: per pixel, ``result - reference`` of the channel with the largest
    ``|difference|`` (the first such channel on ties)."""
    a, b = _pair(reference, result)
    d = b - a
    pick = np.abs(d).argmax(axis=-1)
    return np.take_along_axis(d, pick[..., None], axis=-1)[..., 0]


def signed_diff_heatmap(
    reference: np.ndarray, result: np.ndarray, *, scale: float, per_channel: bool = False
) -> np.ndarray:
    """Diverging heatmap of ``result - reference`` on ``[-scale, scale]``.

    Parameters
    ----------
    reference, result : (H, W, C) float
        The compared values.
    scale : float
        Difference drawn at full colour (> 0); see :func:`diff_scale`.
    per_channel : bool
        False: one (H, W) panel of :func:`signed_diff`. True: one panel per channel, C = 4 as a
        2 x 2 grid (R, G / B, A), else side by side; panels 2 px apart (gap colour
        :data:`GAP_RGB`).

    Returns
    -------
    (H', W', 3) uint8
    """
    a, b = _pair(reference, result)
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale: expected a finite number > 0, got {scale!r}")
    if not per_channel:
        return diverging_rgb(signed_diff(a, b) / scale)
    panels = [diverging_rgb((b[..., c] - a[..., c]) / scale) for c in range(a.shape[2])]
    grid = [panels[:2], panels[2:]] if len(panels) == 4 else [panels]
    return _grid(grid, gap=2)


def _grid(rows: list[list[np.ndarray]], gap: int) -> np.ndarray:
    """Equal-sized (h, w, 3) uint8 panels in rows, ``gap`` px apart."""
    h, w = rows[0][0].shape[:2]
    n_cols = max(len(r) for r in rows)
    out = np.empty((len(rows) * (h + gap) - gap, n_cols * (w + gap) - gap, 3), dtype=np.uint8)
    out[...] = GAP_RGB
    for i, row in enumerate(rows):
        for j, p in enumerate(row):
            out[i * (h + gap) : i * (h + gap) + h, j * (w + gap) : j * (w + gap) + w] = p
    return out


# -- the magnified crop ------------------------------------------------------------------------


def crop_window(
    shape: tuple[int, ...], x: int, y: int, side: int = CROP_SIDE
) -> tuple[slice, slice]:
    """(rows, cols): the ``side`` x ``side`` window centred on pixel (x, y), moved inside an
    image of ``shape`` (H, W, ...) and shrunk to it when the image is smaller."""
    h, w = shape[:2]
    sh, sw = min(side, h), min(side, w)
    y0 = min(max(y - sh // 2, 0), h - sh)
    x0 = min(max(x - sw // 2, 0), w - sw)
    return slice(y0, y0 + sh), slice(x0, x0 + sw)


def _rgb8(a: np.ndarray) -> np.ndarray:
    return np.rint(np.clip(np.nan_to_num(a[..., :3]), 0.0, 1.0) * 255.0).astype(np.uint8)


def mask_rgb(bad: np.ndarray, empty: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 3) uint8 error mask: red where ``bad``, black where ``empty`` and not bad, green
    elsewhere."""
    bad = np.asarray(bad, dtype=bool)
    if bad.ndim != 2:
        raise ValueError(f"bad: expected an (H, W) bool array, got shape {bad.shape}")
    out = np.empty(bad.shape + (3,), dtype=np.uint8)
    out[...] = _MASK_PASS
    if empty is not None:
        out[_bool_plane(empty, bad.shape, "empty")] = _MASK_EMPTY
    out[bad] = _MASK_FAIL
    return out


def magnified_crop(
    reference: np.ndarray,
    result: np.ndarray,
    *,
    x: int,
    y: int,
    scale: float,
    bad: np.ndarray | None = None,
    empty: np.ndarray | None = None,
    side: int = CROP_SIDE,
    zoom: int = CROP_ZOOM,
) -> tuple[np.ndarray, tuple[slice, slice]]:
    """The window around pixel (x, y) magnified ``zoom`` times by pixel repetition (no
    smoothing): reference | result | signed difference | mask (when ``bad`` is given), panels
    ``zoom`` px apart, pixel (x, y) framed in :data:`FRAME_RGB`.

    Parameters
    ----------
    reference, result : (H, W, C) float
        The compared values (C >= 3: the first three are drawn as sRGB; C < 3: the first as gray).
    x, y : int
        The pixel to centre on (inside the image).
    scale : float
        The difference heatmap's scale (:func:`diff_scale`).
    bad, empty : (H, W) bool, optional
        The verdict and the background pixels, for the mask panel.
    side, zoom : int
        Window side (pixels) and magnification (>= 1 each).

    Returns
    -------
    image : (side' * zoom, n * side' * zoom + (n - 1) * zoom, 3) uint8
        n = 4 panels with ``bad``, else 3; side' = the window side clipped to the image.
    window : (slice, slice)
        The rows and columns of the image shown.
    """
    a, b = _pair(reference, result)
    h, w = a.shape[:2]
    if not (0 <= x < w and 0 <= y < h):
        raise ValueError(f"x, y: expected a pixel inside the {w}x{h} image, got ({x}, {y})")
    if zoom < 1 or side < 1:
        raise ValueError(f"side, zoom: expected integers >= 1, got {side}, {zoom}")
    rows, cols = crop_window(a.shape, x, y, side)

    def rgb(v: np.ndarray) -> np.ndarray:
        return _rgb8(v if v.shape[2] >= 3 else np.repeat(v[..., :1], 3, axis=-1))

    panels = [rgb(a[rows, cols]), rgb(b[rows, cols])]
    panels.append(diverging_rgb(signed_diff(a[rows, cols], b[rows, cols]) / scale))
    bad = _bool_plane(bad, (h, w), "bad")
    if bad is not None:
        e = _bool_plane(empty, (h, w), "empty")
        panels.append(mask_rgb(bad[rows, cols], None if e is None else e[rows, cols]))
    fy, fx = (y - rows.start) * zoom, (x - cols.start) * zoom
    big = []
    for p in panels:
        m = np.repeat(np.repeat(p, zoom, axis=0), zoom, axis=1)
        t = max(1, zoom // 8)
        m[fy : fy + zoom, fx : fx + t] = FRAME_RGB
        m[fy : fy + zoom, fx + zoom - t : fx + zoom] = FRAME_RGB
        m[fy : fy + t, fx : fx + zoom] = FRAME_RGB
        m[fy + zoom - t : fy + zoom, fx : fx + zoom] = FRAME_RGB
        big.append(m)
    return _grid([big], gap=zoom), (rows, cols)


# -- thumbnails that keep single pixels --------------------------------------------------------


def pool_factor(shape: tuple[int, ...], box: int) -> int:
    """The integer reduction that fits an (H, W, ...) image in ``box`` x ``box`` px (1: none)."""
    return max(1, math.ceil(max(shape[:2]) / box))


def _blocks(a: np.ndarray, f: int) -> np.ndarray:
    """(ceil(H / f), ceil(W / f), f * f, ...) view of ``a`` padded by edge repetition."""
    h, w = a.shape[:2]
    ph, pw = -h % f, -w % f
    pad = [(0, ph), (0, pw)] + [(0, 0)] * (a.ndim - 2)
    a = np.pad(a, pad, mode="edge")
    hb, wb = a.shape[0] // f, a.shape[1] // f
    a = a.reshape(hb, f, wb, f, *a.shape[2:]).swapaxes(1, 2)
    return a.reshape(hb, wb, f * f, *a.shape[4:])


def pooled_mask(bad: np.ndarray, empty: np.ndarray | None, f: int) -> np.ndarray:
    """(ceil(H / f), ceil(W / f), 3) uint8 mask thumbnail: a block is red if any of its pixels
    fails, else green if any is not background, else black."""
    bad = np.asarray(bad, dtype=bool)
    any_bad = _blocks(bad, f).any(axis=2)
    any_empty_all = (
        _blocks(np.asarray(empty, dtype=bool), f).all(axis=2) if empty is not None else None
    )
    return mask_rgb(any_bad, any_empty_all)


def pooled_diff(signed: np.ndarray, f: int) -> np.ndarray:
    """(ceil(H / f), ceil(W / f)) float64: per f x f block, the value of largest magnitude of
    ``signed`` (H, W) (so one differing pixel still shows)."""
    blk = _blocks(np.asarray(signed, dtype=np.float64), f)
    pick = np.abs(blk).argmax(axis=2)
    return np.take_along_axis(blk, pick[..., None], axis=2)[..., 0]


# -- the tolerance margin ----------------------------------------------------------------------


@dataclass(frozen=True)
class Margin:
    """How far an image case is from its tolerance, one criterion at a time (the others as the
    case states them).

    Attributes
    ----------
    threshold, deviation, max_frac_over, min_ssim : float, int, float, float
        The case's tolerance.
    frac : float
        Fraction of pixels failing the position-tolerant compare at the case's threshold: the
        smallest ``max_frac_over`` at which the render passes that criterion.
    pass_threshold : float
        The smallest k / 255 (k = 0 ... 255) at which the fraction failing is at most
        ``max_frac_over`` (deviation as the case states).
    ssim : float or None
        The render's SSIM: the largest ``min_ssim`` at which it passes that criterion; NaN
        where it cannot be computed (an image under 3 px that differs), which passes it.
    """

    threshold: float
    deviation: int
    max_frac_over: float
    min_ssim: float
    frac: float
    pass_threshold: float
    ssim: float | None

    @property
    def frac_ok(self) -> bool:
        return self.frac <= self.max_frac_over

    @property
    def ssim_ok(self) -> bool:
        return self.ssim is not None and (math.isnan(self.ssim) or self.ssim >= self.min_ssim)


def _tol_number(tol: Mapping[str, Any], key: str) -> float | None:
    v = tol.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return None
    return float(v)


def tolerance_margin(
    reference: np.ndarray,
    result: np.ndarray,
    tolerance: Mapping[str, Any],
    *,
    ssim: float | None,
) -> Margin | None:
    """The :class:`Margin` of an image case (None when ``tolerance`` lacks a valid
    ``threshold``, ``max_frac_over``, ``min_ssim`` or ``position_deviation``).

    Parameters
    ----------
    reference, result : (H, W, 4) float
        The compared values (sRGB composited over black, alpha last).
    tolerance : mapping
        The case's ``tolerance`` (``position_deviation`` defaults to 0, as the check reads it).
    ssim : float or None
        The render's SSIM (the check's ``metrics["ssim"]``).
    """
    a, b = _pair(reference, result)
    threshold = _tol_number(tolerance, "threshold")
    max_frac = _tol_number(tolerance, "max_frac_over")
    min_ssim = _tol_number(tolerance, "min_ssim")
    dev = tolerance.get("position_deviation", 0)
    if (
        threshold is None
        or max_frac is None
        or min_ssim is None
        or isinstance(dev, bool)
        or not isinstance(dev, int)
        or not 0 <= dev <= max(a.shape[:2])
        or threshold < 0
    ):
        return None

    seen: dict[float, float] = {}

    def frac_at(t: float) -> float:
        if t not in seen:
            bad = position_tolerant_mismatch(a, b, threshold=t, deviation=dev)
            seen[t] = float(bad.mean())
        return seen[t]

    # every pixel matches itself at the largest difference (in levels, rounded up): the search
    # needs only [0, that]; one level more where float rounding of k / 255 leaves a pixel out
    top = min(255, math.ceil(float(np.abs(b - a).max()) * 255 - 1e-9))
    while top < 255 and frac_at(top / 255) > max_frac:
        top += 1
    lo, hi = 0, top  # frac_at(hi / 255) passes (at 255 / 255 every [0, 1] value matches)
    if frac_at(0.0) <= max_frac:
        hi = 0
    while hi - lo > 1:  # invariant: lo fails, hi passes
        mid = (lo + hi) // 2
        if frac_at(mid / 255) <= max_frac:
            hi = mid
        else:
            lo = mid
    return Margin(
        threshold=threshold,
        deviation=dev,
        max_frac_over=max_frac,
        min_ssim=min_ssim,
        frac=frac_at(threshold),
        pass_threshold=hi / 255,
        ssim=None if ssim is None else float(ssim),  # NaN: not computable, not judged
    )


# -- FLIP --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Flip:
    """FLIP of one image case.

    Attributes
    ----------
    mean : float or None
        Mean FLIP error (None when not computed).
    error_map : (H, W, 3) uint8 or None
        The per-pixel error in FLIP's magma colour map.
    note : str
        Why it was not computed ("not installed", the error), else "".
    """

    mean: float | None
    error_map: np.ndarray | None
    note: str = ""


def flip_error(reference: np.ndarray, result: np.ndarray) -> Flip:
    """LDR FLIP (``flip-evaluator``, default 67 pixels per degree) of the sRGB colours
    composited over black (the first three channels of (H, W, C) arrays in [0, 1]).

    Without the package: ``Flip(None, None, "not installed")``; equal colours: ``Flip(0.0,
    None)`` without evaluating.
    """
    try:
        import flip_evaluator
    except ImportError:
        return Flip(None, None, "not installed")
    a, b = _pair(reference, result)
    if a.shape[2] < 3:
        return Flip(None, None, "needs colour images")
    ref = np.ascontiguousarray(np.clip(a[..., :3], 0, 1), dtype=np.float32)
    res = np.ascontiguousarray(np.clip(b[..., :3], 0, 1), dtype=np.float32)
    if np.array_equal(ref, res):  # FLIP is 0 everywhere: skip the evaluation (and the map)
        return Flip(0.0, None)
    try:
        emap, mean, _ = flip_evaluator.evaluate(ref, res, "LDR")
    except Exception as exc:  # noqa: BLE001 -- an optional extra: report, never abort
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        return Flip(None, None, f"failed: {first}")
    return Flip(float(mean), _rgb8(np.asarray(emap, dtype=np.float64)))
