"""Strength of the thresholding effect (Veryovka sec. 5, Figure 5).

The paper's material shader "blends between the original and thresholded illumination values"
and the artist varies the blend "depending on surface orientation and/or illumination level":
lines fade on surfaces facing the camera and vanish in the darkest and brightest regions. The
paper gives no formula; refnpr uses

- orientation: ``s_o = 1 - facing_fade * |n.v|^facing_power`` (1 at silhouettes, ``1 -
  facing_fade`` where the surface faces the camera);
- illumination: ``s_i = S(x / dark) * S((1 - x) / bright)`` with S the smoothstep on [0, 1] and
  x the term being thresholded (a width of 0 disables that side);

and the blend ``B(x) = x + strength * s_o * s_i * (T(x) - x)`` of
:func:`refnpr.formulas.threshold.threshold_illumination` (strength 1 = eq. 2, 0 = eq. 1).
"""

from __future__ import annotations

import numpy as np

__all__ = ["smoothstep", "facing_strength", "tone_strength", "blend"]


def smoothstep(x: np.ndarray) -> np.ndarray:
    """3 x^2 - 2 x^3 on x clipped to [0, 1]."""
    c = np.clip(x, 0.0, 1.0)
    return c * c * (3.0 - 2.0 * c)


def facing_strength(n_dot_v: np.ndarray, fade: float, power: float) -> np.ndarray:
    """(M,) float64 ``1 - fade * |n.v|^power``: lines fade where the surface faces the camera."""
    return 1.0 - fade * np.abs(n_dot_v) ** power


def tone_strength(x: np.ndarray, dark: float, bright: float) -> np.ndarray:
    """(M,) float64 in [0, 1]: 0 at x = 0 (if ``dark`` > 0) and x = 1 (if ``bright`` > 0)."""
    out = np.ones_like(x)
    if dark > 0.0:
        out = out * smoothstep(x / dark)
    if bright > 0.0:
        out = out * smoothstep((1.0 - x) / bright)
    return out


def blend(x: np.ndarray, tx: np.ndarray, strength: np.ndarray) -> np.ndarray:
    """``x + strength (T(x) - x)``: eq. 2 at strength 1, eq. 1 at 0 (sec. 5)."""
    return x + strength * (tx - x)
