"""Local illumination terms: Veryovka 2002 eq. 1 and the toon ramp of Lake et al. 2000.

Veryovka eq. 1::

    I = m_a l_a + sum_i m_d f_d(N, L_i) l_i + sum_i m_s f_s(N, L_i, V) l_i

with f_d the Lambert term max(N.L, 0) and f_s a specular term. The paper does not say which
specular model it uses; refnpr offers Blinn-Phong (the default: the specular term of OpenGL's
fixed-function lighting) and Phong, both zero where N.L <= 0 (light behind the surface).

Vectors are arrays ``(..., 3)`` that broadcast against each other: ``normal (H, W, 3)`` with one
light ``(3,)`` gives ``(H, W)``; with L lights ``normal[..., None, :]`` and ``light (L, 3)`` give
``(H, W, L)``. ``light`` and ``view`` point *from the surface towards* the light and the eye.
Vectors are normalized here (``normalize=True``); a zero vector gives a zero term, not NaN.

Lake et al. 2000 (*Stylized rendering techniques for scalable real-time 3D animation*, NPAR)
shade with a 1D texture indexed by max(N.L, 0) and sampled with nearest filtering, so a ramp of
a few constant runs gives hard-edged n-tone shading: ``toon_ramp_texture`` builds such a ramp and
``toon_ramp`` looks it up.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit
from refnpr.device.vectors import dot, reflect, unit_scaled

from ._face import elementwise, face
from ._shading_checks import broadcast, check_range, real, trailing
from ._validate import as_float, check_bool, check_int, check_scalar, describe, result_dtype

__all__ = [
    "ambient",
    "diffuse",
    "specular_base",
    "specular",
    "illumination_term",
    "illumination",
    "toon_ramp_texture",
    "toon_ramp",
    "LUMA_709",
    "luminance",
]

_MODELS = ("blinn-phong", "phong")
#: Rec. 709 luminance weights of linear RGB.
LUMA_709 = (0.2126, 0.7152, 0.0722)


def _vectors(dtype: np.dtype, **named) -> list[tuple[np.ndarray, ...]]:
    """Each named (..., 3) array, checked and broadcast together, as a vector argument of
    ``elementwise`` (a tuple of its three components)."""
    out = []
    for name, value in named.items():
        arr = real(name, value, dtype)
        trailing(name, arr, 3, "a 3-vector per element")
        out.append(arr)
    broadcast(**{k: a[..., 0] for k, a in zip(named, out, strict=True)})
    return [(a[..., 0], a[..., 1], a[..., 2]) for a in out]


@njit
def _ambient(m_a, l_a):
    return m_a * l_a  # eq. 1: m_a l_a


@face(_ambient)
def ambient(m_a, l_a) -> np.ndarray:
    """Ambient term of Veryovka eq. 1: ``m_a * l_a``.

    Parameters
    ----------
    m_a, l_a : scalar or (C,) array
        Ambient material colour and ambient light colour.

    Returns
    -------
    scalar or (C,) ndarray, float64 (float32 if both are float32)
    """
    dt = result_dtype(m_a, l_a)
    m_a = real("m_a", m_a, dt)
    l_a = real("l_a", l_a, dt)
    broadcast(m_a=m_a, l_a=l_a)
    return elementwise(ambient.scalar, dt, m_a, l_a)


@njit
def _diffuse(n, l, normalize):
    if normalize:
        n = unit_scaled(n)
        l = unit_scaled(l)
    d = dot(n, l)
    f_d = d if d >= 0.0 else 0.0  # eq. 1: f_d = max(N.L, 0)
    if normalize and f_d > 1.0:
        f_d = 1.0  # unit vectors: N.L <= 1 up to rounding
    return f_d


@face(_diffuse)
def diffuse(normal, light, *, normalize: bool = True) -> np.ndarray:
    """Diffuse (Lambert) term of Veryovka eq. 1: ``f_d(N, L) = max(N.L, 0)``.

    ``diffuse.scalar(n, l, normalize)`` is the device function (vectors as 3-tuples).

    Parameters
    ----------
    normal : (..., 3) array
        Surface normals N.
    light : (..., 3) array
        Directions from the surface towards the light, L; broadcasts against ``normal``.
    normalize : bool, keyword-only
        Normalize N and L first (scaled by their largest component, so no overflow; zero
        vectors give 0) and clamp to 1 (the rounding of unit vectors).

    Returns
    -------
    (...) ndarray in [0, 1], float64 (float32 if the inputs are float32)
    """
    dt = result_dtype(normal, light)
    n, l = _vectors(dt, normal=normal, light=light)
    return elementwise(diffuse.scalar, dt, n, l, check_bool("normalize", normalize))


@njit
def _specular_base(n, l, v, phong, normalize):
    if normalize:
        n = unit_scaled(n)
        l = unit_scaled(l)
        v = unit_scaled(v)
    if phong:  # R = 2 (N.L) N - L
        b = dot(reflect(l, n, dot(n, l)), v)
    else:  # H = normalize(L + V)
        b = dot(n, unit_scaled((l[0] + v[0], l[1] + v[1], l[2] + v[2])))
    b = b if b >= 0.0 else 0.0
    if normalize and b > 1.0:
        b = 1.0
    return b


@face(_specular_base)
def specular_base(normal, light, view, *, model: str = "blinn-phong", normalize: bool = True):
    """The base of the specular term of Veryovka eq. 1, raised to the shininess by
    :func:`specular`: ``max(N.H, 0)`` with H = normalize(L + V) (Blinn-Phong) or ``max(R.V,
    0)`` with R = 2 (N.L) N - L (Phong); clamped to 1 when the vectors are normalized.

    ``specular_base.scalar(n, l, v, phong, normalize)`` is the device function.

    Parameters and returns as :func:`specular`.
    """
    if model not in _MODELS:
        raise ValueError(f"model: expected one of {_MODELS}, got {describe(model)}")
    dt = result_dtype(normal, light, view)
    n, l, v = _vectors(dt, normal=normal, light=light, view=view)
    return elementwise(
        specular_base.scalar, dt, n, l, v, model == "phong", check_bool("normalize", normalize)
    )


@njit
def _specular(n, l, v, shininess, phong, normalize):
    base = _specular_base(n, l, v, phong, normalize)
    if normalize:
        n = unit_scaled(n)
        l = unit_scaled(l)
    return base**shininess if dot(n, l) > 0.0 else 0.0  # eq. 1: f_s, 0 where N.L <= 0


@face(_specular)
def specular(
    normal, light, view, *, shininess: float, model: str = "blinn-phong", normalize: bool = True
) -> np.ndarray:
    """Specular term f_s(N, L, V) of Veryovka eq. 1 (the paper leaves the model open).

    ``model="blinn-phong"`` (default): ``max(N.H, 0)**shininess`` with H = normalize(L + V).
    ``model="phong"``: ``max(R.V, 0)**shininess`` with R = 2 (N.L) N - L.
    Both are 0 where N.L <= 0 (the light is behind the surface).

    ``specular.scalar(n, l, v, shininess, phong, normalize)`` is the device function.

    Parameters
    ----------
    normal, light, view : (..., 3) arrays
        Normal N, direction to the light L, direction to the eye V; broadcast together.
    shininess : float > 0, keyword-only
        Specular exponent.
    model : {"blinn-phong", "phong"}, keyword-only
    normalize : bool, keyword-only
        Normalize N, L and V first (zero vectors give 0).

    Returns
    -------
    (...) ndarray in [0, 1], float64 (float32 if the vector inputs are float32)
    """
    if model not in _MODELS:
        raise ValueError(f"model: expected one of {_MODELS}, got {describe(model)}")
    p = check_scalar("shininess", shininess, lo=0, lo_open=True, hint="use e.g. 32.0")
    dt = result_dtype(normal, light, view)
    n, l, v = _vectors(dt, normal=normal, light=light, view=view)
    return elementwise(
        specular.scalar, dt, n, l, v, p, model == "phong", check_bool("normalize", normalize)
    )


@njit
def _illumination_term(acc, m, f, l):
    return acc + m * f * l  # eq. 1: one light's term, m f l, added to the sum


@face(_illumination_term)
def illumination_term(acc, m, f, l) -> np.ndarray:
    """One term of the sums of Veryovka eq. 1 added to ``acc``: ``acc + m f l`` (a diffuse
    term m_d f_d l_i, or a specular one m_s f_s l_i), for one channel.

    ``illumination_term.scalar(acc, m, f, l)`` is the device function; kernels add each light's
    diffuse and then specular term, per channel, in that order.

    Returns
    -------
    ndarray of the broadcast shape, float64 (float32 if every input is float32)
    """
    dt = result_dtype(acc, m, f, l)
    arrays = {k: real(k, v, dt) for k, v in (("acc", acc), ("m", m), ("f", f), ("l", l))}
    broadcast(**arrays)
    return elementwise(illumination_term.scalar, dt, *arrays.values())


def _lights(name: str, value) -> list:
    if isinstance(value, (list, tuple)):
        if len(value) == 0:
            raise ValueError(f"{name}: got an empty sequence of lights; pass at least one term")
        return list(value)
    return [value]


def _colour(name: str, value, dtype: np.dtype) -> np.ndarray:
    arr = real(name, value, dtype)
    if arr.ndim > 1:
        raise ValueError(
            f"{name}: expected a scalar or a (C,) colour, got shape {arr.shape}; "
            "pass one colour per light as a list"
        )
    return arr


def illumination(f_d, f_s=None, *, m_a=0.0, l_a=0.0, m_d=1.0, m_s=1.0, l=1.0) -> np.ndarray:
    """Veryovka eq. 1 from precomputed terms: ``m_a l_a + sum_i m_d f_d_i l_i + sum_i m_s f_s_i l_i``.

    Parameters
    ----------
    f_d : (...) array, or a list of them (one per light)
        Diffuse terms (e.g. from :func:`diffuse`).
    f_s : same structure as ``f_d``, or None
        Specular terms (e.g. from :func:`specular`); None omits the specular sum.
    m_a, l_a, m_d, m_s : scalar or (C,) array, keyword-only
        Ambient material, ambient light, diffuse and specular material colours.
    l : scalar or (C,) array, or a list with one such colour per light, keyword-only
        Light colours; a single colour applies to every light.

    Returns
    -------
    (...) ndarray if every colour is a scalar, else (..., C); float64, or float32 if every array
    input is float32.
    """
    terms_d = _lights("f_d", f_d)
    terms_s = None if f_s is None else _lights("f_s", f_s)
    if terms_s is not None and len(terms_s) != len(terms_d):
        raise ValueError(
            f"f_s: expected {len(terms_d)} specular terms (one per diffuse term), got {len(terms_s)}"
        )
    colours_l = _lights("l", l) if isinstance(f_d, (list, tuple)) else [l]
    if len(colours_l) == 1:
        colours_l = colours_l * len(terms_d)
    if len(colours_l) != len(terms_d):
        raise ValueError(
            f"l: expected one light colour or {len(terms_d)} (one per light), got {len(colours_l)}"
        )
    arrays = [*terms_d, *(terms_s or []), m_a, l_a, m_d, m_s, *colours_l]
    dt = result_dtype(*arrays)
    named = (("m_a", m_a), ("l_a", l_a), ("m_d", m_d), ("m_s", m_s))
    m_a, l_a, m_d, m_s = (_colour(k, v, dt) for k, v in named)
    cl = [_colour(f"l[{i}]", c, dt) for i, c in enumerate(colours_l)]
    sizes = {c.shape[0] for c in (m_a, l_a, m_d, m_s, *cl) if c.ndim == 1}
    if len(sizes) > 1:
        raise ValueError(
            f"m_a, l_a, m_d, m_s, l: colours have different channel counts {sorted(sizes)}; "
            "give every colour the same number of channels (or a scalar)"
        )
    channels = next(iter(sizes)) if sizes else None
    rgb = channels is not None
    fd = [real(f"f_d[{i}]", x, dt) for i, x in enumerate(terms_d)]
    fs = [real(f"f_s[{i}]", x, dt) for i, x in enumerate(terms_s or [])]
    shape = broadcast(
        **{f"f_d[{i}]": x for i, x in enumerate(fd)}, **{f"f_s[{i}]": x for i, x in enumerate(fs)}
    )

    def lift(x: np.ndarray) -> np.ndarray:
        return x[..., None] if rgb else x

    shape = shape + ((channels,) if rgb else ())
    total = np.broadcast_to(ambient(m_a, l_a), shape).astype(np.float64)  # eq. 1: ambient
    for i in range(len(fd)):
        total = illumination_term(total, m_d, lift(fd[i]), cl[i])  # eq. 1: diffuse sum
        if fs:
            total = illumination_term(total, m_s, lift(fs[i]), cl[i])  # eq. 1: specular sum
    return np.asarray(total, dtype=dt)


def toon_ramp_texture(boundaries, tones, *, size: int = 256) -> np.ndarray:
    """A 1D toon ramp (Lake et al. 2000) with hard edges: ``len(boundaries) + 1`` constant runs.

    Texel i (centre ``(i + 0.5) / size``) holds ``tones[j]`` where j is the number of boundaries
    <= the texel centre. Boundaries are thus quantized to texel edges (multiples of 1 / size);
    Lake's two-tone default is ``boundaries=(0.5,)``.

    Parameters
    ----------
    boundaries : (n,) increasing values in [0, 1]
    tones : (n + 1,) or (n + 1, C) array
        Tone (or colour) of each run, darkest N.L first.
    size : int >= 1, keyword-only
        Number of texels.

    Returns
    -------
    (size,) or (size, C) ndarray, float64 (float32 if ``tones`` is float32)
    """
    size = check_int("size", size, lo=1)
    dt = result_dtype(tones)
    b = real("boundaries", boundaries, np.dtype(np.float64))
    if b.ndim != 1 or np.any(np.diff(b) < 0):
        raise ValueError(
            f"boundaries: expected a 1-D increasing sequence, got {describe(b)}; sort it"
        )
    check_range("boundaries", b, 0.0, 1.0, "boundaries are values of N.L")
    tones = real("tones", tones, dt)
    if tones.ndim not in (1, 2) or tones.shape[0] != b.size + 1:
        raise ValueError(
            f"tones: expected shape ({b.size + 1},) or ({b.size + 1}, C) for {b.size} boundaries, "
            f"got {tones.shape}; give one tone per run"
        )
    centres = (np.arange(size) + 0.5) / size
    return tones[np.searchsorted(b, centres, side="right")]


@njit
def _toon_ramp(n_dot_l, k):
    x = min(max(n_dot_l, 0.0), 1.0)  # nearest texel of clip(N.L, 0, 1), clamp-to-edge
    j = math.floor(x * k)
    return j if j < k - 1 else k - 1


@face(_toon_ramp)
def toon_ramp(n_dot_l, ramp) -> np.ndarray:
    """Lake et al. 2000 toon shading: nearest-texel lookup of ``max(N.L, 0)`` in a 1D ramp.

    The texture coordinate is ``x = clip(N.L, 0, 1)`` and the texel ``min(floor(x * K), K - 1)``
    (OpenGL ``GL_NEAREST`` with clamp-to-edge) for a ramp of K texels.
    ``toon_ramp.scalar(n_dot_l, k)`` is the device function: the texel index.

    Parameters
    ----------
    n_dot_l : (...) array
        N.L (unclamped values are fine).
    ramp : (K,) or (K, C) array
        The ramp texture, e.g. from :func:`toon_ramp_texture`.

    Returns
    -------
    (...) or (..., C) ndarray, float64 (float32 if both inputs are float32)
    """
    dt = result_dtype(n_dot_l, ramp)
    x = real("n_dot_l", n_dot_l, dt)
    ramp = real("ramp", ramp, dt)
    if ramp.ndim not in (1, 2) or ramp.shape[0] < 1:
        raise ValueError(
            f"ramp: expected a (K,) or (K, C) texture with K >= 1, got shape {ramp.shape}"
        )
    index = elementwise(toon_ramp.scalar, np.int64, x, ramp.shape[0])
    return np.asarray(ramp[index], dtype=dt)


@njit
def _luminance(r, g, b):
    return (r * 0.2126 + g * 0.7152) + b * 0.0722  # Rec. 709, summed r, g, then b


@face(_luminance)
def luminance(rgb) -> np.ndarray:
    """Rec. 709 luminance ``Y = 0.2126 R + 0.7152 G + 0.0722 B`` of linear RGB, in float64.

    Summed r, g, then b, every time: not ``rgb @ weights``, which BLAS may fuse (FMA) or reorder
    depending on the CPU, giving other bits on other machines (and whose worker threads spin
    after a large call, taking the cores from the numba kernels that follow).
    ``luminance.scalar(r, g, b)`` is the device function.

    Parameters
    ----------
    rgb : (..., C) float, C >= 3
        Finite linear colours (real numbers: integer and bool arrays are read as float64);
        channels past the third (alpha) are ignored.

    Returns
    -------
    (...) float64

    Raises
    ------
    TypeError
        For complex, string or object input.
    ValueError
        For another shape, or NaN or inf in ``rgb``.
    """
    a = as_float("rgb", rgb, finite=True)
    if a.ndim < 1 or a.shape[-1] < 3:
        raise ValueError(
            f"rgb: expected an array of shape (..., C) with C >= 3 channels, got shape {a.shape}"
        )
    return elementwise(luminance.scalar, np.float64, a[..., 0], a[..., 1], a[..., 2])
