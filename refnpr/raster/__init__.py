"""Tile-based CPU rasterizer: camera, clipping, triangle setup, binning, numba kernels -> GBuffer.

Depends on the numba flags of ``refnpr._jit``, the memory estimates of ``refnpr._memory`` and
the device layer's world -> pixel projection (``refnpr.device.projection``).
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
