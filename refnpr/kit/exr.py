"""OpenEXR files of float32 arrays (textures, expected linear images), written atomically.

Channel naming (what a backend reads): 1 component ``Y``; 2 components ``R``, ``G``; 3
components ``R``, ``G``, ``B``; 4 components ``R``, ``G``, ``B``, ``A``. Pixel type FLOAT
(32-bit), ZIP compression (lossless), scanline image, row 0 = the array's row 0 (top). Written
by refnpr's one EXR writer (:func:`refnpr.exr.write_exr_channels`: atomic, read back before the
rename, a full disk a clear error).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..exr import write_exr_channels

__all__ = ["EXR_CHANNELS", "write_exr"]

#: Channel names by component count.
EXR_CHANNELS: dict[int, tuple[str, ...]] = {
    1: ("Y",),
    2: ("R", "G"),
    3: ("R", "G", "B"),
    4: ("R", "G", "B", "A"),
}


def write_exr(path: str | os.PathLike, array: np.ndarray) -> Path:
    """Write a float array as a 32-bit float OpenEXR file (atomic rename; its directory is
    created) with the channel naming of the module docstring.

    Parameters
    ----------
    path : str or path
    array : (H, W) or (H, W, C) float, C in 1-4
        Written as float32 (exact for float32 input); no NaN.

    Returns
    -------
    Path
    """
    arr = np.asarray(array)
    if arr.dtype.kind != "f":
        raise TypeError(f"array: expected a float array for {str(path)!r}, got dtype {arr.dtype}")
    if arr.ndim == 2:
        arr = arr[..., None]
    if arr.ndim != 3 or arr.shape[2] not in EXR_CHANNELS or min(arr.shape[:2]) < 1:
        raise ValueError(
            f"array: expected shape (H, W) or (H, W, C) with C in 1-4 for {str(path)!r}, "
            f"got {np.shape(array)}"
        )
    if np.isnan(arr).any():
        raise ValueError(f"array: NaN values cannot be exported to {str(path)!r}")
    arr = arr.astype(np.float32)
    names = EXR_CHANNELS[arr.shape[2]]
    channels = {n: np.ascontiguousarray(arr[..., i]) for i, n in enumerate(names)}
    return write_exr_channels(path, channels)
