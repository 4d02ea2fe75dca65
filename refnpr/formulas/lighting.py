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

import numpy as np

from ._shading_checks import broadcast, check_range, real, trailing, unit_vectors
from ._validate import check_int, check_scalar, describe, result_dtype

__all__ = [
    "ambient",
    "diffuse",
    "specular",
    "illumination",
    "toon_ramp_texture",
    "toon_ramp",
    "LUMA_709",
    "luminance",
]

_MODELS = ("blinn-phong", "phong")
#: Rec. 709 luminance weights of linear RGB.
LUMA_709 = (0.2126, 0.7152, 0.0722)


def _vectors(dtype: np.dtype, normalize: bool, **named) -> list[np.ndarray]:
    out = []
    for name, value in named.items():
        arr = real(name, value, dtype)
        trailing(name, arr, 3, "a 3-vector per element")
        out.append(unit_vectors(arr) if normalize else arr)
    broadcast(**dict(zip(named, out, strict=True)))
    return out


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=-1)


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
    return np.asarray(m_a * l_a, dtype=dt)  # eq. 1


def diffuse(normal, light, *, normalize: bool = True) -> np.ndarray:
    """Diffuse (Lambert) term of Veryovka eq. 1: ``f_d(N, L) = max(N.L, 0)``.

    Parameters
    ----------
    normal : (..., 3) array
        Surface normals N.
    light : (..., 3) array
        Directions from the surface towards the light, L; broadcasts against ``normal``.
    normalize : bool, keyword-only
        Normalize N and L first (zero vectors give 0).

    Returns
    -------
    (...) ndarray in [0, 1], float64 (float32 if the inputs are float32)
    """
    dt = result_dtype(normal, light)
    n, l = _vectors(dt, normalize, normal=normal, light=light)
    f_d = np.maximum(_dot(n, l), 0)  # eq. 1: f_d
    if normalize:
        f_d = np.minimum(f_d, 1)  # unit vectors: N.L <= 1 up to rounding
    return np.asarray(f_d, dtype=dt)


def specular(
    normal, light, view, *, shininess: float, model: str = "blinn-phong", normalize: bool = True
) -> np.ndarray:
    """Specular term f_s(N, L, V) of Veryovka eq. 1 (the paper leaves the model open).

    ``model="blinn-phong"`` (default): ``max(N.H, 0)**shininess`` with H = normalize(L + V).
    ``model="phong"``: ``max(R.V, 0)**shininess`` with R = 2 (N.L) N - L.
    Both are 0 where N.L <= 0 (the light is behind the surface).

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
    n, l, v = _vectors(dt, normalize, normal=normal, light=light, view=view)
    n_dot_l = _dot(n, l)
    if model == "phong":
        r = 2 * n_dot_l[..., None] * n - l
        base = _dot(r, v)
    else:
        h = unit_vectors(l + v)
        base = _dot(n, h)
    base = np.clip(base, 0, 1) if normalize else np.maximum(base, 0)
    f_s = np.where(n_dot_l > 0, base**p, 0)  # eq. 1: f_s
    return np.asarray(f_s, dtype=dt)


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
    m_a, l_a, m_d, m_s = (
        _colour(k, v, dt)
        for k, v in zip(("m_a", "l_a", "m_d", "m_s"), (m_a, l_a, m_d, m_s), strict=True)
    )
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

    total = np.zeros(shape + ((channels,) if rgb else ()), dtype=dt)
    total = total + m_a * l_a  # eq. 1: ambient
    for i in range(len(fd)):
        total = total + m_d * lift(fd[i]) * cl[i]  # eq. 1: diffuse sum
        if fs:
            total = total + m_s * lift(fs[i]) * cl[i]  # eq. 1: specular sum
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


def toon_ramp(n_dot_l, ramp) -> np.ndarray:
    """Lake et al. 2000 toon shading: nearest-texel lookup of ``max(N.L, 0)`` in a 1D ramp.

    The texture coordinate is ``x = clip(N.L, 0, 1)`` and the texel ``min(floor(x * K), K - 1)``
    (OpenGL ``GL_NEAREST`` with clamp-to-edge) for a ramp of K texels.

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
    k = ramp.shape[0]
    x = np.clip(x, 0, 1)
    index = np.minimum(np.floor(x * k), k - 1).astype(np.intp)
    return np.asarray(ramp[index], dtype=dt)


def luminance(rgb) -> np.ndarray:
    """Rec. 709 luminance ``Y = 0.2126 R + 0.7152 G + 0.0722 B`` of linear RGB, in float64.

    Summed r, g, then b, every time: not ``rgb @ weights``, which BLAS may fuse (FMA) or reorder
    depending on the CPU, giving other bits on other machines (and whose worker threads spin
    after a large call, taking the cores from the numba kernels that follow).

    Parameters
    ----------
    rgb : (..., C) float, C >= 3
        Linear colours; channels past the third (alpha) are ignored.

    Returns
    -------
    (...) float64
    """
    a = np.asarray(rgb)
    if a.ndim < 1 or a.shape[-1] < 3:
        raise ValueError(
            f"rgb: expected an array of shape (..., C) with C >= 3 channels, got shape {a.shape}"
        )
    r = a[..., 0].astype(np.float64, copy=False)
    g = a[..., 1].astype(np.float64, copy=False)
    b = a[..., 2].astype(np.float64, copy=False)
    return (r * LUMA_709[0] + g * LUMA_709[1]) + b * LUMA_709[2]
