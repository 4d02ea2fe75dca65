"""X-Toon: tone-detail maps, the 2D toon lookup and normal blending (Barla et al. 2006).

Barla, Thollot, Markosian, *X-Toon: An Extended Toon Shader*, NPAR 2006. Section 3 extends the 1D
toon texture with a second "detail" axis D in [0, 1] chosen per fragment by an attribute map
(depth, focus, orientation, highlight); section 4 blends the shading normal towards the normal of
an abstracted shape.

Conventions used throughout (see ``docs/paper-notes.md``, "Barla et al. 2006 (X-Toon)"):

- ``detail_depth`` takes the **view-axis distance** (the G-buffer ``depth`` channel: distance along
  the focal axis, sec. 3.1 and Fig. 2b); ``detail_focus`` takes the **Euclidean distance to the
  eye** (Fig. 2a), as the paper prefers for depth-of-field. Both clamp D to [0, 1] (the paper
  assumes z_min <= z <= z_max, footnote 1).
- A 2D toon texture is an array ``(rows, cols)`` or ``(rows, cols, C)``: the **row index grows with
  D** (row 0 holds D = 0, the most abstract tone ramp; the last row holds D = 1, full detail) and the
  **column index grows with tone** (column 0 is the darkest tone). The paper's figures draw D = 1 at
  the top; to use such a picture stored with row 0 on top, pass ``image[::-1]``.
- Texels are sampled at their centres, (j + 0.5) / cols along tone and (i + 0.5) / rows along D,
  bilinearly and clamped to the edge (OpenGL ``GL_LINEAR`` + ``GL_CLAMP_TO_EDGE``).

The texture builders (paper's recipes, Figs. 7-11) live in ``textures`` and the abstracted normal
fields (Fig. 5) in ``shapes``; both are re-exported here.
"""

from __future__ import annotations

import numpy as np

from .._shading_checks import unit_vectors
from .._validate import as_float, check_scalar, describe, result_dtype
from .shapes import (
    cylinder_normals,
    ellipsoid_normals,
    shape_frame,
    smoothed_normals,
    sphere_normals,
)
from .textures import (
    toon_texture_backlight,
    toon_texture_blur,
    toon_texture_fade,
    toon_texture_hue,
    toon_texture_levels,
    toon_texture_metal,
    toon_texture_plastic,
    toon_texture_receding,
)

__all__ = [
    "detail_depth",
    "detail_focus",
    "detail_orientation",
    "detail_highlight",
    "toon_lookup",
    "blend_normals",
    "toon_texture_blur",
    "toon_texture_levels",
    "toon_texture_receding",
    "toon_texture_fade",
    "toon_texture_hue",
    "toon_texture_backlight",
    "toon_texture_plastic",
    "toon_texture_metal",
    "smoothed_normals",
    "ellipsoid_normals",
    "cylinder_normals",
    "sphere_normals",
    "shape_frame",
]

_R_HINT = (
    "r is the ratio z_max / z_min of X-Toon sec. 3.1 and must exceed 1 "
    "(the coarsest detail is reached at z_max = r * z_min)"
)


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


def detail_depth(z, z_min: float, r: float) -> np.ndarray:
    """Depth-based (LOA / aerial perspective) detail, X-Toon sec. 3.1.

    D = 1 - log_r(z / z_min), clamped to [0, 1]: D = 1 up to z_min, D = 0 from z_max = r * z_min on,
    logarithmic in between (to account for perspective).

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
    dt = result_dtype(z)
    with np.errstate(divide="ignore"):
        D = 1.0 - np.log(z / dt.type(z_min)) / dt.type(
            np.log(r)
        )  # sec. 3.1: D = 1 - log_r(z/z_min)
    return np.clip(D, 0.0, 1.0).astype(dt, copy=False)  # footnote 1: z_min <= z <= z_max


def detail_focus(z, z_focus: float, z_min: float, r: float) -> np.ndarray:
    """Depth-of-field detail around a focus distance, X-Toon sec. 3.1.

    With z_min^± = z_c ± z_min and z_max^± = z_c ± r z_min::

        D = 1 - log(z / z_min^-) / log(z_max^- / z_min^-)   for z < z_c
        D = log(z / z_max^+) / log(z_min^+ / z_max^+)       for z > z_c

    clamped to [0, 1]: D = 1 within z_min of the focus, 0 beyond r * z_min from it. (Both branches
    are the same expression 1 - log(z / z_min^±) / log(z_max^± / z_min^±); at z = z_c, D = 1.)

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
    z_focus = check_scalar("z_focus", z_focus, lo=0.0, lo_open=True, hint="z_focus is a distance")
    z_min = check_scalar("z_min", z_min, lo=0.0, lo_open=True, hint="z_min is a distance")
    r = check_scalar("r", r, lo=1.0, lo_open=True, hint=_R_HINT)
    if not z_focus - r * z_min > 0.0:
        raise ValueError(
            f"z_focus - r*z_min: expected > 0 (X-Toon footnote 2: 0 < z_max^- = z_c - r*z_min), "
            f"got z_focus={z_focus}, r={r}, z_min={z_min} -> {z_focus - r * z_min}; "
            "move the focus point further away or reduce z_min or r"
        )
    z = _check_depth("z", z)
    dt = result_dtype(z)
    near = z < z_focus
    zmin_pm = np.where(near, dt.type(z_focus - z_min), dt.type(z_focus + z_min))
    log_ratio = np.where(
        near,
        dt.type(np.log((z_focus - r * z_min) / (z_focus - z_min))),
        dt.type(np.log((z_focus + r * z_min) / (z_focus + z_min))),
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        D = 1.0 - np.log(z / zmin_pm) / log_ratio  # sec. 3.1, depth-of-field, both branches
    return np.clip(D, 0.0, 1.0).astype(dt, copy=False)


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
    dt = result_dtype(c)
    return np.power(np.minimum(np.abs(c), 1.0), dt.type(r)).astype(dt, copy=False)  # sec. 3.2


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
    c = _check_no_nan("v_dot_r", v_dot_r)
    dt = result_dtype(c)
    base = np.maximum(c, 0.0) if one_sided else np.abs(c)
    return np.power(np.minimum(base, 1.0), dt.type(s)).astype(dt, copy=False)  # sec. 3.2, Phong


def toon_lookup(texture, tone, detail) -> np.ndarray:
    """Bilinear, edge-clamped lookup in a 2D toon texture, X-Toon sec. 3.

    Parameters
    ----------
    texture : (rows, cols) or (rows, cols, C) float
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
    u = _check_no_nan("tone", tone)
    v = _check_no_nan("detail", detail)
    dt = result_dtype(tex, u, v)
    u, v = np.broadcast_arrays(u.astype(dt), v.astype(dt))
    rows, cols = tex.shape[:2]
    tex = tex.astype(dt, copy=False)
    x = np.clip(np.clip(u, 0.0, 1.0) * cols - 0.5, 0.0, cols - 1)  # texel-centre convention
    y = np.clip(np.clip(v, 0.0, 1.0) * rows - 0.5, 0.0, rows - 1)
    j0 = np.minimum(np.floor(x).astype(np.intp), max(cols - 2, 0))
    i0 = np.minimum(np.floor(y).astype(np.intp), max(rows - 2, 0))
    j1 = np.minimum(j0 + 1, cols - 1)
    i1 = np.minimum(i0 + 1, rows - 1)
    fx = (x - j0).astype(dt)
    fy = (y - i0).astype(dt)
    if tex.ndim == 3:
        fx = fx[..., None]
        fy = fy[..., None]
    top = tex[i0, j0] * (1 - fx) + tex[i0, j1] * fx
    bottom = tex[i1, j0] * (1 - fx) + tex[i1, j1] * fx
    return (top * (1 - fy) + bottom * fy).astype(dt, copy=False)


def _unit(name: str, value) -> np.ndarray:
    arr = as_float(name, value, finite=True)
    if arr.ndim < 1 or arr.shape[-1] != 3:
        raise ValueError(
            f"{name}: expected shape (..., 3), got {describe(arr)}; pass 3D vectors in the last axis"
        )
    zero = np.all(arr == 0, axis=-1)
    if np.any(zero):
        i = int(np.flatnonzero(np.ravel(zero))[0])
        raise ValueError(
            f"{name}: expected non-zero vectors, got a zero vector at index {i}; "
            "repair degenerate normals before blending"
        )
    return unit_vectors(arr)  # scaled first: no overflow or underflow of |v|


def blend_normals(n, n_abstract, weight, *, normalize: bool = True) -> np.ndarray:
    """Blend the shading normal towards an abstracted shape's normal, X-Toon sec. 4.

    ``normalize((1 - weight) * n_hat + weight * n_abstract_hat)`` where ``_hat`` means normalized.
    The paper blends linearly per vertex (vertex shader) and renormalizes per pixel after
    interpolation; ``normalize=False`` returns the unnormalized per-vertex blend for that order of
    operations (interpolate it, then normalize).

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
    a, b, w = a.astype(dt), b.astype(dt), w.astype(dt)[..., None]
    m = (1 - w) * a + w * b  # sec. 4: linear blend of the two normals
    if not normalize:
        return m.astype(dt, copy=False)
    norm = np.linalg.norm(m, axis=-1, keepdims=True)
    tiny = np.finfo(dt).tiny
    fallback = np.where(w < 0.5, a, b)
    out = np.where(norm > tiny, m / np.maximum(norm, tiny), fallback)  # renormalized per pixel
    return out.astype(dt, copy=False)
