"""Veryovka 2002, *Animation with threshold textures* (Graphics Interface 2002).

Discrete-tone shading by thresholding the terms of a local illumination model against a
threshold texture (eq. 2), with procedural multi-scale line textures (sec. 3.2) and filtered
thresholding (sec. 4).

Conventions (see ``docs/paper-notes.md``, "Veryovka 2002"):

- ``T(x, t)`` (eq. 3) is white (1) where ``x >= t`` and black (0) where ``x < t``. A threshold
  texture takes values in [0, 1); it is tone preserving when uniformly distributed, since then the
  mean of ``T(x, t)`` is x.
- The lines are iso-lines of a coordinate v; eq. 5's d is the screen distance between the
  iso-lines v and v + 1 (the paper writes u), and eq. 6 is ``Frac(v * 2**floor(s))``.
- The multi-scale line function uses the paper's base f(v) = v (a sawtooth) and its eq. 8 blend
  by default; ``uniform=True`` selects a monotone tone-preserving correction of that blend.
- Inputs are finite reals whose shapes broadcast; float32 in -> float32 out, else float64.

A style holding per-pixel ``v``, ``s`` (dyadic scale) and ``intensity`` arrays ``(H, W)`` calls::

    t = line_threshold(v, s, uniform=True)          # (H, W) threshold texture
    ink = step(intensity, t)                        # 1 = white, 0 = black line
    ink_aa = line_coverage(v, s, intensity, dv_dx, dv_dy, uniform=True)   # box-filtered

Each per-sample formula is a scalar device function (``f.scalar``: the ``threshold`` style's
kernel calls it per sample) whose public numpy face validates and runs it elementwise. Modules:
``lines`` (eqs. 3-8), ``textures`` and ``compose`` (hatching, cross-hatching, dots), ``stipple``,
``filtering`` (sec. 4), ``strength`` (sec. 5); eq. 2 is :func:`threshold_illumination`.
"""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit

from .. import lighting
from .._face import elementwise
from .._shading_checks import broadcast, check_range, real
from .._validate import result_dtype
from . import compose, filtering, lines, stipple, strength, textures
from .compose import *  # noqa: F403
from .filtering import *  # noqa: F403
from .lines import *  # noqa: F403
from .lines import check_steps, step_any
from .stipple import *  # noqa: F403
from .strength import *  # noqa: F403
from .strength import strength_blend
from .textures import *  # noqa: F403

__all__ = [
    "threshold_illumination",
    *lines.__all__,
    *textures.__all__,
    *compose.__all__,
    *stipple.__all__,
    *filtering.__all__,
    *strength.__all__,
]

_strength_blend = strength_blend.scalar


@njit
def _thresholded_term(f, t, n, strength):
    return _strength_blend(f, step_any(f, t, n), strength)  # eq. 2: T(f), sec. 5 blend


def _thresholded(name: str, terms, t: np.ndarray, n: int, strength: np.ndarray, dt) -> list:
    single = not isinstance(terms, (list, tuple))
    out = []
    for i, f in enumerate([terms] if single else terms):
        f = real(name if single else f"{name}[{i}]", f, dt)
        broadcast(**{name: f, "t": t, "strength": strength})
        out.append(elementwise(_thresholded_term, dt, f, t, n, strength))
    return out[0] if single else out


def threshold_illumination(
    f_d,
    f_s,
    t,
    *,
    m_a=0.0,
    l_a=0.0,
    m_d=1.0,
    m_s=1.0,
    l=1.0,
    n: int = 1,
    t_s=None,
    strength=1.0,
) -> np.ndarray:
    """Discrete-tone shading of Veryovka eq. 2: the diffuse and specular terms thresholded.

    ``I = m_a l_a + sum_i m_d T(f_d_i) l_i + sum_i m_s T(f_s_i) l_i`` with T the step T(., t) of
    eq. 3 (n = 1) or T_n(., t) of eq. 4 (n + 1 tones). The ambient term is kept as is. With
    ``strength`` < 1 the thresholded terms are blended towards the continuous ones, as the paper's
    material shader does to control the strength of the texturing effect (sec. 5).

    Parameters
    ----------
    f_d : (...) array, or a list of them (one per light)
        Diffuse terms f_d(N, L_i) (e.g. :func:`refnpr.formulas.lighting.diffuse`).
    f_s : same structure as ``f_d``, or None
        Specular terms f_s(N, L_i, V); None omits the specular sum.
    t : (...) array
        Threshold texture for the diffuse terms (0.5 everywhere reproduces the classic toon
        shader, Lake et al. 2000).
    m_a, l_a, m_d, m_s, l : keyword-only
        Colours as in :func:`refnpr.formulas.lighting.illumination` (scalars or (C,) arrays;
        ``l`` may be a list with one colour per light).
    n : int in [1, 2**53], keyword-only
        Number of steps of T_n.
    t_s : (...) array or None, keyword-only
        Threshold texture for the specular terms; None uses ``t``.
    strength : float or (...) array in [0, 1], keyword-only
        1 = fully thresholded (eq. 2), 0 = continuous shading (eq. 1).

    Returns
    -------
    (...) or (..., C) ndarray; float64, or float32 if every array input is float32.
    """
    n = check_steps(n)
    terms = [f_d, f_s, t, t_s, strength, m_a, l_a, m_d, m_s, l]
    flat = [x for x in terms if x is not None and not isinstance(x, (list, tuple))]
    flat += [y for x in (f_d, f_s, l) if isinstance(x, (list, tuple)) for y in x]
    dt = result_dtype(*flat)
    t = real("t", t, dt)
    t_s = t if t_s is None else real("t_s", t_s, dt)
    strength = real("strength", strength, dt)
    check_range("strength", strength, 0.0, 1.0, "0 = continuous shading, 1 = thresholded")
    td = _thresholded("f_d", f_d, t, n, strength, dt)
    ts = None if f_s is None else _thresholded("f_s", f_s, t_s, n, strength, dt)
    out = lighting.illumination(td, ts, m_a=m_a, l_a=l_a, m_d=m_d, m_s=m_s, l=l)  # eq. 2
    return np.asarray(out, dtype=dt)
