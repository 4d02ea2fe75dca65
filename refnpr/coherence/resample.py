"""``warp``: frame t-1 resampled along the exact motion field onto the pixels of frame t."""

from __future__ import annotations

import numpy as np

from .motion import MotionField

__all__ = ["warp"]


def warp(prev_image: np.ndarray, motion: MotionField) -> np.ndarray:
    """Sample frame t-1 where each pixel of frame t was: ``warp(I_{t-1})`` of Lai et al. 2018.

    Bilinear between the four pixel centres around the re-projected point (``motion.taps``,
    ``motion.weights``), clamped to the edge pixel in the outer half-pixel band; defined on
    ``motion.valid``, 0 elsewhere.

    Parameters
    ----------
    prev_image : (H, W) or (H, W, C) float
        Frame t-1 (e.g. luminance, or linear RGBA), the size of the motion field.
    motion : MotionField
        From :func:`refnpr.coherence.motion_field` for frames t and t-1.

    Returns
    -------
    (H, W) or (H, W, C) float64
        The warped previous frame on the pixel grid of frame t.
    """
    if not isinstance(motion, MotionField):
        raise TypeError(
            f"motion: expected a MotionField (motion_field(...)), got {type(motion).__name__}"
        )
    img = np.asarray(prev_image)
    if img.ndim not in (2, 3) or img.shape[:2] != motion.shape:
        raise ValueError(
            f"prev_image: expected shape {motion.shape} or {motion.shape + ('C',)} (the motion "
            f"field's H, W), got {img.shape}"
        )
    if img.dtype.kind not in "fiu":
        raise TypeError(f"prev_image: expected a numeric array, got dtype {img.dtype}")
    h, w = motion.shape
    flat = img.reshape(h * w, -1).astype(np.float64)
    out = np.zeros((h, w, flat.shape[1]))
    for k in range(4):
        out += motion.weights[k][..., None] * flat[motion.taps[k]]
    out[~motion.valid] = 0.0
    return out[..., 0] if img.ndim == 2 else out
