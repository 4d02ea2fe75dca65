"""numba texture samplers (private; validated by refnpr.texture.sample): loops over the samples
of :mod:`refnpr.device.sampling`'s GL lookups, one channel at a time."""

from __future__ import annotations

from refnpr._jit import banded, inline_copy
from refnpr.device import sampling

_level = inline_copy(sampling.level)
_trilinear = inline_copy(sampling.trilinear)


@banded("uv")
def sample_level(lo, hi, pyr, uv, levels, out):
    """out (P, C) = bilinear sample of integer ``levels[p]`` (clamped to the pyramid) of the
    packed pyramid ``pyr = (texels, offsets, shapes)`` at uv (P, 2)."""
    for p in range(lo, hi):
        for c in range(out.shape[1]):
            out[p, c] = _level(pyr, levels[p], uv[p, 0], uv[p, 1], c)


@banded("uv")
def sample_trilinear(lo, hi, pyr, uv, lod, out):
    """out (P, C) = GL_LINEAR_MIPMAP_LINEAR sample of ``pyr`` at uv (P, 2) and LOD lod (P,):
    lod clamped to [0, L - 1], bilinear in the two nearest levels, linear in frac(lod)."""
    for p in range(lo, hi):
        for c in range(out.shape[1]):
            out[p, c] = _trilinear(pyr, uv[p, 0], uv[p, 1], lod[p], c)
