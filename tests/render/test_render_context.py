"""The fused composite + resolve kernel (exactly the numpy code it replaced) and RenderContext
(frames identical to render(), buffers reused between them)."""

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.raster import Camera
from refnpr.raster.gbuffer import box_resolve
from refnpr.render import RenderContext, composite_resolve, render
from refnpr.warmup import WARM_ROWS


def numpy_composite_resolve(rgba, n, background):
    """The compositing and resolve of render() in numpy: the oracle of the fused kernel."""
    bg = np.asarray(background, dtype=np.float64)
    a = rgba[..., 3:4].astype(np.float64)
    premult = np.concatenate([rgba[..., :3] * a, a], axis=-1)
    bg_premult = np.concatenate([bg[:3] * bg[3], bg[3:4]])
    over = premult + bg_premult * (1.0 - a)
    res = box_resolve(over, n)
    alpha = res[..., 3:4]
    rgb = np.divide(res[..., :3], alpha, out=np.zeros_like(res[..., :3]), where=alpha > 0)
    return np.concatenate([rgb, alpha], axis=-1).astype(np.float32)


def random_samples(rng, h, w, n):
    rgba = rng.random((h * n, w * n, 4), dtype=np.float32)
    a = rgba[..., 3]
    a[rng.random(a.shape) < 0.3] = 0.0  # empty samples
    a[rng.random(a.shape) < 0.3] = 1.0  # opaque samples
    return rgba


@pytest.mark.parametrize("n", [1, 2, 3, 4])
@pytest.mark.parametrize(
    "background", [(0.0, 0.0, 0.0, 1.0), (0.2, 0.7, 0.9, 0.5), (1.0, 1.0, 1.0, 0.0)]
)
def test_fused_kernel_equals_numpy_bit_for_bit(n, background):
    rng = np.random.default_rng(11 + n)
    rgba = random_samples(rng, 37, 53, n)
    want = numpy_composite_resolve(rgba, n, background)
    got = composite_resolve(rgba, n, background)
    assert got.dtype == np.float32 and got.shape == want.shape
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))


#: float32 values where the kernel's shortcuts could part from the division: 0, 1, subnormals,
#: the largest and smallest normals, values just around 1 (alpha 1 - ulp, 1 + ulp).
_EDGE = np.array(
    [0.0, 1.0, 0.5, 1e-45, 1e-40, 1.1754944e-38, 3.4028235e38, 0.99999994, 1.0000001, 0.1, 0.3],
    dtype=np.float32,
)


@settings(max_examples=60, deadline=None)
@given(
    n=st.sampled_from([1, 2, 3, 4, 5, 8]),
    seed=st.integers(0, 2**32 - 1),
    bg=st.tuples(
        *[st.sampled_from([0.0, 1.0, 0.5, 1e-300, 0.7, 1.0 - 2**-53])] * 3,
        st.sampled_from([0.0, 1.0, 0.5, 1.0 - 2**-53, 1e-300]),
    ),
)
def test_fused_kernel_shortcuts_equal_the_divisions(n, seed, bg):
    """The mean by a power-of-two reciprocal and ``rgb / 1 == rgb`` agree with numpy's
    divisions bit for bit on edge values (subnormal, huge, alpha a ulp off 1)."""
    rng = np.random.default_rng(seed)
    rgba = rng.choice(_EDGE, size=(3 * n, 4 * n, 4))
    with np.errstate(over="ignore"):  # huge samples can give inf pixels
        want = numpy_composite_resolve(rgba, n, bg)
    inf = ~np.isfinite(want).all(axis=2)
    if inf.any():  # refused (a style bug); the other pixels still compared, huge ones too
        with pytest.raises(ValueError, match="NaN or inf"):
            composite_resolve(rgba, n, bg)
        rgba[np.repeat(np.repeat(inf, n, axis=0), n, axis=1)] = 0.0
        want = numpy_composite_resolve(rgba, n, bg)
    got = composite_resolve(rgba, n, bg)
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))


def test_fused_kernel_is_identical_for_one_and_two_threads():
    rng = np.random.default_rng(5)
    rgba = random_samples(rng, 64, 48, 2)
    saved = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = composite_resolve(rgba, 2, (0.3, 0.3, 0.3, 1.0))
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = composite_resolve(rgba, 2, (0.3, 0.3, 0.3, 1.0))
    finally:
        numba.set_num_threads(saved)
    assert np.array_equal(one.view(np.uint32), two.view(np.uint32))


def test_fused_kernel_writes_into_out_and_checks_it():
    rng = np.random.default_rng(1)
    rgba = random_samples(rng, 8, 6, 2)
    out = np.full((8, 6, 4), 7.0, dtype=np.float32)
    assert composite_resolve(rgba, 2, (0, 0, 0, 1), out=out) is out
    assert np.array_equal(out, numpy_composite_resolve(rgba, 2, (0, 0, 0, 1)))
    with pytest.raises(ValueError, match=r"out: expected a writable C-contiguous \(8, 6, 4\)"):
        composite_resolve(rgba, 2, (0, 0, 0, 1), out=np.empty((8, 6, 4), np.float64))
    with pytest.raises(ValueError, match=r"rgba: shape \(16, 12, 4\) is not a whole number"):
        composite_resolve(rgba, 3, (0, 0, 0, 1))
    with pytest.raises(ValueError, match="rgba: expected an"):
        composite_resolve(rgba.astype(np.float64), 2, (0, 0, 0, 1))
    with pytest.raises(ValueError, match="background: expected 4 values"):
        composite_resolve(rgba, 2, (0, 0, 0))


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_fused_kernel_refuses_nan_and_inf(bad):
    rgba = np.zeros((4, 4, 4), np.float32)
    rgba[3, 1, 2] = bad
    with pytest.raises(ValueError, match="style 'toon' produced NaN or inf"):
        composite_resolve(rgba, 2, (0, 0, 0, 1), style_name="toon")


@pytest.mark.parametrize("n", [1, 2, 3])
def test_fused_kernel_finds_a_bad_sample_anywhere_in_the_block(n):
    """Each sample position of a pixel's n x n block (top and bottom sample rows: the spp-4 path
    reads them as two planes), each channel, in the last pixel of a row: one NaN or inf is
    refused. Everything is transparent, so the pixel's colour is the 0 of alpha 0 whatever its
    samples hold: only the per-sample test sees a bad colour channel."""
    for bad in (np.nan, np.inf):
        for j in range(n):
            for i in range(n):
                for c in range(4):
                    rgba = np.full((2 * n, 5 * n, 4), 0.5, np.float32)
                    rgba[..., 3] = 0.0
                    rgba[n + j, 4 * n + i, c] = bad
                    with pytest.raises(ValueError, match="produced NaN or inf"):
                        composite_resolve(rgba, n, (0.2, 0.3, 0.4, 0.0))
    rgba[n + j, 4 * n + i, c] = 0.0  # the same block without it: accepted, transparent
    assert not composite_resolve(rgba, n, (0.2, 0.3, 0.4, 0.0)).any()


def test_fused_kernel_refuses_a_pixel_that_overflows_float32():
    """Finite samples out of range (alpha 2 and -1.999) can resolve to an inf pixel: refused
    like a NaN sample (render builds its Image on this check, without another scan)."""
    rgba = np.zeros((2, 2, 4), np.float32)
    rgba[0, 0] = (3e38, 0.0, 0.0, 2.0)
    rgba[0, 1] = (0.0, 0.0, 0.0, -1.999)
    with pytest.raises(ValueError, match="style 'toon' produced NaN or inf"):
        composite_resolve(rgba, 2, (0, 0, 0, 0), style_name="toon")
    rgba[0, 0, 0] = 1.0  # the same samples in range of float32: accepted
    assert np.isfinite(composite_resolve(rgba, 2, (0, 0, 0, 0))).all()


def _bits(img):
    return img.rgba.view(np.uint32)


@pytest.mark.parametrize("spp", [1, 4])
@pytest.mark.parametrize("style", ["toon", "smooth"])
def test_context_frames_equal_render(plane_scene, style, spp):
    ctx = RenderContext(plane_scene, style, 40, 30, spp)
    other = Camera.look_at((0.5, 0.3, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 45.0, 0.1, 100.0)
    for cam in (None, other, None):
        got = ctx.render(cam, copy=True)
        want = render(plane_scene, style, 40, 30, spp, camera=cam)
        assert np.array_equal(_bits(got), _bits(want))
        assert set(got.timings) == set(want.timings)


def test_context_reuses_its_output_buffer(plane_scene):
    ctx = RenderContext(plane_scene, "toon", 32, 24, 4)
    first = ctx.render()
    kept = ctx.render(copy=True)
    second = ctx.render()
    assert second.rgba is first.rgba  # the context's buffer, overwritten frame to frame
    assert kept.rgba is not second.rgba
    assert np.array_equal(kept.rgba, second.rgba)
    _, gb = ctx.render(return_gbuffer=True)
    assert gb.sample_shape == (48, 64)
    _, gb2 = ctx.render(return_gbuffer=True)
    assert gb2 is gb  # rasterize(..., out=gb): the G-buffer's arrays are overwritten in place
    assert all(gb2[name] is gb[name] for name in gb)


def test_context_checks_its_arguments(plane_scene):
    with pytest.raises(ValueError, match="width"):
        RenderContext(plane_scene, "toon", 0, 10)
    ctx = RenderContext(plane_scene, "toon", 8, 8)
    with pytest.raises(TypeError, match="camera: expected a refnpr.raster.Camera"):
        ctx.render("front")
    with pytest.raises(TypeError, match="copy: expected a bool"):
        ctx.render(copy=1)
    assert "toon" in repr(ctx) and "8x8" in repr(ctx)


@pytest.mark.parametrize("scene, style", WARM_ROWS)  # every style, on its benchmark scene
@pytest.mark.parametrize("spp", [1, 4])
def test_lent_sample_buffer_is_written_in_full(scene, style, spp):
    """Each style writes every sample of the buffer a context lends it (``rgba_out``): frames
    over a buffer poisoned with NaN still equal ``render``, and the buffer is reused."""
    ctx = RenderContext(scene, style, 48, 36, spp)
    ctx.render()
    buf = ctx._samples
    buf[...] = np.nan
    got = ctx.render(copy=True)
    assert ctx._samples is buf
    assert np.array_equal(_bits(got), _bits(render(scene, style, 48, 36, spp)))


def test_rgba_out_lends_a_matching_spare_once():
    from refnpr.styles import ShadeContext

    spare = np.empty((6, 8, 4), np.float32)
    ctx = ShadeContext(None, None, [np.empty((6, 8, 4), np.float64), spare])
    assert ctx.rgba_out((6, 8)) is spare
    again = ctx.rgba_out((6, 8))
    assert again is not spare and again.shape == (6, 8, 4) and again.dtype == np.float32
    other = ShadeContext(None, None, [np.empty((6, 8, 4), np.float32)])
    assert other.rgba_out((5, 8)).shape == (5, 8, 4)  # wrong shape: a new array
    assert ShadeContext(None, None).rgba_out((2, 3)).shape == (2, 3, 4)
