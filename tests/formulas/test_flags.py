"""Every formula flag is a bool: a string or a number is refused, naming the flag, instead of
being taken by its truth value (``normalize="no"`` would normalize)."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.formulas import halftone, lighting, xtoon
from refnpr.formulas import tamiss as tm
from refnpr.formulas import threshold as thr

_N = np.array([[0.0, 0.0, 1.0]])
_L = np.array([[0.0, 0.6, 0.8]])
_V = np.array([[0.0, 0.0, 1.0]])
_X = np.array([0.3, 0.7])

#: flag name -> call with that flag set to ``value``
CALLS = {
    "lighting.diffuse normalize": ("normalize", lambda f: lighting.diffuse(_N, _L, normalize=f)),
    "lighting.specular_base normalize": (
        "normalize",
        lambda f: lighting.specular_base(_N, _L, _V, normalize=f),
    ),
    "halftone.smooth_threshold centred": (
        "centred",
        lambda f: halftone.smooth_threshold(_X, _X, 4.0, centred=f),
    ),
    "halftone.smooth_threshold_tone centred": (
        "centred",
        lambda f: halftone.smooth_threshold_tone(_X, 4.0, centred=f),
    ),
    "threshold.multiscale_line uniform": (
        "uniform",
        lambda f: thr.multiscale_line(_X, _X, uniform=f),
    ),
    "threshold.line_threshold uniform": (
        "uniform",
        lambda f: thr.line_threshold(_X, _X, uniform=f),
    ),
    "threshold.line_coverage uniform": (
        "uniform",
        lambda f: thr.line_coverage(_X, _X, _X, _X, _X, uniform=f),
    ),
    "xtoon.tone half_lambert": ("half_lambert", lambda f: xtoon.tone(_X, half_lambert=f)),
    "xtoon.detail_highlight one_sided": (
        "one_sided",
        lambda f: xtoon.detail_highlight(_X, 2.0, one_sided=f),
    ),
    "xtoon.blend_normals normalize": (
        "normalize",
        lambda f: xtoon.blend_normals(_N, _L, 0.5, normalize=f),
    ),
    "tamiss.tam_opacity clip": ("clip", lambda f: tm.tam_opacity(_X, _X, 0.1, f)),
    "halftone.decode_stroke_map centred (binary)": (
        "centred",
        lambda f: halftone.decode_stroke_map(_X, _X, centred=f),
    ),
    "xtoon.toon_texture_fade alpha": (
        "alpha",
        lambda f: xtoon.toon_texture_fade(np.ones((4, 4)), 3, alpha=f),
    ),
}


#: Flags whose None is a value of their own (``alpha=None``: from the channel count).
NONE_IS_A_VALUE = {"xtoon.toon_texture_fade alpha"}
BAD = ["no", 1, 0.0, None, np.array([True])]


@pytest.mark.parametrize(
    "case, bad",
    [(c, b) for c in sorted(CALLS) for b in BAD if not (b is None and c in NONE_IS_A_VALUE)],
    ids=repr,
)
def test_a_flag_that_is_not_a_bool_is_refused_by_name(case, bad):
    name, call = CALLS[case]
    with pytest.raises(TypeError, match=rf"^{name}: expected a bool \(True or False\), got "):
        call(bad)


@pytest.mark.parametrize("case", sorted(CALLS))
def test_a_numpy_bool_is_the_python_bool(case):
    _, call = CALLS[case]
    for flag in (False, True):
        assert np.array_equal(call(np.bool_(flag)), call(flag))
