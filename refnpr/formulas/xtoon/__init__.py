"""X-Toon: tone-detail maps, the 2D toon lookup and normal blending (Barla et al. 2006).

Barla, Thollot, Markosian, *X-Toon: An Extended Toon Shader*, NPAR 2006. Section 3 extends the 1D
toon texture with a second "detail" axis D in [0, 1] chosen per fragment by an attribute map
(depth, focus, orientation, highlight); section 4 blends the shading normal towards the normal of
an abstracted shape. Conventions (``docs/paper-notes.md``, "Barla et al. 2006 (X-Toon)"): a 2D
toon texture ``(rows, cols[, C])`` has its **row index growing with D** (row 0: D = 0, the most
abstract ramp) and its **column index growing with tone**, texels at their centres; the paper's
figures draw D = 1 at the top (``image[::-1]`` reads such a picture). The texture builders (Figs.
7-11) live in ``textures`` and the abstracted normal fields (Fig. 5) in ``shapes``, both
re-exported here.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import clip01
from refnpr.device.vectors import unit_scaled

from .._face import Whole, elementwise, face
from .._validate import as_float, as_vectors, check_bool, check_scalar, describe, result_dtype
from . import shapes, textures
from .shapes import *  # noqa: F403
from .textures import *  # noqa: F403

__all__ = [
    "tone",
    "detail_depth",
    "focus_constants",
    "detail_focus",
    "detail_orientation",
    "detail_highlight",
    "toon_lookup",
    "blend_normals",
    *textures.__all__,
    *shapes.__all__,
]

_R_HINT = (
    "r is the ratio z_max / z_min of X-Toon sec. 3.1 and must exceed 1 "
    "(the coarsest detail is reached at z_max = r * z_min)"
)


#: Distances are clamped to at least this before the log of sec. 3.1 (a distance of 0, a
#: vertex at the eye, has no log; it gets D = 1).
TINY = 1e-9


def _check_depth(name: str, z) -> np.ndarray:
    arr = as_float(name, z)
    bad = np.isnan(arr) | (arr <= 0)
    if np.any(bad):
        i = int(np.flatnonzero(np.ravel(bad))[0])
        raise ValueError(
            f"{name}: expected positive distances (NaN not allowed, +inf allowed), got "
            f"{np.ravel(arr)[i]} at flat index {i}; mask background and points behind the eye "
            "before computing detail"
        )
    return arr


def _check_no_nan(name: str, value) -> np.ndarray:
    arr = as_float(name, value)
    if np.any(np.isnan(arr)):
        i = int(np.flatnonzero(np.isnan(np.ravel(arr)))[0])
        raise ValueError(f"{name}: must not contain NaN, got NaN at flat index {i}; mask it first")
    return arr


@njit
def _tone(n_dot_l, half_lambert):
    if half_lambert:
        return 0.5 * (n_dot_l + 1.0)  # half-Lambert (Valve): n.l mapped to [0, 1]
    return clip01(n_dot_l)  # sec. 3: tone from n.l, clamped


@face(_tone)
def tone(n_dot_l, *, half_lambert: bool = False) -> np.ndarray:
    """The tone coordinate of the 2D toon texture, X-Toon sec. 3: n . l clamped to [0, 1].

    Parameters
    ----------
    n_dot_l : (...) float
        Dot product of the unit shading normal and the unit direction towards the light.
    half_lambert : bool, keyword-only
        (n . l + 1) / 2 instead (half-Lambert, Valve; refnpr's option): the whole texture width
        over the sphere of normals.

    Returns
    -------
    (...) float64, or float32 if ``n_dot_l`` is float32
    """
    half_lambert = check_bool("half_lambert", half_lambert)
    c = _check_no_nan("n_dot_l", n_dot_l)
    return elementwise(tone.scalar, result_dtype(c), c, half_lambert)


@njit
def _detail_depth(z, z_min, log_r):
    z = max(z, TINY)
    return clip01(1.0 - math.log(z / z_min) / log_r)  # sec. 3.1: 1 - log_r; footnote 1


@face(_detail_depth)
def detail_depth(z, z_min: float, r: float) -> np.ndarray:
    """Depth-based (LOA / aerial perspective) detail, X-Toon sec. 3.1.

    D = 1 - log_r(z / z_min), clamped to [0, 1]: D = 1 up to z_min, D = 0 from z_max = r * z_min on,
    logarithmic in between (to account for perspective).

    ``detail_depth.scalar(z, z_min, log_r)`` is the device function (``log_r = log(r)``, a frame
    constant); it clamps z to at least ``TINY`` (1e-9) first.

    Parameters
    ----------
    z : (...) float
        View-axis distance (distance along the focal axis, Fig. 2b; the G-buffer ``depth``
        channel), > 0. ``+inf`` gives D = 0.
    z_min : float
        Distance at which detail starts to decrease, > 0.
    r : float
        Scale factor, > 1; the coarsest detail is reached at z_max = r * z_min.

    Returns
    -------
    D : (...) float64, or float32 if ``z`` is float32
    """
    z_min = check_scalar("z_min", z_min, lo=0.0, lo_open=True, hint="z_min is a distance")
    r = check_scalar("r", r, lo=1.0, lo_open=True, hint=_R_HINT)
    z = _check_depth("z", z)
    return elementwise(detail_depth.scalar, result_dtype(z), z, z_min, float(np.log(r)))


def focus_constants(z_focus: float, z_min: float, r: float) -> tuple[float, ...]:
    """The frame constants of :func:`detail_focus`'s device function: ``(z_c, z_min^-,
    z_min^+, log(z_max^- / z_min^-), log(z_max^+ / z_min^+))`` with z_min^± = z_c ± z_min and
    z_max^± = z_c ± r z_min (X-Toon sec. 3.1). Validated as :func:`detail_focus`'s arguments."""
    z_focus = check_scalar("z_focus", z_focus, lo=0.0, lo_open=True, hint="z_focus is a distance")
    z_min = check_scalar("z_min", z_min, lo=0.0, lo_open=True, hint="z_min is a distance")
    r = check_scalar("r", r, lo=1.0, lo_open=True, hint=_R_HINT)
    if not z_focus - r * z_min > 0.0:
        raise ValueError(
            f"z_focus - r*z_min: expected > 0 (X-Toon footnote 2: 0 < z_max^- = z_c - r*z_min), "
            f"got z_focus={z_focus}, r={r}, z_min={z_min} -> {z_focus - r * z_min}; "
            "move the focus point further away or reduce z_min or r"
        )
    return (
        z_focus,
        z_focus - z_min,
        z_focus + z_min,
        float(np.log((z_focus - r * z_min) / (z_focus - z_min))),
        float(np.log((z_focus + r * z_min) / (z_focus + z_min))),
    )


@njit
def _detail_focus(z, f):
    z_c, z_min_near, z_min_far, log_near, log_far = f
    z = max(z, TINY)
    if z < z_c:  # sec. 3.1, depth of field: 1 - log(z / z_min^-) / log(z_max^- / z_min^-)
        return clip01(1.0 - math.log(z / z_min_near) / log_near)
    return clip01(1.0 - math.log(z / z_min_far) / log_far)  # the far branch, same form


@face(_detail_focus)
def detail_focus(z, z_focus: float, z_min: float, r: float) -> np.ndarray:
    """Depth-of-field detail around a focus distance, X-Toon sec. 3.1.

    With z_min^± = z_c ± z_min and z_max^± = z_c ± r z_min::

        D = 1 - log(z / z_min^-) / log(z_max^- / z_min^-)   for z < z_c
        D = log(z / z_max^+) / log(z_min^+ / z_max^+)       for z > z_c

    clamped to [0, 1]: D = 1 within z_min of the focus, 0 beyond r * z_min from it. (Both branches
    are the same expression 1 - log(z / z_min^±) / log(z_max^± / z_min^±); at z = z_c, D = 1.)

    ``detail_focus.scalar(z, f)`` is the device function, ``f`` the frame constants of
    :func:`focus_constants`; it clamps z to at least ``TINY`` (1e-9) first.

    Parameters
    ----------
    z : (...) float
        Euclidean distance from the eye (Fig. 2a), > 0.
    z_focus : float
        z_c, the eye distance of the focus point c.
    z_min : float
        Half-width of the sharp region, > 0.
    r : float
        > 1; detail reaches 0 at distance r * z_min from the focus.

    Raises
    ------
    ValueError
        If z_focus - r * z_min <= 0 (footnote 2 requires 0 < z_max^-).

    Returns
    -------
    D : (...) float64, or float32 if ``z`` is float32
    """
    f = focus_constants(z_focus, z_min, r)
    z = _check_depth("z", z)
    return elementwise(detail_focus.scalar, result_dtype(z), z, f)


@njit
def _detail_orientation(n_dot_v, r):
    c = min(max(n_dot_v, -1.0), 1.0)
    return min(abs(c), 1.0) ** r  # sec. 3.2: |n.v|^r


@face(_detail_orientation)
def detail_orientation(n_dot_v, r: float) -> np.ndarray:
    """Near-silhouette detail D = |n . v|^r, X-Toon sec. 3.2.

    Parameters
    ----------
    n_dot_v : (...) float
        Dot product of the unit normal and the unit view vector; clipped to [-1, 1] first
        (interpolated vectors can overshoot slightly).
    r : float
        >= 0, magnitude of the effect (r = 0 gives D = 1 everywhere).

    Returns
    -------
    D : (...) float in [0, 1]; 1 facing the camera, 0 at the silhouette.
    """
    r = check_scalar("r", r, lo=0.0, hint="X-Toon sec. 3.2 requires r >= 0")
    c = _check_no_nan("n_dot_v", n_dot_v)
    return elementwise(detail_orientation.scalar, result_dtype(c), c, r)


@njit
def _detail_highlight(v_dot_r, s, one_sided):
    c = min(max(v_dot_r, -1.0), 1.0)
    base = max(c, 0.0) if one_sided else abs(c)
    return min(base, 1.0) ** s  # sec. 3.2: |v.r|^s (Phong)


@face(_detail_highlight)
def detail_highlight(v_dot_r, s: float, *, one_sided: bool = False) -> np.ndarray:
    """Highlight detail D = |v . r|^s (Phong), X-Toon sec. 3.2.

    Parameters
    ----------
    v_dot_r : (...) float
        Dot product of the unit view vector (surface to eye) and the unit reflection of the light
        vector, r = 2 (n . l) n - l. Clipped to [-1, 1].
    s : float
        Shininess, >= 1 (sec. 3.2).
    one_sided : bool
        The paper's |v . r| also gives D near 1 where v . r is near -1 (the eye opposite the mirror
        direction). ``one_sided=True`` uses max(v . r, 0)^s, the usual Phong lobe.

    Returns
    -------
    D : (...) float in [0, 1]
    """
    s = check_scalar("s", s, lo=1.0, hint="X-Toon sec. 3.2 requires shininess s >= 1")
    one_sided = check_bool("one_sided", one_sided)
    c = _check_no_nan("v_dot_r", v_dot_r)
    return elementwise(detail_highlight.scalar, result_dtype(c), c, s, one_sided)


@njit
def _toon_lookup(texels, rows, cols, tone, detail):
    # sec. 3: bilinear, edge-clamped lookup (texel centres, GL_LINEAR + CLAMP_TO_EDGE); the
    # texel offsets are unsigned (non-negative by construction): no wraparound checks
    tx = min(max(clip01(tone) * cols - 0.5, 0.0), cols - 1.0)
    ty = min(max(clip01(detail) * rows - 0.5, 0.0), rows - 1.0)
    j0 = min(int(math.floor(tx)), max(cols - 2, 0))
    i0 = min(int(math.floor(ty)), max(rows - 2, 0))
    j1 = min(j0 + 1, cols - 1)
    i1 = min(i0 + 1, rows - 1)
    fx = tx - j0
    fy = ty - i0
    a = (
        np.uint64((i0 * cols + j0) * 4),
        np.uint64((i0 * cols + j1) * 4),
        np.uint64((i1 * cols + j0) * 4),
        np.uint64((i1 * cols + j1) * 4),
    )
    return (
        _bilerp(texels, a, np.uint64(0), fx, fy),
        _bilerp(texels, a, np.uint64(1), fx, fy),
        _bilerp(texels, a, np.uint64(2), fx, fy),
        _bilerp(texels, a, np.uint64(3), fx, fy),
    )


@njit
def _bilerp(texels, a, c, fx, fy):
    """Channel ``c`` between the texels at flat offsets ``a = (a00, a01, a10, a11)``."""
    top = texels[a[0] + c] * (1.0 - fx) + texels[a[1] + c] * fx
    bottom = texels[a[2] + c] * (1.0 - fx) + texels[a[3] + c] * fx
    return top * (1.0 - fy) + bottom * fy


@face(_toon_lookup)
def toon_lookup(texture, tone, detail) -> np.ndarray:
    """Bilinear, edge-clamped lookup in a 2D toon texture, X-Toon sec. 3.

    ``toon_lookup.scalar(texels, rows, cols, tone, detail)`` is the device function: ``texels``
    the (rows, cols, 4) RGBA texture as a flat C-ordered float64 array; it returns the 4
    channels.

    Parameters
    ----------
    texture : (rows, cols) or (rows, cols, C) float, rows, cols, C >= 1
        Row index grows with detail D (row 0 is D = 0), column index with tone. Integer textures
        are read as float64 without rescaling.
    tone : (...) float
        Tone coordinate in [0, 1] (e.g. n . l clamped, or (n . l + 1) / 2), clamped.
    detail : (...) float
        D in [0, 1], clamped. ``tone`` and ``detail`` broadcast together.

    Returns
    -------
    (...) or (..., C) float64, float32 if texture, tone and detail are all float32.

    Notes
    -----
    Texel (i, j) sits at tone (j + 0.5) / cols and D (i + 0.5) / rows (OpenGL ``GL_LINEAR`` with
    ``GL_CLAMP_TO_EDGE``), so tone = 0 and D = 0 return the corner texel exactly.
    """
    tex = as_float("texture", texture, finite=True)
    if tex.ndim not in (2, 3) or tex.shape[0] < 1 or tex.shape[1] < 1:
        raise ValueError(
            f"texture: expected shape (rows, cols) or (rows, cols, C) with rows, cols >= 1, got "
            f"{describe(tex)}; a 1D ramp must be turned into a 2D texture first (e.g. "
            "ramp[None, :] or a toon_texture_* builder)"
        )
    if tex.ndim == 3 and tex.shape[2] < 1:
        raise ValueError(
            f"texture: expected shape (rows, cols, C) with C >= 1 channels, got shape {tex.shape}; "
            "pass a (rows, cols) gray texture or give it at least one channel"
        )
    u = _check_no_nan("tone", tone)
    v = _check_no_nan("detail", detail)
    dt = result_dtype(tex, u, v)
    rows, cols = tex.shape[:2]
    planes = tex[..., None] if tex.ndim == 2 else tex
    parts = []
    for k in range(0, planes.shape[2], 4):  # four channels at a time
        chunk = np.zeros((rows, cols, 4))
        width = min(4, planes.shape[2] - k)
        chunk[..., :width] = planes[..., k : k + width]
        rgba = elementwise(toon_lookup.scalar, dt, Whole(chunk.reshape(-1)), rows, cols, u, v)
        parts.append(rgba[..., :width])
    out = np.concatenate(parts, axis=-1)
    return out[..., 0] if tex.ndim == 2 else out


@njit
def _blend_normals(n, n_abstract, weight, normalize):
    a = unit_scaled(n)
    b = unit_scaled(n_abstract)
    w = weight
    m = ((1 - w) * a[0] + w * b[0], (1 - w) * a[1] + w * b[1], (1 - w) * a[2] + w * b[2])
    if not normalize:
        return m  # sec. 4: the linear blend (interpolated, then normalized)
    norm = math.sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2])
    if norm > _TINY_FLOAT:  # renormalized per pixel (sec. 4)
        return (m[0] / norm, m[1] / norm, m[2] / norm)
    return a if w < 0.5 else b


#: The smallest normal float64.
_TINY_FLOAT = float(np.finfo(np.float64).tiny)


def _unit(name: str, value) -> np.ndarray:
    arr = as_vectors(name, value, 3, finite=True, hint="; pass 3D vectors in the last axis")
    zero = np.all(arr == 0, axis=-1)
    if np.any(zero):
        i = int(np.flatnonzero(np.ravel(zero))[0])
        raise ValueError(
            f"{name}: expected non-zero vectors, got a zero vector at index {i}; "
            "repair degenerate normals before blending"
        )
    return arr


@face(_blend_normals)
def blend_normals(n, n_abstract, weight, *, normalize: bool = True) -> np.ndarray:
    """Blend the shading normal towards an abstracted shape's normal, X-Toon sec. 4.

    ``normalize((1 - weight) * n_hat + weight * n_abstract_hat)`` where ``_hat`` means normalized.
    The paper blends linearly per vertex (vertex shader) and renormalizes per pixel after
    interpolation; ``normalize=False`` returns the unnormalized per-vertex blend for that order of
    operations (interpolate it, then normalize).

    ``blend_normals.scalar(n, n_abstract, weight, normalize)`` is the device function (vectors
    as 3-tuples).

    Parameters
    ----------
    n, n_abstract : (..., 3) float
        Original and abstracted normals (any non-zero length; normalized first).
    weight : float or (...) float
        Shape-abstraction weight in [0, 1] (0: original normal, 1: abstracted normal).
    normalize : bool
        Renormalize the blend (default).

    Returns
    -------
    (..., 3) unit vectors (or the raw blend), float64 or float32 if all inputs are float32.

    Notes
    -----
    Where the blend vanishes (opposite normals at weight 0.5) the result is ``n_hat`` for
    weight < 0.5 and ``n_abstract_hat`` otherwise.
    """
    a = _unit("n", n)
    b = _unit("n_abstract", n_abstract)
    w = as_float("weight", weight, finite=True)
    if np.any((w < 0) | (w > 1)):
        raise ValueError(
            f"weight: expected values in [0, 1], got {describe(w)} (min {w.min()}, max {w.max()}); "
            "0 keeps the original normals, 1 uses the abstracted ones"
        )
    dt = result_dtype(a, b, w) if isinstance(weight, np.ndarray) else result_dtype(a, b)
    return elementwise(
        blend_normals.scalar,
        dt,
        (a[..., 0], a[..., 1], a[..., 2]),
        (b[..., 0], b[..., 1], b[..., 2]),
        w,
        check_bool("normalize", normalize),
    )
