"""Named 2D toon textures for the X-Toon style, one per effect of Barla et al. 2006 (Figs. 7-11).

The paper gives its textures only as pictures and one-line recipes; each preset here is one
recipe made concrete with the formula layer's builders (:mod:`refnpr.formulas.xtoon`, whose
orientation they share: row index growing with D, column index with tone). The colours are
refnpr's choices.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from refnpr.formulas import xtoon
from refnpr.image import srgb_to_linear

__all__ = ["PRESETS", "band_ramp", "per_texel", "as_rgba", "preset_texture"]

ROWS = 64
COLS = 256
FINE = 4096  # columns of the continuous "lambert" and "grey" ramps


def _lin(*colours: tuple[float, float, float]) -> np.ndarray:
    """sRGB-encoded colours (as picked in a paint program) -> (K, 3) linear RGB."""
    return srgb_to_linear(np.array(colours))


# Colours of the presets (refnpr's choices), picked in sRGB and stored linear.
_GREY3 = _lin((0.20, 0.20, 0.22), (0.55, 0.55, 0.57), (0.92, 0.92, 0.90))
_EDGES3 = (0.3, 0.65)
_WARM3 = _lin((0.30, 0.17, 0.12), (0.66, 0.48, 0.36), (0.96, 0.89, 0.78))
_BLUE2 = _lin((0.22, 0.30, 0.48), (0.82, 0.87, 0.95))
_SHADE4 = _lin((0.15, 0.17, 0.30), (0.45, 0.55, 0.70), (0.72, 0.79, 0.88), (1.0, 1.0, 1.0))
_EDGES4 = (0.3, 0.6, 0.9)
_GREEN_BROWN = _lin((0.22, 0.32, 0.12), (0.38, 0.55, 0.20), (0.62, 0.70, 0.35), (0.76, 0.66, 0.48))
_BROWNS = _lin((0.40, 0.30, 0.20), (0.52, 0.40, 0.28), (0.66, 0.54, 0.40), (0.78, 0.68, 0.54))
_EDGES_T = (0.25, 0.5, 0.75)
_RED3 = _lin((0.40, 0.05, 0.05), (0.72, 0.12, 0.10), (0.92, 0.35, 0.30))
_STEEL3 = _lin((0.22, 0.25, 0.30), (0.48, 0.52, 0.58), (0.70, 0.74, 0.80))
_SKY = _lin((0.70, 0.78, 0.92))[0]
_PINK = _lin((0.92, 0.72, 0.80))[0]
_HAZE = _lin((0.86, 0.86, 0.88))[0]
_RING = _lin((1.0, 0.45, 0.35))[0]


def band_ramp(
    colors: Sequence, edges: Sequence[float] | None = None, *, cols: int = COLS, smooth=False
):
    """A 1D toon ramp of ``cols`` texels made of hard bands of constant colour.

    Parameters
    ----------
    colors : K colours, each 1, 2, 3 or 4 numbers (all the same length)
        Band colours, darkest tone first.
    edges : K - 1 increasing tones in (0, 1), optional
        Where each band ends; default: K equal bands.
    cols : int
        Texels of the ramp.
    smooth : bool
        Interpolate linearly between band centres instead of hard steps.

    Returns
    -------
    (cols, C) float64
    """
    c = np.asarray(colors, dtype=np.float64)
    if c.ndim == 1:
        c = c[:, None]
    k = c.shape[0]
    e = np.linspace(0.0, 1.0, k + 1)[1:-1] if edges is None else np.asarray(edges, np.float64)
    tau = (np.arange(cols) + 0.5) / cols  # texel centres
    if not smooth:
        return c[np.searchsorted(e, tau, side="right")]
    bounds = np.concatenate([[0.0], e, [1.0]])
    centres = (bounds[:-1] + bounds[1:]) / 2
    return np.stack([np.interp(tau, centres, c[:, j]) for j in range(c.shape[1])], axis=1)


def as_rgba(texture: np.ndarray) -> np.ndarray:
    """(rows, cols[, C]) with C in {1, 2, 3, 4} -> (rows, cols, 4) float64 RGBA (alpha 1 if none)."""
    t = np.asarray(texture, dtype=np.float64)
    t = t[..., None] if t.ndim == 2 else t
    c = t.shape[2]
    rgb = np.repeat(t[..., :1], 3, axis=2) if c <= 2 else t[..., :3]
    alpha = t[..., c - 1 :] if c in (2, 4) else np.ones_like(t[..., :1])
    return np.concatenate([rgb, alpha], axis=2)


def _alpha(ramp: np.ndarray) -> np.ndarray:
    return np.concatenate([ramp, np.ones((ramp.shape[0], 1))], axis=1)


def per_texel(weights: Sequence[float], edges: Sequence[float] | None, cols: int = COLS):
    """One weight per band (``band_ramp``'s bands) -> ``(cols,)`` float64, one per texel."""
    return band_ramp(np.asarray(weights, dtype=np.float64)[:, None], edges, cols=cols)[:, 0]


def _lambert() -> np.ndarray:  # texel j holds its own tone: the lookup returns the tone itself
    ramp = (np.arange(FINE) + 0.5) / FINE  # exact but within half a texel of tone 0 and 1
    return np.repeat(ramp[None], 2, axis=0)


def _grey() -> np.ndarray:  # displayed (sRGB-encoded) grey equals the tone: for looking at n.l
    ramp = srgb_to_linear((np.arange(FINE) + 0.5) / FINE)
    return np.repeat(ramp[None], 2, axis=0)


def _toon() -> np.ndarray:
    return np.repeat(band_ramp(_GREY3, _EDGES3)[None], 2, axis=0)  # constant along D


def _loa_blur() -> np.ndarray:  # Fig. 7b: progressively blurred 1D toon texture
    return xtoon.toon_texture_blur(band_ramp(_WARM3, _EDGES3), ROWS, max_sigma=40.0)


def _loa_levels() -> np.ndarray:  # Fig. 7c: three 1D textures, smooth steps between them
    mid = _WARM3[1]
    ramps = [
        band_ramp([mid]),
        band_ramp([_WARM3[0], _WARM3[2]], [0.45]),
        band_ramp(_WARM3, _EDGES3),
    ]
    return xtoon.toon_texture_levels(ramps, ROWS, transition=0.3)


def _loa_receding() -> np.ndarray:  # Fig. 7d: darker tones slide left, lightened
    return xtoon.toon_texture_receding(band_ramp(_WARM3, _EDGES3), ROWS, shift=0.6, lighten=0.25)


def _dof_blur() -> np.ndarray:  # Fig. 8a: smooth two-tone texture converging to one colour
    ramp = band_ramp(_BLUE2, [0.45], smooth=False)
    return xtoon.toon_texture_blur(ramp, ROWS, max_sigma=160.0)


def _dof_fade() -> np.ndarray:  # Fig. 8b: contrast and opacity fall for intermediate tones
    w = per_texel([0.0, 1.0, 1.0, 0.0], _EDGES4)  # shadows and highlights stay opaque
    ramp = _alpha(band_ramp(_SHADE4, _EDGES4))
    return xtoon.toon_texture_fade(ramp, ROWS, contrast=0.8, opacity=1.0, tone_weight=w)


def _aerial_earth() -> np.ndarray:  # Fig. 9b: green-to-brown ramp -> uniform browns
    ramps = [band_ramp(_BROWNS[1:3], [0.5]), band_ramp(_GREEN_BROWN, _EDGES_T)]
    return xtoon.toon_texture_levels(ramps, ROWS, transition=1.0)


def _aerial_blue() -> np.ndarray:  # Fig. 9c: desaturation and a shift towards blue
    ramp = band_ramp(_GREEN_BROWN, _EDGES_T)
    return xtoon.toon_texture_hue(ramp, ROWS, target=_SKY, amount=0.85, desaturate=1.0)


def _aerial_pink() -> np.ndarray:  # Fig. 9e: towards pink, darker tones first
    ramp = band_ramp(_GREEN_BROWN, _EDGES_T)
    w = per_texel([2.5, 1.8, 1.2, 0.9], _EDGES_T)
    return xtoon.toon_texture_hue(ramp, ROWS, target=_PINK, amount=1.0, tone_weight=w)


def _aerial_fade() -> np.ndarray:  # Fig. 9f: alpha and saturation fall, light grey shadows stay
    ramp = _alpha(band_ramp(_GREEN_BROWN, _EDGES_T))
    w = per_texel([0.6, 0.8, 1.0, 1.0], _EDGES_T)
    return xtoon.toon_texture_fade(
        ramp, ROWS, contrast=1.0, opacity=1.0, target=_HAZE, tone_weight=w
    )


def _silhouette_blur() -> np.ndarray:  # Fig. 10b: shading smoothed near silhouettes
    return xtoon.toon_texture_blur(band_ramp(_GREY3, _EDGES3), ROWS, max_sigma=48.0)


def _silhouette_fade() -> np.ndarray:  # Fig. 10c: opacity falls except for dark tones
    ramp = _alpha(band_ramp(_GREY3, _EDGES3))
    w = per_texel([0.0, 1.0, 1.0], _EDGES3)
    return xtoon.toon_texture_fade(ramp, ROWS, contrast=0.0, opacity=1.0, tone_weight=w)


def _backlight() -> np.ndarray:  # Fig. 10d: a white rim, thinner in darker tones
    ramp = band_ramp(_STEEL3, _EDGES3)
    return xtoon.toon_texture_backlight(ramp, ROWS, color=1.0, width=0.35, thinning=0.8)


def _plastic() -> np.ndarray:  # Fig. 11b: hard white highlight whose width shrinks with D
    return xtoon.toon_texture_plastic(band_ramp(_RED3, _EDGES3), ROWS, color=1.0, size=0.6)


def _metal() -> np.ndarray:  # Fig. 11c: a glow that flares up near the mirror direction
    ramp = band_ramp(_STEEL3, _EDGES3)
    return xtoon.toon_texture_metal(ramp, ROWS, color=1.0, onset=0.3, spread=0.9)


def _highlight_red() -> np.ndarray:  # Fig. 11d: the highlight turns red near its boundary
    base = band_ramp(_STEEL3, _EDGES3)
    size = 0.6
    out = xtoon.toon_texture_plastic(base, ROWS, color=1.0, size=size)
    D = (np.arange(ROWS) + 0.5) / ROWS
    tau = (np.arange(COLS) + 0.5) / COLS
    edge = 1.0 - size * D[:, None]  # highlight starts at this tone (plastic recipe)
    ring = 0.25 * size * D[:, None]  # red ring, wider for larger highlights
    red = (tau[None, :] > edge) & (tau[None, :] <= edge + ring)
    out[red] = _RING
    return out


#: Preset name -> builder of a ``(rows, cols, C)`` texture (converted to RGBA by the caller).
PRESETS: dict[str, Callable[[], np.ndarray]] = {
    "lambert": _lambert,
    "grey": _grey,
    "toon": _toon,
    "loa_blur": _loa_blur,
    "loa_levels": _loa_levels,
    "loa_receding": _loa_receding,
    "dof_blur": _dof_blur,
    "dof_fade": _dof_fade,
    "aerial_earth": _aerial_earth,
    "aerial_blue": _aerial_blue,
    "aerial_pink": _aerial_pink,
    "aerial_fade": _aerial_fade,
    "silhouette_blur": _silhouette_blur,
    "silhouette_fade": _silhouette_fade,
    "backlight": _backlight,
    "plastic": _plastic,
    "metal": _metal,
    "highlight_red": _highlight_red,
}


def preset_texture(name: str) -> np.ndarray:
    """The preset ``name`` as ``(rows, cols, 4)`` float64 RGBA."""
    return as_rgba(PRESETS[name]())
