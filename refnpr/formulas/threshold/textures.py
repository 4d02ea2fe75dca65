"""Line-texture compositions of Veryovka sec. 3.2 (Fig. 4): hatching at one or more angles and
stippling from a 2D multi-scale dot function."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import clip, frac

from .._face import Whole, elementwise, face
from .._shading_checks import broadcast, check_positive, real, trailing
from .._validate import check_int, check_scalar, describe, result_dtype
from .compose import combine_thresholds
from .lines import TINY, _dyadic_remap, dyadic_scale_from_gradient, line_threshold

__all__ = [
    "hatch_coordinate",
    "hatch_threshold",
    "dot_function",
    "dot_dyadic_scale",
    "DotToneTable",
    "dot_tone_table",
    "dot_threshold",
]


def _uv(name: str, value, dtype: np.dtype) -> np.ndarray:
    arr = real(name, value, dtype)
    trailing(name, arr, 2, "texture coordinates (u, v)")
    return arr


def _angle(name: str, value) -> float:
    return check_scalar(name, value, hint="angles are in radians")


def _angles(angles) -> list[float]:
    """``angles`` (a non-empty sequence or 1-D array of radians) as a list of floats."""
    one_d = isinstance(angles, np.ndarray) and angles.ndim == 1
    seq = isinstance(angles, Sequence) and not isinstance(angles, (str, bytes))
    if not (one_d or seq) or len(angles) == 0:
        raise ValueError(
            f"angles: expected a non-empty sequence of radians, got {describe(angles)}; "
            "pass at least one angle, e.g. (0.3,) for single lines"
        )
    return [_angle(f"angles[{i}]", a) for i, a in enumerate(angles)]


@njit
def _hatch_coordinate(u, v, sin_a, cos_a):
    return -u * sin_a + v * cos_a  # v rotated: iso-lines along (cos a, sin a)


@face(_hatch_coordinate)
def hatch_coordinate(uv, angle: float) -> np.ndarray:
    """Line coordinate of hatching at ``angle``: ``v_theta = -u sin(angle) + v cos(angle)``.

    Its iso-lines run along the direction (cos(angle), sin(angle)) of texture space; angle 0
    gives v itself (lines parallel to u, as in the paper). Linear, so the same call maps
    ``duv_dx`` / ``duv_dy`` to the screen derivatives of v_theta.
    ``hatch_coordinate.scalar(u, v, sin_a, cos_a)`` is the device function.

    Parameters
    ----------
    uv : (..., 2) array
        Texture coordinates (or their screen derivatives).
    angle : float
        Radians.

    Returns
    -------
    (...) ndarray; float64, or float32 if ``uv`` is float32.
    """
    a = _angle("angle", angle)
    dt = result_dtype(uv)
    uv = _uv("uv", uv, dt)
    sin_a, cos_a = math.sin(a), math.cos(a)
    return elementwise(hatch_coordinate.scalar, dt, uv[..., 0], uv[..., 1], sin_a, cos_a)


def hatch_threshold(
    uv,
    duv_dx,
    duv_dy,
    *,
    w,
    angles: Sequence[float] = (0.0,),
    onsets=None,
    uniform: bool = False,
    noise=None,
) -> np.ndarray:
    """Single-line or cross-hatching threshold texture (Veryovka sec. 3.2, Fig. 4).

    For each angle: the line coordinate :func:`hatch_coordinate`, its dyadic scale from the
    screen derivatives (eq. 5 with d = 1 / |grad v_theta|) and :func:`line_threshold`; then
    :func:`combine_thresholds` of the layers.

    Parameters
    ----------
    uv : (..., 2) array
        Texture coordinates.
    duv_dx, duv_dy : (..., 2) arrays
        Their screen derivatives per pixel (G-buffer ``duv_dx``, ``duv_dy``).
    w : float or (...) array > 0, keyword-only
        Line period in pixels.
    angles : sequence or (L,) array of floats, keyword-only
        Hatching directions in texture space, radians; one angle, ``(a,)``, gives single lines.
    onsets : sequence of floats, keyword-only
        Per-angle onset intensity (see :func:`combine_thresholds`).
    uniform : bool, keyword-only
        Tone-preserving multi-scale blend (see :func:`multiscale_line`).
    noise : (...) array or None, keyword-only
        Phase modulation in line periods, applied to every layer (see :func:`line_threshold`).

    Returns
    -------
    (...) ndarray in [0, 1); float64, or float32 if the inputs are float32.
    """
    angs = _angles(angles)
    dt = result_dtype(uv, duv_dx, duv_dy)
    uv = _uv("uv", uv, dt)
    gx = _uv("duv_dx", duv_dx, dt)
    gy = _uv("duv_dy", duv_dy, dt)
    broadcast(uv=uv, duv_dx=gx, duv_dy=gy)
    layers = []
    for a in angs:
        v = hatch_coordinate(uv, a)
        s = dyadic_scale_from_gradient(hatch_coordinate(gx, a), hatch_coordinate(gy, a), w)
        layers.append(line_threshold(v, s.astype(dt), uniform=uniform, noise=noise))
    if len(layers) == 1 and onsets is None:
        return layers[0]
    return combine_thresholds(layers, onsets=onsets)


@njit
def _dot(pu, pv):
    """D at a position (pu, pv) in [0, 1)^2 of the cell."""
    du = pu if pu <= 1 - pu else 1 - pu
    dv = pv if pv <= 1 - pv else 1 - pv
    r2 = du * du + dv * dv
    r2 = r2 if r2 <= 0.5 else 0.5
    r = max(math.sqrt(r2), 0.5)
    segment = r * r * math.acos(0.5 / r) - 0.5 * math.sqrt(max(r * r - 0.25, 0.0))
    area = math.pi * r2 - 4 * (segment if r2 > 0.25 else 0.0)  # within r of the corners
    return clip(1 - area, 0.0, 1.0)


@njit
def _dot_function(pu, pv):
    return _dot(frac(pu), frac(pv))  # period 1 in both axes


@face(_dot_function)
def dot_function(p) -> np.ndarray:
    """Base dot function D(p) of the stipple texture: uniform on [0, 1], 1 at lattice points.

    ``D = 1 - A(r)`` with r the distance from p to the nearest integer lattice point and A(r)
    the area of the unit cell within distance r of its corners (pi r^2 up to r = 1/2, minus four
    circular segments beyond). A is the fraction of the cell with a smaller distance, so D is
    exactly uniform over a cell; thresholded, it gives round dots centred on the lattice that
    grow with darkness and merge at the darkest tones. ``dot_function.scalar(pu, pv)`` is the
    device function.

    Parameters
    ----------
    p : (..., 2) array
        Position in dot cells (period 1 in both axes).

    Returns
    -------
    (...) ndarray in [0, 1]; float64, or float32 if ``p`` is float32.
    """
    dt = result_dtype(p)
    p = _uv("p", p, dt)
    return elementwise(dot_function.scalar, dt, p[..., 0], p[..., 1])


@njit
def _dot_dyadic_scale(du, dv, log2_w):
    rho = max(math.hypot(du[0], du[1]), math.hypot(dv[0], dv[1]))  # the GL LOD footprint
    rho = rho if rho >= TINY else TINY  # (NaN stays NaN)
    return -(math.log2(rho) + log2_w)  # eq. 5


@face(_dot_dyadic_scale)
def dot_dyadic_scale(duv_dx, duv_dy, w) -> np.ndarray:
    """Isotropic dyadic scale for 2D textures: eq. 5 with d = 1 / rho, rho the GL LOD footprint.

    ``rho = max(|duv_dx|, |duv_dy|)`` (texture units per pixel), ``s = -log2(w * rho)``; a zero
    footprint is clamped to the smallest normal float64 so s stays finite.
    ``dot_dyadic_scale.scalar(du, dv, log2_w)`` is the device function (``du = duv_dx``,
    ``dv = duv_dy`` as 2-tuples, ``log2_w = log2(w)``).

    Parameters
    ----------
    duv_dx, duv_dy : (..., 2) arrays
        Screen derivatives of the texture coordinates.
    w : float or (...) array > 0
        Dot spacing in pixels.

    Returns
    -------
    (...) ndarray; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(duv_dx, duv_dy, w)
    gx = _uv("duv_dx", duv_dx, dt)
    gy = _uv("duv_dy", duv_dy, dt)
    w = real("w", w, dt)
    check_positive("w", w, "w is the dot spacing in pixels, e.g. 6")
    broadcast(duv_dx=gx[..., 0], duv_dy=gy[..., 0], w=w)
    du = (gx[..., 0], gx[..., 1])
    dv = (gy[..., 0], gy[..., 1])
    return elementwise(dot_dyadic_scale.scalar, dt, du, dv, np.log2(w.astype(np.float64)))


@dataclass(frozen=True, eq=False)
class DotToneTable:
    """Tabulated CDF of the 2D multi-scale dot function, ``cdf[j, i] = G(y_i, t_j)``.

    ``t_j = j / (n_t - 1)`` and ``y_i = i / (n_y - 1)``; rows t = 0 and t = 1 are the identity
    (D is exactly uniform there). Build it once with :func:`dot_tone_table` and pass it to
    :func:`dot_threshold`.

    Attributes
    ----------
    cdf : (n_t, n_y) float64 ndarray, non-decreasing along y, 0 at y = 0 and 1 at y = 1.
    """

    cdf: np.ndarray


def dot_tone_table(*, n_t: int = 33, n_y: int = 257, samples: int = 256) -> DotToneTable:
    """Build the :class:`DotToneTable` by sampling F(p, t) on a ``samples x samples`` cell grid.

    The 2D analogue of ``multiscale_line(uniform=True)``: the paper's blend (eq. 8 in 2D) is not
    uniform at intermediate scales, and its CDF has no simple closed form, so it is tabulated.
    The defaults take about 0.1 s and give a tone error below 0.01.

    Parameters
    ----------
    n_t, n_y : int >= 2, keyword-only
        Table resolution in t and in the threshold value y.
    samples : int >= 8, keyword-only
        Grid resolution per cell axis.

    Returns
    -------
    DotToneTable
    """
    n_t = check_int("n_t", n_t, lo=2)
    n_y = check_int("n_y", n_y, lo=2)
    samples = check_int("samples", samples, lo=8)
    g = (np.arange(samples) + 0.5) / samples
    pu, pv = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    d0 = elementwise(_dot, np.float64, pu, pv)
    d1 = elementwise(_dot, np.float64, *(np.where(p < 0.5, 2 * p, 2 * p - 1) for p in (pu, pv)))
    y = np.linspace(0.0, 1.0, n_y)
    cdf = np.empty((n_t, n_y))
    for j, t in enumerate(np.linspace(0.0, 1.0, n_t)):
        f = np.sort((1 - t) * d0 + t * d1)  # eq. 8
        cdf[j] = np.searchsorted(f, y, side="right") / f.size
    cdf[0] = y
    cdf[-1] = y
    cdf[:, 0] = 0.0
    cdf[:, -1] = 1.0
    cdf.setflags(write=False)
    return DotToneTable(cdf=cdf)


@njit
def _half_scale(p):
    return 2 * p if p < 0.5 else 2 * p - 1  # eq. 7 per axis: Frac(2 p)


@njit
def _dot_threshold(u, v, s, cdf):
    t = s - np.floor(s)
    pu = _dyadic_remap(u, s)  # eq. 6 per axis
    pv = _dyadic_remap(v, s)
    f = (1 - t) * _dot(pu, pv) + t * _dot(_half_scale(pu), _half_scale(pv))  # eq. 8
    if cdf.shape[0] > 0:  # bilinear lookup of G(f, t) in the tone table
        nt = cdf.shape[0] - 1
        ny = cdf.shape[1] - 1
        x = t * nt
        j = int(clip(np.floor(x), 0.0, nt - 1.0))
        ft = x - j
        yy = clip(f, 0.0, 1.0) * ny
        i = int(clip(np.floor(yy), 0.0, ny - 1.0))
        fy = yy - i
        g0 = cdf[j, i] * (1 - fy) + cdf[j, i + 1] * fy
        g1 = cdf[j + 1, i] * (1 - fy) + cdf[j + 1, i + 1] * fy
        f = (1 - ft) * g0 + ft * g1
    return clip(f, 0.0, 1.0)


@face(_dot_threshold)
def dot_threshold(uv, s, *, tone_table: DotToneTable | None = None) -> np.ndarray:
    """Multi-scale stipple threshold texture (Veryovka sec. 3.2, Fig. 4): eqs. 6-8 in 2D.

    ``F(p, t) = (1 - t) D(p) + t D(Frac(2 p))`` with ``p = Frac(uv * 2**floor(s))``, t = Frac(s)
    and D :func:`dot_function`. The dots of one scale stay dots at the next (lattice points
    stay lattice points) and new dots grow in the cell centres as t goes from 0 to 1; no jump
    where s crosses an integer. With ``tone_table`` the blend is made uniform at every t (the
    paper's blend drifts in tone, as for lines), through a monotone map that keeps the order of
    values. ``dot_threshold.scalar(u, v, s, cdf)`` is the device function (``cdf`` the table's,
    or an empty (0, 0) array).

    Parameters
    ----------
    uv : (..., 2) array
        Texture coordinates (one dot cell per texture unit at s = 0).
    s : (...) array
        Dyadic scale, e.g. :func:`dot_dyadic_scale`; broadcasts against ``uv[..., 0]``.
    tone_table : DotToneTable or None, keyword-only
        From :func:`dot_tone_table`; None keeps the paper's blend.

    Returns
    -------
    (...) ndarray in [0, 1]; float64, or float32 if the inputs are float32.
    """
    if tone_table is not None and not isinstance(tone_table, DotToneTable):
        raise TypeError(
            f"tone_table: expected a DotToneTable from dot_tone_table(), got {describe(tone_table)}"
        )
    dt = result_dtype(uv, s)
    uv = _uv("uv", uv, dt)
    s = real("s", s, dt)
    broadcast(uv_u=uv[..., 0], s=s)
    cdf = np.zeros((0, 0)) if tone_table is None else tone_table.cdf
    cdf = Whole(np.ascontiguousarray(cdf, dtype=np.float64))
    return elementwise(dot_threshold.scalar, dt, uv[..., 0], uv[..., 1], s, cdf)
