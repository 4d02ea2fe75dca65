"""Periodic plus smooth decomposition of an image (Moisan 2011), to make a texture tile.

L. Moisan, "Periodic plus smooth image decomposition", Journal of Mathematical Imaging and
Vision 39(2):161-179, 2011. An image u is the sum u = p + s of a *periodic* component p, whose
GL_REPEAT copies join without a seam, and a *smooth* component s that carries the jumps between
opposite borders. p is the unique image with

    Lap_per p = Lap_int u,    mean(p) = mean(u)                       (Moisan's definition of p)

where Lap_per is the discrete Laplacian on the torus (four neighbours, across the borders too)
and Lap_int the Laplacian of u with free borders: p keeps every local difference of u and
replaces the jump across each border by a smooth variation. s solves Lap_per s = v, v the jumps
across opposite borders, one division per frequency after the FFT (Moisan's closed form).
Rows are v, columns u (:mod:`refnpr.texture.pyramid`).
"""

from __future__ import annotations

import numpy as np

from ._checks import _image_shape

__all__ = ["TILINGS", "check_tiling", "make_tileable", "periodic_component", "smooth_component"]

#: Values of the ``tiling`` option of texture loaders: "none" (the image as given; ``None``
#: means the same) or "periodic" (its Moisan periodic component, clipped to [0, 1]).
TILINGS = ("none", "periodic")


def _as_float64_image(image, name: str) -> np.ndarray:
    a = np.asarray(image)
    if a.dtype.kind not in "fiub":
        raise TypeError(f"{name}: expected a numeric image array, got dtype {a.dtype}")
    _image_shape(name, a)
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    return a


def _boundary_image(u: np.ndarray) -> np.ndarray:
    """v = Lap_per u - Lap_int u: at each border texel, its wrap-around neighbour's value minus
    its own (Moisan's boundary image; corners receive both a row and a column term)."""
    v = np.zeros_like(u)
    v[0] += u[-1] - u[0]  # the neighbour of row 0 across the border is row M-1
    v[-1] += u[0] - u[-1]
    v[:, 0] += u[:, -1] - u[:, 0]
    v[:, -1] += u[:, 0] - u[:, -1]
    return v


def smooth_component(image) -> np.ndarray:
    """The smooth component ``s = image - periodic_component(image)`` (Moisan 2011).

    Parameters
    ----------
    image : (M, N) or (M, N, C) array
        Any numeric image; channels are decomposed independently.

    Returns
    -------
    (M, N) or (M, N, C) float64
        Zero mean per channel; zero exactly when ``image`` already tiles.
    """
    u = _as_float64_image(image, "image")
    m, n = u.shape[:2]
    v = _boundary_image(u)
    q = np.arange(m).reshape(m, 1)
    r = np.arange(n).reshape(1, n)
    # Fourier symbol of Lap_per (Moisan): 2 cos(2 pi q / M) + 2 cos(2 pi r / N) - 4
    symbol = 2.0 * np.cos(2.0 * np.pi * q / m) + 2.0 * np.cos(2.0 * np.pi * r / n) - 4.0
    symbol[0, 0] = 1.0  # the mean of s is 0: its (0, 0) coefficient is set below
    if u.ndim == 3:
        symbol = symbol[..., None]
    s_hat = np.fft.fft2(v, axes=(0, 1)) / symbol  # Lap_per s = v, solved per frequency
    s_hat[0, 0] = 0.0
    return np.fft.ifft2(s_hat, axes=(0, 1)).real


def periodic_component(image) -> np.ndarray:
    """The periodic component p of ``image`` (Moisan 2011), which tiles without a seam: the
    solution of ``Lap_per p = Lap_int u`` with ``mean(p) = mean(u)``, by the FFT in float64.

    Takes and returns arrays as :func:`smooth_component`; p has the mean of ``image`` and may
    leave its range near the borders.
    """
    u = _as_float64_image(image, "image")
    return u - smooth_component(u)


def check_tiling(tiling, *, param: str = "tiling") -> str:
    """``tiling`` as one of :data:`TILINGS` (``None`` is "none"); TypeError/ValueError else."""
    if tiling is None:
        return "none"
    if not isinstance(tiling, str):
        raise TypeError(
            f"{param}: expected one of {list(TILINGS)} (or None), got "
            f"{type(tiling).__name__} {tiling!r}"
        )
    if tiling not in TILINGS:
        raise ValueError(
            f"{param}: expected one of {list(TILINGS)}: 'none' uses the image as given, "
            f"'periodic' its periodic component (Moisan 2011) so that it tiles; got {tiling!r}"
        )
    return tiling


def make_tileable(texture: np.ndarray, tiling: str | None, *, param: str = "tiling") -> np.ndarray:
    """``texture`` ((rows, cols[, C]) float in [0, 1]) as is for ``tiling`` "none" or None; for
    "periodic" its periodic component, clipped to [0, 1] (pointwise, so it still tiles), float32.
    ``param`` names the user's parameter in error messages."""
    if check_tiling(tiling, param=param) == "none":
        return texture
    return np.clip(periodic_component(texture), 0.0, 1.0).astype(np.float32)
