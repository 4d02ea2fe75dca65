"""Builders of 2D X-Toon textures from a 1D toon ramp (Barla et al. 2006, sec. 3, Figs. 7-11).

The paper gives its textures as pictures and one-line recipes ("we progressively blurred an input
1D toon texture", "sliding the darker tones to the left", ...); each builder here is one recipe
made precise (the exact profiles are refnpr's choices, documented per function).

Layout (as :func:`refnpr.formulas.xtoon.toon_lookup` reads it): the ramp's shape with a leading
row axis; row i holds the recipe at D_i = (i + 0.5) / rows, with abstraction a = 1 - D_i (high
rows: the ramp itself or nearly so), and column j is the ramp's texel j, at tone (j + 0.5) /
cols. float32 ramps give float32 textures.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float, check_bool, check_int, check_scalar, describe
from ..lighting import luminance

__all__ = [
    "toon_texture_blur",
    "toon_texture_levels",
    "toon_texture_receding",
    "toon_texture_fade",
    "toon_texture_hue",
    "toon_texture_backlight",
    "toon_texture_plastic",
    "toon_texture_metal",
]


def _ramp(ramp, name: str = "ramp") -> np.ndarray:
    arr = as_float(name, ramp, finite=True)
    if arr.ndim not in (1, 2) or arr.shape[0] < 1 or (arr.ndim == 2 and arr.shape[1] < 1):
        raise ValueError(
            f"{name}: expected a 1D toon ramp of shape (cols,) or (cols, C), got {describe(arr)}; "
            "pass one texel (or one colour) per tone"
        )
    return arr


def _rows(rows) -> tuple[int, np.ndarray]:
    n = check_int("rows", rows, lo=1)
    return n, (np.arange(n) + 0.5) / n  # texel centres along D


def _tone_axis(cols: int) -> np.ndarray:
    return (np.arange(cols) + 0.5) / cols


def _tone_weight(tone_weight, cols: int) -> np.ndarray:
    if tone_weight is None:
        return np.ones(cols)
    w = as_float("tone_weight", tone_weight, finite=True)
    if w.shape != (cols,) or np.any(w < 0):
        raise ValueError(
            f"tone_weight: expected {cols} non-negative values (one per ramp texel), got "
            f"{describe(w)}; larger weights make that tone change sooner as D decreases"
        )
    return w.astype(np.float64)


def _color(name: str, color, like: np.ndarray):
    """``color`` as one value per channel of the ramp ``like`` (a scalar for a (cols,) ramp)."""
    channels = 1 if like.ndim == 1 else like.shape[1]
    c = as_float(name, color, finite=True).astype(np.float64)
    if c.ndim == 0:
        c = np.full(channels, float(c))
    elif c.shape != (channels,):
        raise ValueError(
            f"{name}: expected a scalar or {channels} values (one per ramp channel), got "
            f"{describe(c)}; match the ramp's channel count"
        )
    return c[0] if like.ndim == 1 else c


def _smoothstep(e0: float, e1, x):
    """Hermite smoothstep; a hard step at e0 when e1 <= e0."""
    e1 = np.asarray(e1, dtype=np.float64)
    width = e1 - e0
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip((x - e0) / np.where(width > 0, width, 1.0), 0.0, 1.0)
    s = np.where(width > 0, s, (x >= e0).astype(np.float64))
    return s * s * (3 - 2 * s)


def _lerp(a, b, t):
    """(1 - t) a + t b (exact at t = 0 and t = 1), t broadcast over a trailing channel axis."""
    t = np.asarray(t, dtype=np.float64)
    if np.ndim(a) > t.ndim:
        t = t[..., None]
    return (1.0 - t) * a + t * b


def _sample_ramp(ramp: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Linear, edge-clamped ramp lookup at tone positions ``tau`` (texel-centre convention)."""
    cols = ramp.shape[0]
    x = np.clip(np.clip(tau, 0.0, 1.0) * cols - 0.5, 0.0, cols - 1)
    j0 = np.minimum(np.floor(x).astype(np.intp), max(cols - 2, 0))
    j1 = np.minimum(j0 + 1, cols - 1)
    return _lerp(ramp[j0], ramp[j1], x - j0)


def _finish(out: np.ndarray, ramp: np.ndarray) -> np.ndarray:
    return out.astype(ramp.dtype, copy=False)


def _towards(r: np.ndarray, color, m: np.ndarray) -> np.ndarray:
    """The ramp ``r`` blended towards ``color`` by ``m (rows, cols)``, in the ramp's dtype."""
    return _finish(_lerp(r.astype(np.float64)[None], _color("color", color, r), m), r)


def toon_texture_blur(ramp, rows: int, *, max_sigma: float) -> np.ndarray:
    """Progressive blur down the D axis (Fig. 7b, Fig. 8a).

    Row D is the ramp convolved with a Gaussian of standard deviation ``max_sigma * (1 - D)`` texels,
    with mirror-symmetric boundaries (so the blur preserves the ramp's mean and a large
    ``max_sigma`` converges to a constant colour, as in Fig. 8a).

    Parameters
    ----------
    ramp : (cols,) or (cols, C) float
    rows : int >= 1
    max_sigma : float >= 0, in texels

    Returns
    -------
    (rows, cols) or (rows, cols, C), the ramp's dtype (float32 stays float32).
    """
    r = _ramp(ramp)
    n, D = _rows(rows)
    max_sigma = check_scalar("max_sigma", max_sigma, lo=0.0, hint="a blur width in texels")
    cols = r.shape[0]
    radius = int(np.ceil(4.0 * max_sigma))
    offsets = np.arange(-radius, radius + 1)
    sigma = max_sigma * (1.0 - D)  # row blur grows as detail decreases
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.exp(-0.5 * (offsets[None, :] / sigma[:, None]) ** 2)
    w = np.where(sigma[:, None] > 0, w, (offsets[None, :] == 0).astype(np.float64))
    w /= w.sum(axis=1, keepdims=True)
    idx = np.arange(cols)[:, None] + offsets[None, :]
    m = np.mod(idx, 2 * cols)
    idx = np.where(m < cols, m, 2 * cols - 1 - m)  # mirror boundary, any radius
    gathered = r.astype(np.float64)[idx]  # (cols, 2R+1[, C])
    out = np.einsum("ro,jo...->rj...", w, gathered)
    return _finish(out, r)


def toon_texture_levels(ramps, rows: int, *, transition: float = 0.25) -> np.ndarray:
    """Discrete levels of abstraction with smooth steps between them (Fig. 7c).

    The K ramps split the D axis into K equal bands, ``ramps[0]`` at the low-detail end and
    ``ramps[-1]`` at D = 1; neighbouring bands blend with a smoothstep of width ``transition``
    (a fraction of a band, centred on the band boundary; 0 gives hard steps).

    Parameters
    ----------
    ramps : (K, cols) or (K, cols, C) float, K >= 1
    rows : int >= 1
    transition : float in [0, 1]

    Returns
    -------
    (rows, cols) or (rows, cols, C)
    """
    rs = as_float("ramps", ramps, finite=True)
    if rs.ndim not in (2, 3) or rs.shape[0] < 1 or rs.shape[1] < 1:
        raise ValueError(
            f"ramps: expected shape (K, cols) or (K, cols, C) with K >= 1, got {describe(rs)}; "
            "stack the 1D ramps along a first axis, least detailed first"
        )
    n, D = _rows(rows)
    transition = check_scalar("transition", transition, lo=0.0, hi=1.0)
    K = rs.shape[0]
    p = np.clip(D * K - 0.5, 0.0, K - 1)  # band coordinate, band k centred at k
    k0 = np.minimum(np.floor(p).astype(np.intp), max(K - 2, 0))
    k1 = np.minimum(k0 + 1, K - 1)
    f = p - k0
    alpha = _smoothstep(0.5 - transition / 2, 0.5 + transition / 2, f)
    out = _lerp(rs[k0].astype(np.float64), rs[k1].astype(np.float64), alpha[:, None])
    return out.astype(rs.dtype, copy=False)


def toon_texture_receding(ramp, rows: int, *, shift: float = 0.5, lighten: float = 0.0):
    """Receding shadows (Fig. 7d): dark tones slide to the left as D decreases.

    Row D reads the ramp at tone + ``shift`` * (1 - D) (edge-clamped, linear), so a dark band that
    ends at tone t0 at D = 1 ends at t0 - shift * (1 - D); then it blends towards the ramp's last
    (brightest) texel by ``lighten`` * (1 - D).

    Parameters
    ----------
    ramp : (cols,) or (cols, C) float
    rows : int >= 1
    shift : float in [0, 1], tone units
    lighten : float in [0, 1]
    """
    r = _ramp(ramp)
    n, D = _rows(rows)
    shift = check_scalar("shift", shift, lo=0.0, hi=1.0)
    lighten = check_scalar("lighten", lighten, lo=0.0, hi=1.0)
    a = 1.0 - D
    rf = r.astype(np.float64)
    tau = _tone_axis(r.shape[0])[None, :] + shift * a[:, None]  # shadows slide left
    out = _sample_ramp(rf, tau)
    out = _lerp(out, rf[-1], np.broadcast_to((lighten * a)[:, None], tau.shape))
    return _finish(out, r)


def toon_texture_fade(
    ramp,
    rows: int,
    *,
    contrast: float = 1.0,
    opacity: float = 0.0,
    target=None,
    tone_weight=None,
    alpha: bool | None = None,
) -> np.ndarray:
    """Contrast and opacity fade down the D axis (Fig. 8b, Fig. 9b/f, Fig. 10c).

    With a = 1 - D and a per-tone weight w (``tone_weight``, default 1; set it to 0 for tones that
    must stay intact, e.g. shadows and highlights in Fig. 8b): colour channels blend towards
    ``target`` (default: the ramp's mean colour, i.e. contrast loss) by clip(contrast * w * a, 0, 1)
    and the alpha channel is multiplied by 1 - clip(opacity * w * a, 0, 1).

    Parameters
    ----------
    ramp : (cols,) or (cols, C) float
    rows : int >= 1
    contrast, opacity : float >= 0
        Strengths; 1 reaches the full effect at D = 0 for weight 1.
    target : scalar or (C_colour,) float, optional
    tone_weight : (cols,) float >= 0, optional
    alpha : bool, optional
        Whether the last channel is alpha; default: yes for C in (2, 4). Required when
        ``opacity > 0``.
    """
    r = _ramp(ramp)
    n, D = _rows(rows)
    contrast = check_scalar("contrast", contrast, lo=0.0)
    opacity = check_scalar("opacity", opacity, lo=0.0)
    has_alpha = (
        (r.ndim == 2 and r.shape[1] in (2, 4)) if alpha is None else check_bool("alpha", alpha)
    )
    if has_alpha and r.ndim == 1:
        raise ValueError(
            "alpha: a ramp of shape (cols,) has no alpha channel; pass (cols, 2) or (cols, 4) "
            "with alpha last, or alpha=False"
        )
    if opacity > 0 and not has_alpha:
        raise ValueError(
            f"opacity: a fade of {opacity} needs an alpha channel, but the ramp has shape "
            f"{r.shape}; append one, e.g. np.concatenate([ramp, np.ones((len(ramp), 1))], axis=1)"
        )
    w = _tone_weight(tone_weight, r.shape[0])
    a = (1.0 - D)[:, None] * w[None, :]
    rf = r.astype(np.float64)
    colour = rf[:, :-1] if has_alpha else rf
    tgt = _color("target", colour.mean(axis=0) if target is None else target, colour)
    out_colour = _lerp(colour[None], tgt, np.clip(contrast * a, 0.0, 1.0))  # contrast loss
    if not has_alpha:
        return _finish(out_colour, r)
    out_alpha = rf[None, :, -1] * (1.0 - np.clip(opacity * a, 0.0, 1.0))  # opacity loss
    return _finish(np.concatenate([out_colour, out_alpha[..., None]], axis=-1), r)


def toon_texture_hue(
    ramp,
    rows: int,
    *,
    target,
    amount: float = 1.0,
    desaturate: float = 0.0,
    tone_weight=None,
) -> np.ndarray:
    """Aerial perspective: desaturation and a shift towards a hue (Fig. 9a/d).

    With a = 1 - D and per-tone weight w: colours first blend towards their Rec. 709 luma by
    clip(desaturate * w * a, 0, 1), then towards ``target`` by clip(amount * w * a, 0, 1). A weight
    above 1 makes a tone change sooner ("darker tones modified prior to lighter ones", Fig. 9d).

    Parameters
    ----------
    ramp : (cols, 3) RGB or (cols, 4) RGBA float (alpha is kept)
    rows : int >= 1
    target : (3,) float, the RGB colour reached at full abstraction
    amount, desaturate : float >= 0
    tone_weight : (cols,) float >= 0, optional
    """
    r = _ramp(ramp)
    if r.ndim != 2 or r.shape[1] not in (3, 4):
        raise ValueError(
            f"ramp: expected an RGB (cols, 3) or RGBA (cols, 4) ramp for a hue shift, got "
            f"{describe(r)}; convert grey ramps with np.repeat(ramp[:, None], 3, axis=1)"
        )
    n, D = _rows(rows)
    amount = check_scalar("amount", amount, lo=0.0)
    desaturate = check_scalar("desaturate", desaturate, lo=0.0)
    rf = r.astype(np.float64)
    rgb = rf[:, :3]
    tgt = _color("target", target, rgb)
    w = _tone_weight(tone_weight, r.shape[0])
    a = (1.0 - D)[:, None] * w[None, :]
    luma = luminance(rgb)[:, None]
    out = _lerp(rgb[None], luma[None], np.clip(desaturate * a, 0.0, 1.0))  # desaturation
    out = _lerp(out, tgt, np.clip(amount * a, 0.0, 1.0))  # shift towards the target hue
    if r.shape[1] == 4:
        out = np.concatenate([out, np.broadcast_to(rf[None, :, 3:], (n, r.shape[0], 1))], -1)
    return _finish(out, r)


def toon_texture_backlight(
    ramp,
    rows: int,
    *,
    color=1.0,
    width: float = 0.3,
    thinning: float = 1.0,
    softness: float = 0.0,
) -> np.ndarray:
    """Backlight (Fig. 10d), for the near-silhouette map D = |n . v|^r.

    Texels with D below w(tone) = ``width`` * (1 - ``thinning`` * (1 - tone)) take ``color``: a
    rim that "grows thinner in darker tones". ``softness`` > 0 replaces the hard edge by a
    smoothstep over D in [w - softness, w + softness].

    Parameters
    ----------
    ramp : (cols,) or (cols, C) float
    rows : int >= 1
    color : scalar or (C,) float
    width, thinning : float in [0, 1]
    softness : float >= 0
    """
    r = _ramp(ramp)
    n, D = _rows(rows)
    width = check_scalar("width", width, lo=0.0, hi=1.0)
    thinning = check_scalar("thinning", thinning, lo=0.0, hi=1.0)
    softness = check_scalar("softness", softness, lo=0.0)
    wt = width * (1.0 - thinning * (1.0 - _tone_axis(r.shape[0])))  # thinner in dark tones
    return _towards(
        r, color, 1.0 - _smoothstep(0.0, 2 * softness, D[:, None] - wt[None, :] + softness)
    )


def toon_texture_plastic(ramp, rows: int, *, color=1.0, size: float = 0.3) -> np.ndarray:
    """Plastic highlight (Fig. 11b), for the highlight map D = |v . r|^s.

    A hard-edged highlight of constant ``color`` covers the tones above 1 - ``size`` * D: its width
    shrinks with D and vanishes at D = 0, its colour and profile do not change.

    Parameters
    ----------
    ramp : (cols,) or (cols, C) float
    rows : int >= 1
    color : scalar or (C,) float
    size : float in [0, 1], tone width of the highlight at D = 1
    """
    r = _ramp(ramp)
    n, D = _rows(rows)
    size = check_scalar("size", size, lo=0.0, hi=1.0)
    m = (_tone_axis(r.shape[0])[None, :] > 1.0 - size * D[:, None]).astype(np.float64)
    return _towards(r, color, m)


def toon_texture_metal(
    ramp, rows: int, *, color=1.0, onset: float = 0.8, spread: float = 0.5
) -> np.ndarray:
    """Metal "glowing" highlight (Fig. 11c), for the highlight map D = |v . r|^s.

    Nothing happens below D = ``onset``; above it the texel blends towards ``color`` by
    smoothstep(onset, 1, D) * smoothstep(1 - spread, 1, tone): the highlight flares up only near the
    mirror direction and has a soft tone profile.

    Parameters
    ----------
    ramp : (cols,) or (cols, C) float
    rows : int >= 1
    color : scalar or (C,) float
    onset : float in [0, 1)
    spread : float in (0, 1], tone width of the glow
    """
    r = _ramp(ramp)
    n, D = _rows(rows)
    onset = check_scalar("onset", onset, lo=0.0, hi=1.0, hi_open=True)
    spread = check_scalar("spread", spread, lo=0.0, hi=1.0, lo_open=True)
    glow = _smoothstep(onset, 1.0, D)[:, None]  # sudden flare near the mirror direction
    profile = _smoothstep(1.0 - spread, 1.0, _tone_axis(r.shape[0]))[None, :]
    return _towards(r, color, glow * profile)
