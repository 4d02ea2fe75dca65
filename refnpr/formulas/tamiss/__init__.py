"""TAMISS: per-stroke cubic least squares over stroke fragments (Szécsi, Szirányi, Kacsó).

*Tonal Art Maps with Image Space Strokes*. Fragments of TAM/RPTAM strokes carry a stroke id, screen
position (x_i, y_i) and stroke parameter t_i. Per stroke, a cubic r(t) = (c_x . t, c_y . t),
t = (1, t, t^2, t^3), is fitted by ordinary least squares, b = A c with A = sum t_i t_i^T (eq. 1),
solved by four conjugate-gradient iterations; a cubic visibility v(t) fitted against evenly spread
zero-visibility points gives up to two visible segments, which are extruded to triangle strips.

Numerics (see ``docs/paper-notes.md``, "Szécsi et al. (TAMISS)"). The paper's claim that four
float32 CG iterations suffice fails on its literal formulation (raw monomials of t: pixels off on
narrow t ranges) and still fails, by up to a few pixels, when t is only centred and scaled. The
default fit therefore (1) sums the moments in s = (2 t - t_min - t_max) / (t_max - t_min) in
[-1, 1], with [t_min, t_max] from a first min/max pass, (2) sums x and y relative to the centre of
the stroke's fragment bounding box (found in the same pass), and (3) runs the four CG iterations
in the Legendre basis P_0..P_3 with diagonal scaling, a fixed 4 x 4 change of basis applied to the
paper's 15 sums (so the aggregate layout is the paper's). ``basis="monomial"`` and ``basis="raw"``
(with ``centre_xy=False``) keep the weaker variants to show where they break.

Pipeline: ``fit_fragments(ids, t, x, y)`` = min/max of t, x, y per stroke -> ``normalize_t`` ->
``fragment_regressors`` -> sum per stroke (``aggregate``) -> ``fit_strokes`` (the batched fit the
renderer calls) -> ``StrokeFit.visible_segments`` -> ``extrude_stroke``. The GPU's double-hashed
routing of fragments to aggregate texels is modelled separately by :class:`StrokeHashTable`.

The package is split by stage (``field``: the RPTAM stroke field the fragments are gathered
from; ``moments``, ``solve``, ``curve``, ``fit``, ``segments``, ``hashing``); this module
re-exports their public API. Per-sample formulas are scalar device functions (``f.scalar``) that
the ``tam`` and ``tamiss`` kernels call, ``f`` their numpy faces; the per-stroke solves (CG,
visibility prior, visible segments) are batched numpy host steps.
"""

from __future__ import annotations

from . import curve, field, fit, hashing, moments, segments, solve
from .curve import *  # noqa: F403
from .field import *  # noqa: F403
from .fit import *  # noqa: F403
from .hashing import *  # noqa: F403
from .moments import *  # noqa: F403
from .segments import *  # noqa: F403
from .solve import *  # noqa: F403

__all__ = [
    *moments.__all__,
    *solve.__all__,
    *fit.__all__,
    *segments.__all__,
    *hashing.__all__,
    *curve.__all__,
    *field.__all__,
]
