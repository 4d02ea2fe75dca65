"""CLAHE on the torus: contrast-limited adaptive histogram equalization of a repeating texture.

Zuiderveld's CLAHE (Graphics Gems IV, 1994; what Veryovka 2002 sec. 3.1 applies to every mip
level): each contextual region of about ``window`` x ``window`` texels clips its histogram at
``clip_limit`` times its texel count, spreads the excess evenly over all bins and maps gray
levels by its cumulative histogram; a texel blends the maps of the four regions whose centres
surround it, bilinearly. Here the regions tile the torus (``round(size / window)`` per axis,
their borders partitioning one period; texels near a border blend regions across it), so the
result tiles whenever the input does, for any level size. scikit-image's ``equalize_adapthist``
pads by reflection and aligns its regions to the image corner, so its output is not periodic.
"""

from __future__ import annotations

import numpy as np

__all__ = ["periodic_clahe"]

#: Clip-and-redistribute passes: each pass spreads the excess evenly, which can lift bins just
#: under the limit over it; a few passes leave a negligible residue (Zuiderveld's single pass
#: plus residual redistribution has the same fixed point).
_CLIP_PASSES = 8


def _regions(n: int, window: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Cyclic contextual regions along one axis of ``n`` texels.

    Returns ``(region, r0, r1, w1)``, each (n,): the region holding each texel, the two regions
    whose centres enclose the texel's centre (cyclically) and the weight of ``r1``.
    """
    k = max(1, int(round(n / min(window, n))))
    edges = np.floor(np.arange(k + 1) * n / k).astype(np.int64)  # borders partition [0, n)
    region = np.repeat(np.arange(k), np.diff(edges))
    centres = 0.5 * (edges[:-1] + edges[1:])
    # the centres extended by one period on each side, with the region each one belongs to
    ext = np.concatenate([[centres[-1] - n], centres, [centres[0] + n]])
    ids = np.concatenate([[k - 1], np.arange(k), [0]])
    x = np.arange(n) + 0.5  # texel centres
    j = np.searchsorted(ext, x, side="right") - 1
    w1 = (x - ext[j]) / (ext[j + 1] - ext[j])
    return region, ids[j], ids[j + 1], w1


def _clip(hist: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """Clip each histogram (..., nbins) at ``limit`` (...,) and spread the excess evenly."""
    h = hist.astype(np.float64)
    lim = limit[..., None]
    for _ in range(_CLIP_PASSES):
        excess = np.maximum(h - lim, 0.0).sum(axis=-1, keepdims=True)
        if not np.any(excess > 0.0):
            break
        h = np.minimum(h, lim) + excess / h.shape[-1]
    return h


def periodic_clahe(level: np.ndarray, *, window: int, clip_limit: float, nbins: int) -> np.ndarray:
    """CLAHE of one gray level on the torus (see the module docstring).

    Parameters
    ----------
    level : (rows, cols) float array in [0, 1]
    window : int >= 1
        Contextual region size in texels (the paper's w); capped at the level size, so a level
        smaller than ``window`` is one region (plain histogram equalization).
    clip_limit : float in (0, 1]
        Histogram clip limit as a fraction of a region's texel count (scikit-image's units); 1
        leaves histograms unclipped (AHE).
    nbins : int >= 2
        Histogram bins over the level's [min, max] range.

    Returns
    -------
    (rows, cols) float32 in [0, 1]
        Min-max rescaled to [0, 1] (a constant level gives 0.5 everywhere).
    """
    a = np.asarray(level, dtype=np.float64)
    lo, hi = float(a.min()), float(a.max())
    if hi <= lo:
        return np.full(a.shape, 0.5, dtype=np.float32)
    b = np.minimum(((a - lo) / (hi - lo) * nbins).astype(np.int64), nbins - 1)
    reg_r, r0, r1, wr = _regions(a.shape[0], window)
    reg_c, c0, c1, wc = _regions(a.shape[1], window)
    kr, kc = int(reg_r.max()) + 1, int(reg_c.max()) + 1
    cell = (reg_r[:, None] * kc + reg_c[None, :]) * nbins + b
    hist = np.bincount(cell.ravel(), minlength=kr * kc * nbins).reshape(kr, kc, nbins)
    count = hist.sum(axis=-1).astype(np.float64)
    hist = _clip(hist, np.maximum(clip_limit * count, 1.0))
    maps = np.cumsum(hist, axis=-1) / count[..., None]  # each region's gray-level map
    wr, wc = wr[:, None], wc[None, :]
    out = (
        (1.0 - wr) * (1.0 - wc) * maps[r0[:, None], c0[None, :], b]
        + (1.0 - wr) * wc * maps[r0[:, None], c1[None, :], b]
        + wr * (1.0 - wc) * maps[r1[:, None], c0[None, :], b]
        + wr * wc * maps[r1[:, None], c1[None, :], b]
    )
    lo, hi = float(out.min()), float(out.max())
    if hi <= lo:
        return np.full(a.shape, 0.5, dtype=np.float32)
    return ((out - lo) / (hi - lo)).astype(np.float32)
