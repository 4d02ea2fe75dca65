"""``composite_ink`` (one numba pass) against the whole-image numpy expression it replaced
(:func:`composite_ink_numpy`, kept here as the oracle): bit for bit, over a base style, over
paper, over nothing, with one ink colour or one per sample, and for any thread count."""

from __future__ import annotations

from types import SimpleNamespace

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.styles._common import rgba_from
from refnpr.styles.base import Style
from refnpr.styles.tamiss.compose import composite_ink


def composite_ink_numpy(ctx, ink, ink_color, *, base, paper):
    """Ink over the base's RGBA, the paper on covered samples or nothing, in numpy."""
    shape = ink.shape
    if base is not None:
        under = np.asarray(base.shade(ctx), dtype=np.float64)
    elif paper is not None:
        under = rgba_from(np.asarray(paper), ctx.mask).astype(np.float64)
    else:
        under = np.zeros(shape + (4,))
    a = np.clip(ink, 0.0, 1.0)
    a_b = under[..., 3]
    alpha = a + a_b * (1.0 - a)
    premult = (
        np.broadcast_to(np.asarray(ink_color, dtype=np.float64), shape + (3,)) * a[..., None]
        + under[..., :3] * (a_b * (1.0 - a))[..., None]
    )
    rgb = np.divide(
        premult, alpha[..., None], out=np.zeros_like(premult), where=alpha[..., None] > 0
    )
    out = np.concatenate([np.clip(rgb, 0.0, 1.0), alpha[..., None]], axis=-1)
    return out.astype(np.float32)


class _Fixed(Style):
    """A base style that returns a given RGBA array."""

    name = "fixed"

    def __init__(self, rgba):
        self.rgba = rgba

    def requires(self, scene):
        return frozenset()

    def shade(self, ctx):
        return self.rgba


def _case(seed: int, shape: tuple[int, int], per_sample: bool):
    rng = np.random.default_rng(seed)
    # coverage outside [0, 1] and exactly 0 / 1 too (clipped by both)
    ink = rng.choice([0.0, 1.0, -0.25, 1.5, 0.5], size=shape) * (rng.random(shape) < 0.3)
    ink = ink + rng.random(shape) * (rng.random(shape) >= 0.3)
    under = rng.random(shape + (4,)).astype(np.float32)
    under[..., 3] = rng.choice([0.0, 1.0, 0.3], size=shape)  # transparent, opaque, partial
    color = rng.random(shape + (3,)) if per_sample else tuple(rng.random(3))
    ctx = SimpleNamespace(mask=rng.random(shape) < 0.6)
    return ctx, ink, under, color


def _same(a: np.ndarray, b: np.ndarray) -> None:
    assert a.dtype == b.dtype == np.float32 and a.shape == b.shape
    assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    rows=st.integers(1, 9),
    cols=st.integers(1, 11),
    per_sample=st.booleans(),
    under=st.sampled_from(["base", "paper", "none"]),
)
def test_kernel_equals_numpy(seed, rows, cols, per_sample, under):
    ctx, ink, rgba, color = _case(seed, (rows, cols), per_sample)
    base = _Fixed(rgba) if under == "base" else None
    paper = (0.95, 1.25, -0.1) if under == "paper" else None  # clipped as rgba_from does
    got = composite_ink(ctx, ink, color, base=base, paper=paper)
    want = composite_ink_numpy(ctx, ink, color, base=base, paper=paper)
    _same(got, want)


def test_hand_values():
    """Half ink over an opaque grey base, full ink, and ink over a transparent sample."""
    ctx = SimpleNamespace(mask=np.ones((1, 3), dtype=bool))
    under = np.array([[[0.5, 0.5, 0.5, 1.0], [0.5, 0.5, 0.5, 1.0], [0.2, 0.4, 0.6, 0.0]]])
    ink = np.array([[0.5, 1.0, 0.25]])
    got = composite_ink(
        ctx, ink, (0.0, 0.0, 0.0), base=_Fixed(under.astype(np.float32)), paper=None
    )
    np.testing.assert_array_equal(got[0, 0], np.float32([0.25, 0.25, 0.25, 1.0]))
    np.testing.assert_array_equal(got[0, 1], np.float32([0.0, 0.0, 0.0, 1.0]))
    np.testing.assert_array_equal(got[0, 2], np.float32([0.0, 0.0, 0.0, 0.25]))


@pytest.mark.parametrize("under", ["float64 base", "float32 ink"])
def test_other_dtypes_are_converted(under):
    """A float64 base is read as the float32 a style's shade gives, float32 ink as float64."""
    ctx, ink, rgba, color = _case(5, (4, 6), False)
    if under == "float64 base":
        base, cov = _Fixed(rgba.astype(np.float64) + 1e-9), ink
        as_given = _Fixed((rgba.astype(np.float64) + 1e-9).astype(np.float32))
    else:
        base, cov = _Fixed(rgba), ink.astype(np.float32)
        as_given = base
    got = composite_ink(ctx, cov, color, base=base, paper=None)
    want = composite_ink_numpy(ctx, cov.astype(np.float64), color, base=as_given, paper=None)
    _same(got, want)


def test_same_result_for_one_and_two_threads():
    ctx, ink, rgba, color = _case(11, (67, 45), True)
    saved = numba.get_num_threads()
    try:
        results = []
        for threads in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(threads)
            results.append(composite_ink(ctx, ink, color, base=_Fixed(rgba), paper=None))
    finally:
        numba.set_num_threads(saved)
    _same(*results)
