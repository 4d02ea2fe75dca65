"""X-Toon (Barla, Thollot, Markosian 2006): a 2D toon texture indexed by tone and detail, and
shape abstraction by normal blending.

Tone (sec. 3) is n . l of the shading normal and the scene's light ``light`` (clamped to [0, 1],
or half-Lambert (n . l + 1) / 2). Detail D in [0, 1] comes from an attribute map:

=========== ======================================= =========================================
detail      D                                        paper
=========== ======================================= =========================================
depth       1 - log_r(z / z_min), z = view-axis      sec. 3.1, LOA and aerial perspective
            distance (G-buffer ``depth``)            (Figs. 3a/b, 7, 9)
focus       two-sided log around the focus point,    sec. 3.1, depth of field (Figs. 3c, 8)
            z = Euclidean distance to the eye
orientation |n . v|^r                               sec. 3.2, near-silhouette (Figs. 4a, 10)
highlight   |v . r|^s (or max(v . r, 0)^s)           sec. 3.2, plastic and metal (Figs. 4b, 11)
flow        1 - clip((‖f‖ - flow_min) /              sec. 5, optical flow (Fig. 6): f = screen
            (flow_max - flow_min)), pixels           displacement since ``prev_camera`` and
                                                     ``prev_transforms`` (a still: zero flow)
map         a user-supplied per-pixel map in [0, 1]
none        1 (the texture's full-detail row)
=========== ======================================= =========================================

The texture's row index grows with D and its column index with tone; its alpha is the output
alpha. Shape abstraction (sec. 4) blends the mesh normals with those of an abstracted shape
(``shape``, ``shape_weight``, ``shape_blend``). Every parameter is declared, with its meaning,
in :data:`refnpr.styles.xtoon.params.PARAMS`; ``docs/xtoon.md`` shows the paper's figures.
"""

from __future__ import annotations

from .params import DETAILS
from .presets import PRESETS
from .shape import SHAPES, AbstractedNormals, abstract_normals
from .style import XToonStyle
from .texture import resolve_texture

__all__ = [
    "XToonStyle",
    "AbstractedNormals",
    "abstract_normals",
    "resolve_texture",
    "PRESETS",
    "DETAILS",
    "SHAPES",
]
