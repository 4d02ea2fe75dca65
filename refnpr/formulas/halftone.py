"""Freudenberg, Masuch, Strothotte 2002, *Real-Time Halftoning: A Primitive For
Non-Photorealistic Shading* (Eurographics Workshop on Rendering 2002).

Thresholding a target intensity against a halftone screen held in texture space (sec. 3), stroke
maps that store ordered stroke layers in one screen (sec. 4.2), a 1D engraving screen (sec. 4.1),
indication mapping and per-stroke lighting (sec. 5).

Conventions (see ``docs/paper-notes.md``, "Freudenberg et al. 2002"): screens, intensities and
outputs are in [0, 1] with 0 = black and 1 = white. A screen value g is drawn black while
``g + intensity <= 1``, so darker screen values stay black up to lighter intensities. Inputs are
finite reals whose shapes broadcast; float32 in -> float32 out, else float64.

The per-sample formulas are scalar device functions (``f.scalar``) that the ``halftone`` style's
kernel calls for every sample, with numpy faces (:mod:`refnpr.formulas._face`) computing in
float64; the stroke-map encoding runs per texel in the layers' float type. The engraving ramp and
the tone curve of the smooth threshold are numpy.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit
from refnpr.device.scalars import clip01
from refnpr.device.vectors import dot, unit_scaled

from ._face import Whole, elementwise, face
from ._shading_checks import broadcast, check_range, frac, real, reals, scaled_lengths, trailing
from ._validate import check_bool, check_int, check_scalar, describe, result_dtype

__all__ = [
    "binary_threshold",
    "smooth_threshold",
    "smooth_threshold_tone",
    "stroke_levels",
    "encode_stroke_map",
    "decode_stroke_map",
    "layer_onsets",
    "apply_indication",
    "sample_indication",
    "tangent_frame",
    "stroke_lighting",
    "engraving_screen",
    "engraving_ramp",
]

_PROFILES = ("ramp", "triangle")


@njit
def _binary_threshold(s, x):
    tmp = s + (x - 0.5)  # sec. 3.1: add(tex, col - 0.5)
    return 1.0 if tmp > 0.5 else 0.0  # sec. 3.1: mux(tmp, 0, 1)


@face(_binary_threshold)
def binary_threshold(screen, intensity) -> np.ndarray:
    """Binary threshold of Freudenberg sec. 3.1 in its register-combiner (mux) form.

    ``tmp = screen + (intensity - 0.5)``; ``out = mux(tmp, 0, 1) = 0 if tmp <= 0.5 else 1``, i.e.
    white where ``screen + intensity > 1``. With a screen uniform on [0, 1] the white fraction is
    the intensity.

    Parameters
    ----------
    screen : array_like in [0, 1]
        Halftone screen sampled at the pixel (texture ``tex``).
    intensity : array_like
        Target intensity (``col``); broadcasts against ``screen``.

    ``binary_threshold.scalar(s, x)`` is the device function.

    Returns
    -------
    ndarray of 0.0 / 1.0; float64, or float32 if the inputs are float32.
    """
    dt, scr, x = reals(screen=screen, intensity=intensity)
    return elementwise(binary_threshold.scalar, dt, scr, x)


@njit
def _smooth_threshold(s, x, c, centred):
    tmp = (1.0 - s - x) * c  # sec. 3.2: add(1 - tex, -col) * C
    top = 0.5 if centred else 1.0  # centred: the ramp straddles the binary threshold
    return clip01(top - tmp)  # sec. 3.2: 1 - tmp, clamped


@face(_smooth_threshold)
def smooth_threshold(screen, intensity, c: float = 4.0, *, centred: bool = False) -> np.ndarray:
    """Smooth threshold of Freudenberg sec. 3.2: ``clip(1 - c (1 - screen - intensity), 0, 1)``.

    A ramp of slope c instead of a step (antialiased strokes). The paper's form is one-sided: black
    at ``screen + intensity <= 1 - 1/c``, white at ``>= 1``; the grey ramp lies where the binary
    threshold is black, so the mean output exceeds the intensity by 1/(2c) (lighter; see
    :func:`smooth_threshold_tone`). ``centred=True`` centres the ramp on the binary threshold,
    ``clip(1/2 - c (1 - screen - intensity), 0, 1)``, which has no tone bias. Both tend to
    :func:`binary_threshold` as c grows.

    Parameters
    ----------
    screen : array_like in [0, 1]
        Halftone screen.
    intensity : array_like
        Target intensity; broadcasts against ``screen``.
    c : float > 0
        Slope (the paper uses 4).
    centred : bool, keyword-only
        Use the centred variant.

    ``smooth_threshold.scalar(s, x, c, centred)`` is the device function.

    Returns
    -------
    ndarray in [0, 1]; float64, or float32 if the inputs are float32 (computed in float64 and
    rounded once).
    """
    c = check_scalar("c", c, lo=0, lo_open=True, hint="c is the slope of the ramp, e.g. 4.0")
    dt, scr, x = reals(screen=screen, intensity=intensity)
    return elementwise(smooth_threshold.scalar, dt, scr, x, c, check_bool("centred", centred))


def smooth_threshold_tone(intensity, c: float = 4.0, *, centred: bool = False) -> np.ndarray:
    """Mean output of :func:`smooth_threshold` over a screen uniform on [0, 1] (tone curve).

    z = screen + I - 1 is uniform on [I - 1, I]; E is the mean of the clamped ramp over it.
    One-sided (the paper's): ``E = I + 1/(2c)`` for I in [0, 1 - 1/c] and ``I + (1 - I) -
    c (1 - I)^2 / 2`` above, so the bias E - I is 1/(2c) (lighter) over most of the range.
    Centred: ``E = I`` for I in [1/(2c), 1 - 1/(2c)].

    Parameters
    ----------
    intensity : array_like
        Target intensity.
    c : float > 0
        Slope.
    centred : bool, keyword-only
        Tone curve of the centred variant.

    Returns
    -------
    ndarray in [0, 1]; float64, or float32 if ``intensity`` is float32.
    """
    c = check_scalar("c", c, lo=0, lo_open=True, hint="c is the slope of the ramp, e.g. 4.0")
    dt = result_dtype(intensity)
    x = real("intensity", intensity, np.dtype(np.float64))
    centred = check_bool("centred", centred)
    off = 0.5 if centred else 1.0  # ramp clip(off + c z, 0, 1) runs over z in [lo, hi]
    lo, hi = -off / c, (1 - off) / c
    # z = screen + I - 1 is uniform on [I - 1, I]: white part + ramp part (midpoint x length)
    white = np.clip(x - np.maximum(x - 1, hi), 0, None)
    p = np.clip(x - 1, lo, hi)
    q = np.clip(x, lo, hi)
    ramp = (q - p) * (off + c * (p + q) / 2)
    return np.asarray(np.clip(white + ramp, 0, 1), dtype=dt)


def stroke_levels(m: int) -> np.ndarray:
    """Default grey levels of m stroke layers: ``g_i = i / m`` (layer 0 black).

    Layer i then appears below the intensity 1 - i/m, so m layers split the tone range evenly.

    Returns
    -------
    (m,) float64 ndarray
    """
    m = check_int("m", m, lo=1)
    return np.arange(m) / m


def _levels(levels, m: int) -> np.ndarray:
    if levels is None:
        return stroke_levels(m)
    g = real("levels", levels, np.dtype(np.float64))
    if g.shape != (m,):
        raise ValueError(f"levels: expected {m} grey levels (one per layer), got shape {g.shape}")
    if np.any(np.diff(g) <= 0) or g[0] < 0 or g[-1] >= 1:
        raise ValueError(
            f"levels: expected strictly increasing values in [0, 1), got {g.tolist()}; "
            "layer 0 is the darkest (usually 0) and each later layer lighter"
        )
    return g


@njit
def _encode_stroke_map(screen, ink, grey, one):
    return (one - ink) * screen + ink * grey  # sec. 4.2: layer i drawn over, in its grey g_i


@face(_encode_stroke_map)
def encode_stroke_map(layers, *, levels=None) -> np.ndarray:
    """Stroke-map encoding of Freudenberg sec. 4.2 (Fig. 3).

    Layer i (ink coverage, 1 = ink) is encoded with the grey range [g_i, 1]: its ink colour is
    g_i (layer 0 unscaled, black ink ranging to white; later layers compressed towards white). The
    layers are drawn over a white screen from the last (lightest) to the first (darkest) with
    alpha compositing, ``screen = (1 - alpha_i) screen + alpha_i g_i``, so darker layers lie on
    top.

    Parameters
    ----------
    layers : (m, ...) array or sequence of m (...) arrays, values in [0, 1]
        Ink coverage of each stroke layer (antialiased strokes have fractional coverage); layer 0
        is the darkest, drawn in the lightest regions already.
    levels : (m,) increasing values in [0, 1), keyword-only
        Ink grey of each layer; default :func:`stroke_levels`.

    ``encode_stroke_map.scalar(screen, ink, grey, one)`` is the device function of one layer
    drawn over ``screen`` (``one`` is 1 in the layers' float type: float32 layers encode in
    float32).

    Returns
    -------
    (...) ndarray screen in [0, 1]; float64, or float32 if the layers are float32.
    """
    if isinstance(layers, (list, tuple)):
        if not layers:
            raise ValueError("layers: got no stroke layers; pass at least one")
        dt, *arrs = reals(**{f"layers[{i}]": a for i, a in enumerate(layers)})
    else:
        dt, stack = reals(layers=layers)
        if stack.ndim == 0 or stack.shape[0] == 0:
            raise ValueError(
                f"layers: expected shape (m, ...) with m >= 1 layers, got {stack.shape}"
            )
        arrs = list(stack)
    for i, a in enumerate(arrs):
        check_range(f"layers[{i}]", a, 0.0, 1.0, "a layer holds ink coverage (0 = none, 1 = ink)")
    g = _levels(levels, len(arrs))
    screen = np.ones(np.broadcast_shapes(*(a.shape for a in arrs)), dtype=dt)
    one = dt.type(1)
    for i in range(len(arrs) - 1, -1, -1):  # sec. 4.2: lightest layer first, darkest last
        screen = elementwise(
            encode_stroke_map.scalar, dt, screen, arrs[i], dt.type(g[i]), one, compute=dt
        )
    return screen


def decode_stroke_map(screen, intensity, *, c: float | None = None, centred: bool = False):
    """Stroke-map decoding by threshold (Freudenberg sec. 4.2, Fig. 4).

    :func:`binary_threshold` (``c=None``) or :func:`smooth_threshold` with slope c. Layer i, ink
    grey g_i, is drawn black where ``g_i + intensity <= 1``: in the lightest regions only the
    darkest layer shows, and every layer visible at some intensity stays visible at all darker
    intensities (the output is non-decreasing in the intensity).

    Parameters
    ----------
    screen : (...) array in [0, 1]
        Stroke map (e.g. from :func:`encode_stroke_map`).
    intensity : (...) array
        Target intensity.
    c : float > 0 or None, keyword-only
        Smooth-threshold slope; None for the binary threshold.
    centred : bool, keyword-only
        Centred smooth threshold.

    Returns
    -------
    (...) ndarray in [0, 1]; float64, or float32 if the inputs are float32.
    """
    centred = check_bool("centred", centred)
    if c is None:
        return binary_threshold(screen, intensity)
    return smooth_threshold(screen, intensity, c, centred=centred)


def layer_onsets(levels) -> np.ndarray:
    """Intensity at and below which each stroke layer is drawn: ``1 - g_i`` (binary threshold).

    Parameters
    ----------
    levels : (m,) increasing values in [0, 1)
        Ink greys of the layers (e.g. :func:`stroke_levels`).

    Returns
    -------
    (m,) float64 ndarray, decreasing.
    """
    arr = real("levels", levels, np.dtype(np.float64))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"levels: expected a 1-D sequence of grey levels, got shape {arr.shape}")
    return 1 - _levels(arr, arr.size)


@njit
def _apply_indication(x, ind):
    return clip01(x + ind)  # sec. 5.1: the signed map offsets the intensity


@face(_apply_indication)
def apply_indication(intensity, indication) -> np.ndarray:
    """Indication mapping of Freudenberg sec. 5.1: ``clip(intensity + indication, 0, 1)``.

    The signed indication map offsets the target intensity: 0 leaves the default lighting,
    positive values lighten (fading strokes out), negative values darken.
    ``apply_indication.scalar(x, ind)`` is the device function.

    Parameters
    ----------
    intensity : array_like
        Target intensity.
    indication : array_like in [-1, 1]
        Signed indication value (a low-resolution map sampled at the pixel); broadcasts.

    Returns
    -------
    ndarray in [0, 1]; float64, or float32 if the inputs are float32.
    """
    dt, x, ind = reals(intensity=intensity, indication=indication)
    check_range("indication", ind, -1.0, 1.0, "the indication map holds signed values in [-1, 1]")
    return elementwise(apply_indication.scalar, dt, x, ind)


@njit
def _sample_indication(imap, u, v):
    rows, cols = imap.shape
    x = min(max(u * cols - 0.5, 0.0), cols - 1.0)  # texel centres at (i + 1/2) / size
    y = min(max(v * rows - 0.5, 0.0), rows - 1.0)
    x0 = min(np.int64(math.floor(x)), cols - 1)
    y0 = min(np.int64(math.floor(y)), rows - 1)
    x1 = min(x0 + 1, cols - 1)
    y1 = min(y0 + 1, rows - 1)
    fx = x - x0
    fy = y - y0
    top = imap[y0, x0] * (1.0 - fx) + imap[y0, x1] * fx
    bottom = imap[y1, x0] * (1.0 - fx) + imap[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy  # sec. 5.1: the low-resolution map at (u, v)


@face(_sample_indication)
def sample_indication(indication_map, uv) -> np.ndarray:
    """The indication map of Freudenberg sec. 5.1 at texture coordinates ``uv``: a
    low-resolution signed map over [0, 1]^2, sampled bilinearly with clamp-to-edge (texel
    centres at (i + 0.5) / size; u along columns, v along rows, row 0 at v = 0).

    ``sample_indication.scalar(imap, u, v)`` is the device function.

    Parameters
    ----------
    indication_map : (rows, cols) array in [-1, 1]
    uv : (..., 2) array

    Returns
    -------
    (...) float64 ndarray
    """
    imap = real("indication_map", indication_map, np.dtype(np.float64))
    if imap.ndim != 2 or imap.size == 0:
        raise ValueError(f"indication_map: expected a (rows, cols) map, got shape {imap.shape}")
    check_range("indication_map", imap, -1.0, 1.0, "an indication map holds signed values")
    uv = real("uv", uv, np.dtype(np.float64))
    trailing("uv", uv, 2, "texture coordinates (u, v)")
    imap = np.ascontiguousarray(imap)
    return elementwise(sample_indication.scalar, np.float64, Whole(imap), uv[..., 0], uv[..., 1])


#: How far from 1 the length of a normal given to :func:`tangent_frame` may be.
_UNIT_TOL = 1e-5


def _check_unit(name: str, vectors: np.ndarray) -> None:
    """Raise ``ValueError`` unless every (..., 3) vector of ``vectors`` has length 1 within
    :data:`_UNIT_TOL`."""
    big, _, scaled = scaled_lengths(vectors)
    length = (big * scaled)[..., 0]
    off = ~(np.abs(length - 1.0) <= _UNIT_TOL)
    if np.any(off):
        at = np.unravel_index(int(np.flatnonzero(off)[0]), off.shape)
        where = f" at index {tuple(map(int, at))}" if off.ndim else ""
        raise ValueError(
            f"{name}: expected unit vectors (length 1 within {_UNIT_TOL}), got "
            f"{vectors[at].tolist()} of length {float(length[at])!r}{where}; normalize it first "
            f"({name} / numpy.linalg.norm({name}, axis=-1, keepdims=True)) and leave out "
            "samples without a surface"
        )


_TINY_DET = 1e-20  # |det J| at or below this: no tangent frame (edge-on view, degenerate uv)
_TINY_LEN = 1e-30  # a tangent at or below this length: none


@njit
def _tangent_frame(n, dp_dx, dp_dy, duv_dx, duv_dy):
    dxu, dxv = duv_dx
    dyu, dyv = duv_dy
    det = dxu * dyv - dyu * dxv  # det J, J = [[du/dx, du/dy], [dv/dx, dv/dy]]
    ok = abs(det) > _TINY_DET
    inv = 1.0 / det if ok else 0.0
    p_u = (  # dP/du = (dP/dx dv/dy - dP/dy dv/dx) / det J
        (dp_dx[0] * dyv - dp_dy[0] * dxv) * inv,
        (dp_dx[1] * dyv - dp_dy[1] * dxv) * inv,
        (dp_dx[2] * dyv - dp_dy[2] * dxv) * inv,
    )
    p_v = (  # dP/dv = (dP/dy du/dx - dP/dx du/dy) / det J
        (dp_dy[0] * dxu - dp_dx[0] * dyu) * inv,
        (dp_dy[1] * dxu - dp_dx[1] * dyu) * inv,
        (dp_dy[2] * dxu - dp_dx[2] * dyu) * inv,
    )
    d = dot(p_u, n)  # Gram-Schmidt: T from dP/du against N
    t = (p_u[0] - d * n[0], p_u[1] - d * n[1], p_u[2] - d * n[2])
    t_len = math.sqrt(dot(t, t))
    if t_len > _TINY_LEN:
        t = (t[0] / t_len, t[1] / t_len, t[2] / t_len)
    else:
        t = (0.0, 0.0, 0.0)
    d1 = dot(p_v, n)  # B from dP/dv against N and T
    d2 = dot(p_v, t)
    b = (
        (p_v[0] - d1 * n[0]) - d2 * t[0],
        (p_v[1] - d1 * n[1]) - d2 * t[1],
        (p_v[2] - d1 * n[2]) - d2 * t[2],
    )
    b_len = math.sqrt(dot(b, b))
    if b_len > _TINY_LEN:
        b = (b[0] / b_len, b[1] / b_len, b[2] / b_len)
    else:
        b = (0.0, 0.0, 0.0)
    return t, b, ok and t_len > _TINY_LEN and b_len > _TINY_LEN


@njit
def _tangent_frame_flat(n, dp_dx, dp_dy, duv_dx, duv_dy):
    """:func:`_tangent_frame` as one flat tuple (T, B, valid as 1.0 / 0.0), for ``elementwise``."""
    t, b, valid = _tangent_frame(n, dp_dx, dp_dy, duv_dx, duv_dy)
    return t[0], t[1], t[2], b[0], b[1], b[2], 1.0 if valid else 0.0


@face(_tangent_frame)
def tangent_frame(normal, dp_dx, dp_dy, duv_dx, duv_dy):
    """The tangent frame (T, B) of the stroke lighting of Freudenberg sec. 5.2: unit vectors
    along +u and +v in the tangent plane of N, from screen derivatives of position and uv.

    ``[dP/dx dP/dy] = [dP/du dP/dv] J`` with ``J = [[du/dx, du/dy], [dv/dx, dv/dy]]``, so
    ``dP/du = (dP/dx dv/dy - dP/dy dv/dx) / det J`` and ``dP/dv = (dP/dy du/dx - dP/dx du/dy) /
    det J``; then Gram-Schmidt against N (T first, B against N and T; the handedness of (u, v)
    is kept). Invalid where ``|det J| <= 1e-20`` or a tangent's length is ``<= 1e-30``
    (edge-on views, degenerate uv).

    ``tangent_frame.scalar(n, dp_dx, dp_dy, duv_dx, duv_dy)`` is the device function (3- and
    2-tuples): ``(t, b, valid)``.

    The Gram-Schmidt step projects along N as given (the kernels pass the G-buffer's
    renormalized normal), which is a projection onto the tangent plane only for a unit N: the
    face refuses a normal whose length is not 1 within 1e-5 (a float32 unit vector's rounding is
    about 1e-7).

    Parameters
    ----------
    normal : (..., 3) array
        The unit normal N (length 1 within 1e-5; normalize it first).
    dp_dx, dp_dy : (..., 3) arrays
        dP/dx, dP/dy.
    duv_dx, duv_dy : (..., 2) arrays
        (du/dx, dv/dx) and (du/dy, dv/dy).

    Returns
    -------
    T, B : (..., 3) float64 unit vectors (0 where invalid); valid : (...) bool

    Raises
    ------
    ValueError
        For a normal that is not a unit vector (zero, or of another length), a shape that is
        not (..., 3) / (..., 2), shapes that do not broadcast, or NaN or inf.
    """
    dt = np.dtype(np.float64)
    arrays = {
        "normal": (real("normal", normal, dt), 3),
        "dp_dx": (real("dp_dx", dp_dx, dt), 3),
        "dp_dy": (real("dp_dy", dp_dy, dt), 3),
        "duv_dx": (real("duv_dx", duv_dx, dt), 2),
        "duv_dy": (real("duv_dy", duv_dy, dt), 2),
    }
    for name, (arr, size) in arrays.items():
        trailing(name, arr, size, "a vector per sample")
    broadcast(**{name: arr[..., 0] for name, (arr, _) in arrays.items()})
    _check_unit("normal", arrays["normal"][0])
    vectors = [tuple(arr[..., k] for k in range(size)) for arr, size in arrays.values()]
    out = elementwise(_tangent_frame_flat, dt, *vectors)
    return out[..., 0:3], out[..., 3:6], out[..., 6] > 0.0


@njit
def _stroke_lighting(nm, l, encoded, normalize):
    n = nm
    if encoded:  # sec. 5.2: the DOT3 expansion 2 rgb - 1
        n = (2.0 * nm[0] - 1.0, 2.0 * nm[1] - 1.0, 2.0 * nm[2] - 1.0)
    if normalize:
        n = unit_scaled(n)
    return clip01(dot(n, unit_scaled(l)))  # sec. 5.2: clip(N . L, 0, 1)


@face(_stroke_lighting)
def stroke_lighting(
    normal_map, light, *, encoded: bool = True, normalize: bool = False
) -> np.ndarray:
    """Individual stroke lighting of Freudenberg sec. 5.2: DOT3 bump mapping of a stroke normal map.

    ``clip(N . L, 0, 1)`` with N from the normal map (``2 rgb - 1`` when ``encoded``) and L the
    unit direction to the light in the same (tangent) space. Used as (or multiplied into) the
    target intensity, it thins a stroke on its lit side and keeps it on the shadowed side, so a
    stroke's width depends on the light direction.
    ``stroke_lighting.scalar(nm, l, encoded, normalize)`` is the device function (3-tuples).

    Parameters
    ----------
    normal_map : (..., 3) array
        Per-pixel stroke normals, RGB-encoded in [0, 1] if ``encoded`` else components in [-1, 1].
    light : (..., 3) array
        Direction to the light (normalized here; a zero vector gives 0).
    encoded : bool, keyword-only
        Decode ``2 rgb - 1`` first (the DOT3 texture encoding).
    normalize : bool, keyword-only
        Renormalize the decoded normals (DOT3 hardware does not, the default).

    Returns
    -------
    (...) ndarray in [0, 1]; float64, or float32 if the inputs are float32.
    """
    dt = result_dtype(normal_map, light)
    nm = real("normal_map", normal_map, dt)
    li = real("light", light, dt)
    trailing("normal_map", nm, 3, "a normal per pixel")
    trailing("light", li, 3, "a light direction")
    broadcast(normal_map=nm, light=li)
    n = (nm[..., 0], nm[..., 1], nm[..., 2])
    v = (li[..., 0], li[..., 1], li[..., 2])
    return elementwise(
        stroke_lighting.scalar,
        dt,
        n,
        v,
        check_bool("encoded", encoded),
        check_bool("normalize", normalize),
    )


def _profile(profile: str) -> str:
    if profile not in _PROFILES:
        raise ValueError(f"profile: expected one of {_PROFILES}, got {describe(profile)}")
    return profile


def engraving_screen(v, *, profile: str = "ramp") -> np.ndarray:
    """1D engraving screen of Freudenberg sec. 4.1 as a function of the line coordinate v.

    ``"ramp"``: the grey ramp of the paper's Fig. 2 repeated along v, ``Frac(v)``: lines grow from
    one side as the tone darkens. ``"triangle"``: ``|2 Frac(v) - 1|``, lines centred at
    Frac(v) = 1/2 that swell symmetrically (engraving). Both are uniform over a period, so
    thresholding preserves tone.

    Parameters
    ----------
    v : array_like
        Line coordinate (period 1; lines are iso-lines of v).
    profile : {"ramp", "triangle"}, keyword-only

    Returns
    -------
    ndarray in [0, 1]; float64, or float32 if ``v`` is float32.
    """
    profile = _profile(profile)
    dt = result_dtype(v)
    f = frac(real("v", v, dt))
    out = f if profile == "ramp" else np.abs(2 * f - 1)
    return np.asarray(out, dtype=dt)


def engraving_ramp(size: int = 256, *, profile: str = "ramp") -> np.ndarray:
    """The 1D engraving screen as a texture of ``size`` texels (values at texel centres).

    Sample it with linear filtering and repeat wrapping along v.

    Returns
    -------
    (size,) float64 ndarray in [0, 1]
    """
    size = check_int("size", size, lo=1)
    return engraving_screen((np.arange(size) + 0.5) / size, profile=_profile(profile))
