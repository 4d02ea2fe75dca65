"""Real-time halftoning (Freudenberg, Masuch, Strothotte 2002) as a style.

Per sample: the target intensity I (ambient + diffuse + specular of Veryovka eq. 1, as luminance;
sec. 5 effects applied) is thresholded against a halftone screen sampled trilinearly at the
sample's uv and LOD (sec. 3): binary (sec. 3.1) or smooth (sec. 3.2). Screens (sec. 4): a 1D
engraving ramp, dither screens (CLAHE pyramids), stroke maps encoded from ordered layers.
Effects (sec. 5): indication maps offset I; stroke sets with a normal map light each stroke
(DOT3), so lit strokes thin out. Extensions: anisotropic filtering of the screen
(``anisotropy``, keeps a stroke map's strokes thin on surfaces seen at grazing angles) and raw
views of the screen, normal map and intensity (``show``, Figs. 3 and 8).

Built screens of specs that read no file are shared between style instances
(:func:`.screens.cached_screen`).
"""

from __future__ import annotations

from .style import HalftoneStyle

__all__ = ["HalftoneStyle"]
