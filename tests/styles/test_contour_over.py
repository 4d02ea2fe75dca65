"""The contour layer's compositing kernel against the numpy expression it replaced, and the
sequence protocol going through ``Contoured`` to its base style."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.styles import _kernels as K
from refnpr.styles import get_style
from refnpr.styles.base import Style


def _numpy_over(rgba, cov, ink):
    """``Contoured.shade`` before the kernel, verbatim."""
    rgba = np.asarray(rgba, dtype=np.float64)
    cov = cov[..., None]
    color = np.asarray(ink, dtype=np.float64)
    out = np.empty_like(rgba)
    a = cov[..., 0] + rgba[..., 3] * (1.0 - cov[..., 0])
    premult = color * cov + rgba[..., :3] * rgba[..., 3:4] * (1.0 - cov)
    out[..., :3] = np.divide(
        premult, a[..., None], out=np.zeros_like(premult), where=a[..., None] > 0
    )
    out[..., 3] = a
    return out.astype(np.float32)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    h=st.integers(1, 17),
    w=st.integers(1, 23),
    empty=st.floats(0.0, 1.0),
    ink=st.tuples(*[st.floats(0.0, 1.0)] * 3),
)
def test_ink_over_is_the_numpy_expression_bit_for_bit(seed, h, w, empty, ink):
    rng = np.random.default_rng(seed)
    rgba = rng.random((h, w, 4)).astype(np.float32)
    rgba[..., 3][rng.random((h, w)) < empty] = 0.0
    cov = rng.random((h, w))
    cov[rng.random((h, w)) < empty] = 0.0
    cov[rng.random((h, w)) < 0.1] = 1.0
    expected = _numpy_over(rgba, cov, ink)
    out = rgba.copy()
    K.ink_over(out, cov, np.asarray(ink, dtype=np.float64))
    assert np.array_equal(out, expected)


class _Counting(Style):
    """A stateless base whose state counts frames and whose for_frame records the previous scene."""

    name = "counting-test"

    def __init__(self, seen=None):
        self.seen = seen

    def requires(self, scene):
        return frozenset({"tri_id"})

    def shade(self, ctx):
        h, w = ctx.gb["tri_id"].shape
        return np.full((h, w, 4), 0.5, dtype=np.float32)

    def for_frame(self, scene, prev_scene):
        return _Counting(seen=prev_scene)

    def initial_state(self):
        return 0

    def shade_frame(self, ctx, state):
        return self.shade(ctx), state + 1


def test_contoured_passes_the_sequence_protocol_to_its_base():
    styled = get_style("contoured", base=_Counting(), contours=True)
    prev, scene = object(), object()
    framed = styled.for_frame(scene, prev)
    assert framed is not styled and framed.base.seen is prev
    assert styled.base.seen is None  # the original is untouched
    assert framed.layer is styled.layer
    assert styled.initial_state() == 0
    plain = get_style("contoured", base="toon", contours=True)
    assert plain.for_frame(scene, prev) is plain  # nothing to configure: the style itself
