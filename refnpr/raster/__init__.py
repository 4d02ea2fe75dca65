"""Tile-based CPU rasterizer: camera, clipping, triangle setup, binning, numba kernels -> GBuffer.

Depends on nothing else of refnpr (only the numba flags of ``refnpr._jit``).
"""

from .camera import Camera
from .gbuffer import BUILTIN_CHANNELS, GBuffer, box_resolve
from .mesh import Mesh
from .rasterize import rasterize, valid_channels

__all__ = [
    "BUILTIN_CHANNELS",
    "Camera",
    "GBuffer",
    "Mesh",
    "box_resolve",
    "rasterize",
    "valid_channels",
]
