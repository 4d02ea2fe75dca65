"""The sRGB transfer functions (IEC 61966-2-1) of one value."""

from __future__ import annotations

from refnpr._jit import njit

__all__ = ["srgb_to_linear", "linear_to_srgb"]


@njit
def srgb_to_linear(x):
    """Linear value of the sRGB-encoded ``x`` in [0, 1]."""
    if x <= 0.04045:
        return x / 12.92
    return ((x + 0.055) / 1.055) ** 2.4


@njit
def linear_to_srgb(x):
    """sRGB encoding of the linear value ``x`` in [0, 1]."""
    if x <= 0.0031308:
        return x * 12.92
    return 1.055 * x ** (1.0 / 2.4) - 0.055
