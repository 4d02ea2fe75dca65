"""Strength of the thresholding effect (Veryovka sec. 5, Figure 5).

The paper's material shader "blends between the original and thresholded illumination values"
and the artist varies the blend "depending on surface orientation and/or illumination level":
lines fade on surfaces facing the camera and vanish in the darkest and brightest regions. The
paper gives no formula; refnpr uses

- orientation: ``s_o = 1 - fade * |n.v|^power`` (1 at silhouettes, ``1 - fade`` where the
  surface faces the camera): :func:`facing_strength`;
- illumination: ``s_i = S(x / dark) * S((1 - x) / bright)`` with S the smoothstep on [0, 1] and
  x the term being thresholded (a width of 0 disables that side): :func:`tone_strength`;

and the blend ``B(x) = x + st (T(x) - x)`` (:func:`strength_blend`; st = strength s_o s_i) of
:func:`refnpr.formulas.threshold.threshold_illumination` (st = 1: eq. 2, st = 0: eq. 1).
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import clip01

from .._face import elementwise, face
from .._shading_checks import reals
from .._validate import check_scalar

__all__ = ["facing_strength", "tone_strength", "strength_blend"]


@njit
def _pow(x, p):
    """``x ** p`` with numpy's fast paths of a scalar exponent (square, identity, sqrt)."""
    if p == 2.0:
        return x * x
    if p == 1.0:
        return x
    if p == 0.5:
        return math.sqrt(x)
    return x**p


@njit
def _smoothstep(x):
    c = clip01(x)
    return c * c * (3.0 - 2.0 * c)  # 3 x^2 - 2 x^3 on x clipped to [0, 1]


@njit
def _facing_strength(n_dot_v, fade, power):
    return 1.0 - fade * _pow(abs(n_dot_v), power)  # sec. 5: lines fade facing the camera


@face(_facing_strength)
def facing_strength(n_dot_v, fade: float, power: float) -> np.ndarray:
    """Orientation strength of sec. 5: ``1 - fade |n.v|^power``.

    ``facing_strength.scalar(n_dot_v, fade, power)`` is the device function.

    Parameters
    ----------
    n_dot_v : (...) array
        Normal times the unit direction towards the eye.
    fade : float in [0, 1]
        The strength lost where the surface faces the camera.
    power : float > 0
        How fast the fade sets in away from silhouettes.

    Returns
    -------
    (...) ndarray; float64, or float32 if ``n_dot_v`` is float32.
    """
    fade = check_scalar("fade", fade, lo=0.0, hi=1.0, hint="0 = no fade, 1 = none facing")
    power = check_scalar("power", power, lo=0.0, lo_open=True, hint="use e.g. 1 or 2")
    dt, c = reals(n_dot_v=n_dot_v)
    return elementwise(facing_strength.scalar, dt, c, fade, power)


@njit
def _tone_strength(x, dark, bright):
    ts = 1.0
    if dark > 0.0:  # 0 at x = 0
        ts = ts * _smoothstep(x / dark)
    if bright > 0.0:  # 0 at x = 1
        ts = ts * _smoothstep((1.0 - x) / bright)
    return ts


@face(_tone_strength)
def tone_strength(x, dark: float, bright: float) -> np.ndarray:
    """Illumination strength of sec. 5: ``S(x / dark) S((1 - x) / bright)``, S the smoothstep.

    0 at x = 0 (if ``dark`` > 0) and at x = 1 (if ``bright`` > 0), 1 between the two fades.
    ``tone_strength.scalar(x, dark, bright)`` is the device function.

    Parameters
    ----------
    x : (...) array
        The term being thresholded.
    dark, bright : float in [0, 0.5]
        Widths of the fades (0: none).

    Returns
    -------
    (...) ndarray in [0, 1]; float64, or float32 if ``x`` is float32.
    """
    dark = check_scalar("dark", dark, lo=0.0, hi=0.5, hint="a width of 0 disables the fade")
    bright = check_scalar("bright", bright, lo=0.0, hi=0.5, hint="a width of 0 disables the fade")
    dt, x = reals(x=x)
    return elementwise(tone_strength.scalar, dt, x, dark, bright)


@njit
def _strength_blend(x, tx, strength):
    return x + strength * (tx - x)  # sec. 5: eq. 2 at strength 1, eq. 1 at 0


@face(_strength_blend)
def strength_blend(x, tx, strength) -> np.ndarray:
    """The blend of sec. 5: ``x + strength (T(x) - x)``, from the continuous term x (eq. 1) to
    the thresholded one T(x) (eq. 2).

    ``strength_blend.scalar(x, tx, strength)`` is the device function.

    Parameters
    ----------
    x, tx : (...) arrays
        The term and its (filtered) thresholding.
    strength : (...) array in [0, 1]

    Returns
    -------
    (...) ndarray; float64, or float32 if every input is float32.
    """
    dt, x, tx, strength = reals(x=x, tx=tx, strength=strength)
    return elementwise(strength_blend.scalar, dt, x, tx, strength)
