"""A picture of the X-Toon presets: the 2D toon textures of Figs. 7a, 8, 9a, 9d, 10a and 11a of
Barla et al. 2006, one row per figure, drawn as the paper draws them (tone to the right, D = 1 at
the top; alpha over a grey checkerboard).

``python -m refnpr.styles.xtoon.sheet docs/images/xtoon-textures.png`` writes it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from refnpr.image import linear_to_srgb, write_png_atomic

from .presets import preset_texture

__all__ = ["FIGURE_TEXTURES", "texture_sheet"]

#: Figure -> the presets it shows (the paper's panels, in order).
FIGURE_TEXTURES: dict[str, tuple[str, ...]] = {
    "7a": ("loa_blur", "loa_levels", "loa_receding"),
    "8": ("dof_blur", "dof_fade"),
    "9a": ("aerial_earth", "aerial_blue"),
    "9d": ("aerial_pink", "aerial_fade"),
    "10a": ("silhouette_blur", "silhouette_fade", "backlight"),
    "11a": ("plastic", "metal", "highlight_red"),
}


def _panel(name: str, width: int, height: int) -> np.ndarray:
    """(height, width, 3) float64 linear RGB: the preset resampled (nearest texel), D up."""
    tex = preset_texture(name)
    rows, cols = tex.shape[:2]
    i = ((np.arange(height) + 0.5) / height * rows).astype(np.intp)[::-1]  # D = 1 on top
    j = ((np.arange(width) + 0.5) / width * cols).astype(np.intp)
    t = tex[i][:, j]
    yy, xx = np.mgrid[0:height, 0:width]
    checker = np.where(((yy // 8) + (xx // 8)) % 2 == 0, 0.55, 0.8)[..., None]  # linear greys
    return t[..., :3] * t[..., 3:] + checker * (1.0 - t[..., 3:])


def texture_sheet(*, width: int = 128, height: int = 96, gap: int = 6) -> np.ndarray:
    """All panels of ``FIGURE_TEXTURES``, one row per figure, as ``(H, W, 4)`` uint8 sRGB RGBA.

    Parameters
    ----------
    width, height : int
        Size of one texture panel in pixels (tone across, D up).
    gap : int
        White margin between panels.
    """
    for name, v in (("width", width), ("height", height), ("gap", gap)):
        if isinstance(v, bool) or not isinstance(v, int) or v < (0 if name == "gap" else 1):
            raise ValueError(f"{name}: expected a positive integer number of pixels, got {v!r}")
    n_cols = max(len(v) for v in FIGURE_TEXTURES.values())
    n_rows = len(FIGURE_TEXTURES)
    out = np.ones((gap + n_rows * (height + gap), gap + n_cols * (width + gap), 3))
    for r, names in enumerate(FIGURE_TEXTURES.values()):
        for c, name in enumerate(names):
            y, x = gap + r * (height + gap), gap + c * (width + gap)
            out[y : y + height, x : x + width] = _panel(name, width, height)
    rgba = np.full(out.shape[:2] + (4,), 255, dtype=np.uint8)
    rgba[..., :3] = np.rint(linear_to_srgb(out) * 255.0)
    return rgba


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m refnpr.styles.xtoon.sheet OUT.png", file=sys.stderr)
        return 2
    path = write_png_atomic(Path(args[0]), texture_sheet())
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
