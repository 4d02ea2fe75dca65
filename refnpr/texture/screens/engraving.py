"""The 1D engraving screen of sec. 4.1 as a mip-mapped texture."""

from __future__ import annotations

import numpy as np

from refnpr.formulas import halftone

from .._checks import _pow2
from ..pyramid import MipPyramid
from .stroke_set import level_sizes


def engraving_pyramid(size: int = 256, *, profile: str = "triangle") -> MipPyramid:
    """The 1D engraving screen (sec. 4.1) as a ``(1, size)`` mip-mapped texture along u.

    Level ``k`` is :func:`refnpr.formulas.halftone.engraving_ramp` ``(size_k)``, the profile
    sampled at the level's own texel centres (the 1-texel level is 0.5): for the ramp this is
    the box-filtered pyramid; for the triangle it keeps the full trough and peak that a box
    filter flattens where the kink falls inside a texel. Each level is as uniform as its texel
    count allows, so thresholding keeps the tone at every level.

    Returns
    -------
    MipPyramid of (1, size_k) float32
    """
    size = _pow2("size", size, 2, 1 << 16)
    levels = [
        halftone.engraving_ramp(s, profile=profile).astype(np.float32)[None, :]
        for s in level_sizes(size)[:-1]
    ]
    return MipPyramid(tuple(levels) + (np.full((1, 1), 0.5, dtype=np.float32),))
