"""Mip pyramids (GL-style level sizes) and CLAHE pyramids (Veryovka 2002 sec. 3.1).

Texture space convention (shared by every sampler in refnpr): a texture is an array
``(rows, cols)`` or ``(rows, cols, C)``; ``u`` runs along columns and ``v`` along rows, texel
``(row j, col i)`` covers ``u in [i/cols, (i+1)/cols)``, ``v in [j/rows, (j+1)/rows)`` and its
centre is at ``((i + 0.5)/cols, (j + 0.5)/rows)``: the OpenGL convention for an image uploaded
with its row 0 first. Wrapping is GL_REPEAT.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from ._checks import _image_shape, _int
from .clahe import periodic_clahe

__all__ = ["MipPyramid", "build_pyramid", "clahe_pyramid", "rank_equalize", "as_texture"]


def as_texture(image, *, name: str = "image") -> np.ndarray:
    """``image`` as a float32 texture in [0, 1]: uint8/uint16/bool scaled, floats checked."""
    a = np.asarray(image)
    _image_shape(name, a)
    if a.dtype == np.bool_:
        return a.astype(np.float32)
    if a.dtype == np.uint8:
        return a.astype(np.float32) / 255.0
    if a.dtype == np.uint16:
        return a.astype(np.float32) / 65535.0
    if a.dtype.kind != "f":
        raise TypeError(f"{name}: expected uint8, uint16, bool or float pixels, got {a.dtype}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    if a.min() < 0.0 or a.max() > 1.0:
        raise ValueError(
            f"{name}: float pixels must lie in [0, 1], got [{a.min()}, {a.max()}]; rescale first"
        )
    return a.astype(np.float32)


def _box_taps(n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """The exact box filter from n texels to m (output texel i averages the input interval
    [i n/m, (i+1) n/m); 2x2 boxes when n = 2 m) as taps: ``(index, weight)``, both (m, K), K
    <= 3 input texels per output texel in increasing order (weight 0 past the interval), so
    a level costs O(texels), not O(n m)."""
    r = n / m
    lo = np.arange(m, dtype=np.float64)[:, None] * r
    first = np.floor(lo).astype(np.int64)
    k = int(np.ceil(r)) + 1
    j = first + np.arange(k)[None, :]
    overlap = np.clip(np.minimum(j + 1, lo + r) - np.maximum(j, lo), 0.0, None)
    used = np.any(overlap > 0.0, axis=0)  # drop taps no output texel uses (n = 2 m: the third)
    return np.minimum(j, n - 1)[:, used], overlap[:, used] / r


def _filter_axis(a: np.ndarray, axis: int, m: int) -> np.ndarray:
    """``a`` box-filtered to ``m`` texels along ``axis``, in float64: each output texel the sum
    of its taps' weighted inputs, taps in increasing order."""
    index, weight = _box_taps(a.shape[axis], m)
    a = np.moveaxis(a, axis, 0)
    shape = (m,) + (1,) * (a.ndim - 1)
    out = weight[:, 0].reshape(shape) * a[index[:, 0]]
    for t in range(1, index.shape[1]):
        out = out + weight[:, t].reshape(shape) * a[index[:, t]]
    return np.moveaxis(out, 0, axis)


def _downsample(level: np.ndarray) -> np.ndarray:
    """Next mip level, GL size rule max(1, floor(n / 2)) per axis, exact box filter (rows,
    then columns, in float64)."""
    h, w = level.shape[:2]
    a = _filter_axis(level, 0, max(1, h // 2))  # float64 from the float64 weights on
    a = _filter_axis(a, 1, max(1, w // 2))
    return a.astype(np.float32)


@dataclass(frozen=True, eq=False)
class MipPyramid:
    """A mip pyramid: ``levels[k]`` has GL size ``max(1, floor(size_0 / 2**k))``, down to 1x1.

    Attributes
    ----------
    levels : tuple of (rows_k, cols_k[, C]) float32 arrays in [0, 1]
    """

    levels: tuple[np.ndarray, ...]

    @property
    def size(self) -> tuple[int, int]:
        """(cols, rows) of level 0: the texture size the ``lod`` channel is computed for."""
        return (int(self.levels[0].shape[1]), int(self.levels[0].shape[0]))

    @property
    def n_levels(self) -> int:
        return len(self.levels)

    @property
    def channels(self) -> int:
        return 1 if self.levels[0].ndim == 2 else int(self.levels[0].shape[2])

    def packed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(texels (N, C) float32, offsets (L,) int64, shapes (L, 2) int64) for the kernels."""
        flat = [lv.reshape(lv.shape[0] * lv.shape[1], -1) for lv in self.levels]
        offsets = np.cumsum([0] + [f.shape[0] for f in flat[:-1]]).astype(np.int64)
        shapes = np.array([lv.shape[:2] for lv in self.levels], dtype=np.int64)
        return np.ascontiguousarray(np.concatenate(flat), dtype=np.float32), offsets, shapes


def build_pyramid(image) -> MipPyramid:
    """Box-filtered mip pyramid of ``image`` ((rows, cols[, C]); uint8/uint16/bool/float)."""
    level = as_texture(image)
    levels = [level]
    while level.shape[0] > 1 or level.shape[1] > 1:
        level = _downsample(level)
        levels.append(level)
    return MipPyramid(tuple(levels))


def rank_equalize(level: np.ndarray) -> np.ndarray:
    """Monotone map of a level onto exactly uniform values ``(rank + 0.5) / N`` (stable ties),
    so that thresholding against it preserves mean tone exactly; local order (minima, maxima)
    is unchanged."""
    flat = level.ravel()
    order = np.argsort(flat, kind="stable")
    ranks = np.empty(flat.size, dtype=np.float64)
    ranks[order] = (np.arange(flat.size) + 0.5) / flat.size
    return ranks.reshape(level.shape).astype(np.float32)


def clahe_pyramid(
    image, *, window: int = 16, clip_limit: float = 0.01, nbins: int = 256, uniform: bool = True
) -> MipPyramid:
    """Mip pyramid with CLAHE applied to every level (Veryovka 2002 sec. 3.1).

    CLAHE makes threshold values approximately uniform and homogeneous at every scale, so
    thresholding keeps the mean tone while features stay sharp across mip levels. It runs on
    the torus (:func:`refnpr.texture.clahe.periodic_clahe`), so every level tiles when ``image``
    does; make an image that does not tile do so first (``load_texture(..., tiling="periodic")``).

    Parameters
    ----------
    image : (rows, cols) array
        Gray texture (uint8/uint16/bool or float in [0, 1]).
    window : int >= 2
        CLAHE window w in texels (the paper's w, capped at the level size; smaller gives softer
        textures).
    clip_limit : float in (0, 1]
        CLAHE clip limit (scikit-image's normalized units): any real number (a Python or
        numpy integer or float; not a bool).
    nbins : int >= 2
    uniform : bool
        Follow CLAHE by :func:`rank_equalize` on each level: CLAHE only *approximates* a uniform
        distribution (the brick texture's level 0 has a mean of about 0.46, its emptiest eighth
        of [0, 1] 1% of the texels of the fullest), which shifts thresholded tone; the rank map
        makes it exact, keeping CLAHE's local contrast and the alignment of minima and maxima
        across levels. ``False`` keeps the paper's CLAHE output.
    """
    window, nbins = _int("window", window, 2), _int("nbins", nbins, 2)
    real = isinstance(clip_limit, numbers.Real) and not isinstance(clip_limit, (bool, np.bool_))
    if not real or not 0.0 < clip_limit <= 1.0:
        raise ValueError(f"clip_limit: expected a number in (0, 1], got {clip_limit!r}")
    if not isinstance(uniform, (bool, np.bool_)):  # 1 and 0 are not flags
        raise TypeError(f"uniform: expected a bool, got {uniform!r}")
    base = build_pyramid(image)
    if base.channels != 1:
        raise ValueError(
            f"image: CLAHE threshold textures are gray, got {base.channels} channels; "
            "convert with skimage.color.rgb2gray first"
        )
    levels = [  # a level under 2 texels wide is the median threshold
        np.full_like(lv, 0.5)
        if min(lv.shape[:2]) < 2
        else periodic_clahe(lv, window=window, clip_limit=float(clip_limit), nbins=nbins)
        for lv in base.levels
    ]
    if uniform:
        levels = [rank_equalize(lv) for lv in levels]
    return MipPyramid(tuple(levels))
