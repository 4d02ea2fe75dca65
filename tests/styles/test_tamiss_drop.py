"""The drop rule's stretch test: a fit its fragments do not determine is not drawn.

Oracle: each stroke's fragments (their bounding box in pixels). A drawn stroke of extent
``"range"`` (no run-on) stays near the fragments it was fitted to; with the stretch test off (and each
patch its own chart), the teapot's spout lip has a stroke seen by 7 fragments whose cubic swings
75 px away.
"""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import get_style
from refnpr.styles.base import ShadeContext


def _worst_excursion(max_stretch, orient_charts=True):
    sc = load_scene("tamiss_teapot")
    st = get_style("tamiss", directions=["u", "v"], density=1.0, extent="range",
                   max_stretch=max_stretch, orient_charts=orient_charts)  # fmt: skip
    gb = rasterize(sc, sc.camera, 384, 288, sorted(st.requires(sc)), 1, **st.raster_options(sc))
    r = st.run(ShadeContext(gb, sc))
    f = r.fragments
    order = np.argsort(f.id, kind="stable")
    ids, start = np.unique(f.id[order], return_index=True)
    lo_x = np.minimum.reduceat(f.x[order], start)
    hi_x = np.maximum.reduceat(f.x[order], start)
    lo_y = np.minimum.reduceat(f.y[order], start)
    hi_y = np.maximum.reduceat(f.y[order], start)
    k = np.searchsorted(ids, r.strips.ids)
    mid = 0.5 * (r.strips.strip.left + r.strips.strip.right)  # (P, K, 2) centreline
    out_x = np.maximum(lo_x[k, None] - mid[..., 0], mid[..., 0] - hi_x[k, None])
    out_y = np.maximum(lo_y[k, None] - mid[..., 1], mid[..., 1] - hi_y[k, None])
    return float(np.nanmax(np.maximum(out_x, out_y))), len(r.strips)


@pytest.mark.parametrize("orient_charts", [True, False])
def test_drawn_strokes_stay_near_their_fragments(orient_charts):
    worst, n = _worst_excursion(3.0, orient_charts)
    assert n > 200
    assert worst < 6.0  # pixels outside the fragments' bounding box


def test_without_the_stretch_test_a_fit_runs_away():
    # each patch its own chart (the ids of before the charts were laid out as one atlas): the
    # spout-lip stroke of 7 fragments
    worst, _ = _worst_excursion(None, orient_charts=False)
    assert worst > 30.0


def test_max_stretch_errors():
    with pytest.raises(ValueError, match="max_stretch"):
        get_style("tamiss", max_stretch=0.5)
