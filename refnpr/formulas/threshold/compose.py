"""Composition of threshold textures (Veryovka sec. 3.2, Fig. 4: cross-hatching).

The paper composes line textures "to approximate various styles of line drawings" without a
formula. refnpr composes them as the *union of their dark lines*: with eq. 3 a sample is black
where ``x < t``, so black where any layer is black is ``t = max_i h_i(F_i)``, with h_i a
non-decreasing re-mapping of layer i. The re-mappings are chosen so that

- the composite is uniform when the layers are independent uniform textures (tone preserving:
  the white fraction at intensity x is ``prod_i w_i(x) = x``, w_i = layer i's white fraction);
- layer i appears below the intensity ``onsets[i]`` (staged cross-hatching);
- the dark lines of every layer present stay as thin as possible: a new layer takes all the
  darkening until its lines are as wide as those of the layers already drawn, then all darken
  together (scaling one common level per layer instead keeps darkening the first layer, which
  goes mostly black while the second only chops its white gaps into dashes).

In darkness ``lambda = -ln x`` the allocation is water-filling: ``lambda = sum_i lambda_i``
(tone), ``lambda_i = 0`` while ``lambda < Lambda_i = -ln onsets[i]``, and each increment goes to
the active layers of least darkness. Every ``lambda_i(lambda)`` is piecewise linear. The
kernel's device functions take the schedule of :func:`layer_schedule` (``lam_bp``, ``lev_bp``,
computed once per frame).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import ONE_BELOW, clip, interp

from .._face import Whole, elementwise, face
from .._shading_checks import check_range, real, reals
from .._validate import describe
from .lines import _below_one

__all__ = ["layer_schedule", "layer_whites", "combine_thresholds", "check_onsets"]

_EPS = 1e-12


def check_onsets(onsets, count: int) -> np.ndarray:
    """Validated onsets as ``(count,)`` float64 (all 1 when None)."""
    if onsets is None:
        return np.ones(count)
    o = real("onsets", onsets, np.dtype(np.float64))
    if o.shape != (count,):
        raise ValueError(f"onsets: expected {count} values (one per layer), got shape {o.shape}")
    if np.any(o <= 0) or np.any(o > 1) or o.max() != 1:
        raise ValueError(
            f"onsets: expected values in (0, 1] with maximum 1, got {o.tolist()}; "
            "the first layer must appear at intensity 1"
        )
    return o


def layer_schedule(onsets) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints of the water-filling allocation of darkness between hatching layers.

    Parameters
    ----------
    onsets : (L,) sequence of floats in (0, 1], largest 1
        Intensity below which each layer appears.

    Returns
    -------
    lam : (B,) float64, strictly increasing from 0
        Total darkness ``-ln x`` at the breakpoints.
    levels : (B, L) float64
        Each layer's darkness ``-ln w_i`` there; beyond the last breakpoint every layer gains
        ``1 / L`` per unit of total darkness. ``levels.sum(axis=1) == lam``.
    """
    o = real("onsets", onsets, np.dtype(np.float64))
    if o.ndim != 1 or o.size == 0:
        raise ValueError(
            f"onsets: expected a non-empty sequence of intensities in (0, 1] (one per layer), "
            f"got {describe(onsets)}; pass e.g. (1.0,) or (1.0, 0.5)"
        )
    o = check_onsets(o, o.size)
    act = -np.log(o)  # Lambda_i: the total darkness at which layer i appears
    n = len(o)
    lam = 0.0
    lev = np.zeros(n)
    lams, levs = [0.0], [lev.copy()]
    while True:
        active = act <= lam + _EPS
        if active.all() and np.ptp(lev) <= _EPS:
            break
        low = lev[active].min()
        rising = active & (lev <= low + _EPS)
        above = lev[active & ~rising]
        catch = (above.min() - low) * rising.sum() if above.size else np.inf
        pending = act[~active]
        start = pending.min() - lam if pending.size else np.inf
        step = min(catch, start)
        lev = lev + np.where(rising, step / rising.sum(), 0.0)
        lam += step
        if step > _EPS:
            lams.append(lam)
            levs.append(lev.copy())
        else:
            levs[-1] = lev.copy()
    return np.asarray(lams), np.asarray(levs)


@njit
def _layer_white(x, lam_bp, lev_bp, i):
    c = clip(x, 0.0, 1.0)
    lam = -math.log(c) if c > 0.0 else math.inf  # total darkness -ln x
    li = interp(lam, lam_bp, lev_bp[:, i])  # layer i's darkness: the water-filling schedule
    last = lam_bp.shape[0] - 1
    if lam > lam_bp[last]:  # beyond the last breakpoint every layer gains 1 / L
        li = lev_bp[last, i] + (lam - lam_bp[last]) / lev_bp.shape[1]
    return math.exp(-li)


@face(_layer_white)
def layer_whites(x, onsets) -> np.ndarray:
    """White fraction w_i(x) of each hatching layer at intensity x (tone-preserving allocation).

    ``prod_i w_i(x) = x``; ``w_i = 1`` for ``x >= onsets[i]``; a newly appearing layer darkens
    alone until its lines are as wide as the others' (see the module docstring). With the
    sawtooth layers of :func:`line_threshold` the black line fraction of layer i is 1 - w_i.
    ``layer_whites.scalar(x, lam_bp, lev_bp, i)`` is the device function: layer i's w_i(x)
    under the schedule ``lam_bp, lev_bp = layer_schedule(onsets)``.

    Parameters
    ----------
    x : (...) array in [0, 1]
        Intensity.
    onsets : (L,) sequence of floats in (0, 1], largest 1

    Returns
    -------
    (L, ...) ndarray in [0, 1]; float64, or float32 if ``x`` is float32.
    """
    dt, x = reals(x=x)
    lam_bp, lev_bp = (Whole(a) for a in layer_schedule(onsets))
    n = lev_bp.value.shape[1]
    out = np.empty((n, *x.shape), dtype=dt)
    for i in range(n):
        out[i] = elementwise(layer_whites.scalar, dt, x, lam_bp, lev_bp, i)
    return out


@njit
def _darkness(f, lam_bp, lev_bp, i):
    """lambda*_i(F): the largest total darkness at which a sample with layer value F is white.

    White iff ``F <= w_i(x)`` iff ``q = -ln F >= lambda_i(lambda)`` (lambda_i non-decreasing);
    the layer's threshold is ``h_i(F) = exp(-lambda*)``.
    """
    c = clip(f, 0.0, 1.0)
    q = -math.log(c) if c > 0.0 else math.inf
    nb = lam_bp.shape[0]
    k = 0  # first breakpoint whose level exceeds q (searchsorted, side="right")
    while k < nb and lev_bp[k, i] <= q:
        k += 1
    last = nb - 1
    if k > last:  # beyond the last breakpoint (slope 1 / L)
        return lam_bp[last] + (q - lev_bp[last, i]) * lev_bp.shape[1]
    if last >= 1:
        hi = k if k >= 1 else 1
        if hi > last:
            hi = last
    else:
        hi = 0
    lo = hi - 1 if hi >= 1 else 0
    dlev = lev_bp[hi, i] - lev_bp[lo, i]
    safe = dlev if dlev > 0 else 1.0
    return lam_bp[lo] + (q - lev_bp[lo, i]) * (lam_bp[hi] - lam_bp[lo]) / safe


@njit
def _combine_thresholds(fs, lam_bp, lev_bp):
    lam_star = math.inf
    for i in range(len(fs)):
        li = _darkness(fs[i], lam_bp, lev_bp, i)
        lam_star = li if li < lam_star else lam_star  # white in every layer
    t = math.exp(-lam_star)  # union of the dark lines: t = max_i h_i(F_i)
    if t < 0.0:
        t = 0.0
    return t if t < ONE_BELOW else ONE_BELOW


@face(_combine_thresholds)
def combine_thresholds(layers: Sequence, *, onsets=None) -> np.ndarray:
    """Compose threshold textures into one (cross-hatching): the union of their dark lines.

    ``t = max_i h_i(F_i)`` (eq. 3: black where ``x < t``, so black where any layer is black),
    with h_i the inverse of layer i's white fraction :func:`layer_whites`: uniform (tone
    preserving) when the layers are independent uniform textures (lines at different angles
    over an area); layer i takes part only below the intensity ``onsets[i]``, and a new layer's
    lines grow until they are as wide as those already drawn before all darken together.
    ``combine_thresholds.scalar(fs, lam_bp, lev_bp)`` is the device function: ``fs`` the L
    layer values (an array or a tuple), the schedule ``layer_schedule(onsets)``.

    Parameters
    ----------
    layers : sequence of (...) arrays in [0, 1]
        Threshold textures, e.g. :func:`line_threshold` at several angles; they broadcast.
    onsets : sequence of floats in (0, 1], keyword-only
        Intensity below which each layer appears; the largest must be 1 (a uniform composite
        has some black at every intensity below 1). Default: all 1 (every layer at once, each
        with white fraction ``x ** (1 / L)``).

    Returns
    -------
    (...) ndarray in [0, 1); float64, or float32 if the layers are float32.
    """
    if isinstance(layers, np.ndarray) or not isinstance(layers, Sequence) or len(layers) == 0:
        raise TypeError(
            f"layers: expected a non-empty list of threshold arrays, got {describe(layers)}"
        )
    dt, *fs = reals(**{f"layers[{i}]": x for i, x in enumerate(layers)})
    for i, f in enumerate(fs):
        check_range(f"layers[{i}]", f, 0.0, 1.0, "threshold textures take values in [0, 1]")
    lam_bp, lev_bp = layer_schedule(check_onsets(onsets, len(fs)))
    t = elementwise(combine_thresholds.scalar, dt, tuple(fs), Whole(lam_bp), Whole(lev_bp))
    return _below_one(t)
