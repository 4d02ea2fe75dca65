"""X-Toon (Barla, Thollot, Markosian 2006): a 2D toon texture indexed by tone and detail, and
shape abstraction by normal blending.

Tone (sec. 3) is n . l of the shading normal and the scene's light ``light`` (clamped to [0, 1],
or half-Lambert (n . l + 1) / 2). Detail D in [0, 1] comes from an attribute map:

========== ======================================= =========================================
detail     D                                        paper
========== ======================================= =========================================
depth      1 - log_r(z / z_min), z = view-axis      sec. 3.1, LOA and aerial perspective
           distance (G-buffer ``depth``)            (Figs. 3a/b, 7, 9)
focus      two-sided log around the focus point,    sec. 3.1, depth of field (Figs. 3c, 8)
           z = Euclidean distance to the eye
orientation |n . v|^r                               sec. 3.2, near-silhouette (Figs. 4a, 10)
highlight  |v . r|^s (or max(v . r, 0)^s)           sec. 3.2, plastic and metal (Figs. 4b, 11)
flow       1 - clip((|f| - flow_min) /              sec. 5, optical flow (Fig. 6): f = screen
           (flow_max - flow_min)), pixels           displacement since ``prev_camera``
map        a user-supplied per-pixel map in [0, 1]
none       1 (the texture's full-detail row)
========== ======================================= =========================================

The flow of a point is its screen position now minus that of its object-space position through
``prev_transforms`` and ``prev_camera`` (default: the current ones, a still: zero flow); in a
sequence ``XToonStyle.for_frame`` takes both from the previous frame.

``distance`` swaps the depth of the depth and focus maps (Fig. 2: view axis or eye). All D are
clamped to [0, 1]. ``show="detail"`` (or ``"inverse_detail"``, ``"tone"``) draws D (1 - D, the
tone) as a grey image instead of the texture: the attribute-map pictures of Figs. 3 and 4.

``detail_mode="pixel"`` (default) evaluates the map per sample from interpolated quantities
(the exact reference); ``"vertex"`` evaluates it per vertex and interpolates D (for ``flow``: the
displacement vector), as the paper's vertex shader does for depth. The texture's **row index
grows with D** (row 0: D = 0, most abstract; last row: D = 1) and its column index with tone;
its alpha is the output alpha, composited over the background.

Shape abstraction (sec. 4): ``shape`` gives per-vertex abstracted normals (smoothed, ellipsoid,
cylinder, sphere; or a precomputed :class:`AbstractedNormals`, or a callable), blended with the
mesh normals by ``shape_weight``: per vertex, linearly, renormalized per pixel
(``shape_blend="vertex"``, the paper's), or per pixel with both normals renormalized first
(``"pixel"``). A weight may vary locally (the paper's future work): ``"detail"`` (w = 1 - D of the
same attribute map, evaluated with the mesh normals), a grey texture at uv, or a per-pixel array.
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
