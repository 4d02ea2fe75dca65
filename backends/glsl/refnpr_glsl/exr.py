"""OpenEXR float32 images through the ``OpenEXR`` package (array layout: row 0 = top)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR

__all__ = ["read_exr", "write_exr"]

_ORDER = {"R": 0, "G": 1, "B": 2, "A": 3, "Y": 0}


def read_exr(path: str | Path) -> np.ndarray:
    """Read an EXR as float32: (H, W) for one channel, else (H, W, C) in R, G, B, A order."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"exr: file {str(path)!r} does not exist")
    with OpenEXR.File(str(p), separate_channels=True) as f:
        chans = {k: np.asarray(v.pixels, dtype=np.float32) for k, v in f.channels().items()}
    names = sorted(chans, key=lambda k: (_ORDER.get(k.split(".")[-1], 9), k))
    if len(names) == 1:
        return chans[names[0]].copy()
    return np.stack([chans[k] for k in names], axis=-1)


def write_exr(path: str | Path, image: np.ndarray) -> Path:
    """Write (H, W) as channel Y or (H, W, 3|4) as RGB(A), float32, ZIP compression."""
    img = np.ascontiguousarray(image, dtype=np.float32)
    if img.ndim == 2:
        channels = {"Y": img}
    elif img.ndim == 3 and img.shape[2] in (3, 4):
        channels = {"RGBA"[: img.shape[2]]: img}
    else:
        raise ValueError(f"image: expected (H, W) or (H, W, 3|4), got shape {img.shape}")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))
    return Path(path)
