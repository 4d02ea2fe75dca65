"""numba kernels of ``refnpr.render``: compositing, box resolve and unpremultiply in one pass;
and of ``refnpr.image``: a PNG's row filters undone (:func:`png_unfilter`).

Private: :func:`refnpr.render.composite_resolve` validates the arrays and calls the first,
:func:`refnpr.image.decode_png16` the PNG stream and the second. The compositing's float64
arithmetic is numpy's, operation for operation, so the result is bit-identical to it, for any
thread count (each output row is owned by one thread; a pixel's samples are summed in one order).
"""

from __future__ import annotations

import numpy as np

from ._jit import banded, njit, specialised


@njit(inline="always")
def _over(src, i, bg0, bg1, bg2, bg3):
    """The sample at ``src[i:i + 4]`` (float32, straight alpha) premultiplied over the
    premultiplied background, in float64, and whether the sample is NaN or inf."""
    r = np.float64(src[i])
    g = np.float64(src[i + 1])
    b = np.float64(src[i + 2])
    a = np.float64(src[i + 3])
    one_a = 1.0 - a
    bad = (r + g + b + a) * 0.0 != 0.0
    return r * a + bg0 * one_a, g * a + bg1 * one_a, b * a + bg2 * one_a, a + bg3 * one_a, bad


@njit(inline="always")
def _unpremultiply(s0, s1, s2, s3):
    """Straight-alpha float32 pixel of a premultiplied mean ``(s0, s1, s2, s3)`` (float64).

    ``rgb / alpha`` where alpha > 0, else 0, branch-free (the quotient is computed either way
    and selected, so a loop of these vectorizes).
    """
    pos = s3 > 0.0
    d = s3 if pos else 1.0
    return (
        np.float32(s0 / d if pos else 0.0),
        np.float32(s1 / d if pos else 0.0),
        np.float32(s2 / d if pos else 0.0),
        np.float32(s3),
    )


@njit(inline="always")
def _nonfinite(p0, p1, p2, p3):
    """Whether a float32 pixel as stored holds NaN or inf (finite samples out of range can
    overflow float32); their float64 sum cannot overflow."""
    return ((np.float64(p0) + np.float64(p1)) + (np.float64(p2) + np.float64(p3))) * 0.0 != 0.0


@njit
def _pair_means(top, bot, mean, w):
    """``mean[x] = (((top[2x] + top[2x + 1]) + bot[2x]) + bot[2x + 1]) * 0.25`` (1D float64
    views; 0.25 = 1 / 4 exactly, the same bits as dividing by 4)."""
    for x in range(w):
        k = 2 * x
        mean[x] = (((top[k] + top[k + 1]) + bot[k]) + bot[k + 1]) * 0.25


@njit
def _store_row(q0, q1, q2, q3, dst, w):
    """Unpremultiply a row of planar means (1D float64 views) into ``dst (w * 4,)`` float32;
    whether a stored pixel is NaN or inf."""
    bad = False
    for x in range(w):
        p0, p1, p2, p3 = _unpremultiply(q0[x], q1[x], q2[x], q3[x])
        bad |= _nonfinite(p0, p1, p2, p3)
        dst[4 * x] = p0
        dst[4 * x + 1] = p1
        dst[4 * x + 2] = p2
        dst[4 * x + 3] = p3
    return bad


@specialised
def composite_resolve_for(case):
    """:func:`composite_resolve` for one ``case``: 1 (n = 1), 2 (n = 2) or 0 (any n, the
    general loop); numba prunes the other cases before typing them, so spp 1 and spp 4 frames
    each compile one (:func:`refnpr._jit.specialised`)."""

    @banded("out")
    def composite_resolve(lo, hi, rgba, n, bg, out, bad_rows):
        """Composite per sample over ``bg``, box-resolve n x n samples, unpremultiply.

        rgba (n H, n W, 4) float32 C-contiguous (rows read as flat views), n samples per pixel
        along each axis, bg (4,) float64 straight alpha; writes out (H, W, 4) float32 and
        bad_rows (H,) uint8: 1 where a sample or a pixel of that row is NaN or inf (a pixel
        overflows float32 where finite samples are out of range). A pixel's n x n values are
        summed sample row by sample row, left to right (numpy's ``mean(axis=(1, 3))`` order).

        Divisions are the costly part (double division is not pipelined on the CPUs measured): by a
        power-of-two n * n the mean is a multiplication by its exact reciprocal (the same bits as
        the division). A sample is NaN or inf exactly where ``(r + g + b + a) * 0`` is not 0 (the
        float64 sum of four float32 values cannot overflow), and so is a stored pixel; a row's flag
        is the OR of those tests.

        n = 1 and n = 2 (spp 1 and 4, the usual cases) run over each row as a flat view
        (``rgba[y].reshape(-1)``), branch-free: ``rgb / alpha`` is computed for every pixel and
        selected where alpha > 0 (``x / 1 == x``, so opaque pixels keep their bits). LLVM vectorizes
        the n = 1 loop (``vdivpd``, ``vcvtps2pd`` on 4 lanes; over 2D indexing, with an alpha == 1
        shortcut branch and a float sum as the NaN probe, it stayed scalar): 12 -> 2.6 ms at 1080p.
        At n = 2 the over values of a row pair go to planar float64 scratch, then the means to
        planar scratch per channel (``_pair_means``), then the pixels are stored (``_store_row``):
        each loop with one or two inputs vectorizes, which one loop over the eight planes did not
        (30 -> 18 ms with the first pass alone, -> 13 ms with all three, at 1080p spp 4).
        The same operations in the same order as the general loop below, so the same bits
        (``tests/render/test_render_context.py`` compares every n with numpy bit for bit).
        """
        w = out.shape[1]
        bg0 = bg[0] * bg[3]
        bg1 = bg[1] * bg[3]
        bg2 = bg[2] * bg[3]
        bg3 = bg[3]
        if case == 1:
            for y in range(lo, hi):
                src = rgba[y].reshape(w * 4)
                dst = out[y].reshape(w * 4)
                bad = False
                for x in range(w):
                    s0, s1, s2, s3, bad_s = _over(src, 4 * x, bg0, bg1, bg2, bg3)
                    p0, p1, p2, p3 = _unpremultiply(s0, s1, s2, s3)
                    bad |= bad_s | _nonfinite(p0, p1, p2, p3)
                    dst[4 * x] = p0
                    dst[4 * x + 1] = p1
                    dst[4 * x + 2] = p2
                    dst[4 * x + 3] = p3
                bad_rows[y] = 1 if bad else 0
        elif case == 2:
            scr = np.empty((8, 2 * w))  # per sample of a row pair: the 4 channels of over, planar
            t0, t1, t2, t3 = scr[0], scr[1], scr[2], scr[3]
            u0, u1, u2, u3 = scr[4], scr[5], scr[6], scr[7]
            means = np.empty((4, w))  # per pixel: the 4 channels of the mean, planar
            q0, q1, q2, q3 = means[0], means[1], means[2], means[3]
            for y in range(lo, hi):
                top = rgba[2 * y].reshape(w * 8)
                bot = rgba[2 * y + 1].reshape(w * 8)
                dst = out[y].reshape(w * 4)
                bad = False
                for j in range(2 * w):  # over per sample, both rows (planar stores: vectorized)
                    t0[j], t1[j], t2[j], t3[j], bad_t = _over(top, 4 * j, bg0, bg1, bg2, bg3)
                    u0[j], u1[j], u2[j], u3[j], bad_b = _over(bot, 4 * j, bg0, bg1, bg2, bg3)
                    bad |= bad_t | bad_b
                _pair_means(t0, u0, q0, w)  # sample row by sample row, left to right
                _pair_means(t1, u1, q1, w)
                _pair_means(t2, u2, q2, w)
                _pair_means(t3, u3, q3, w)
                bad |= _store_row(q0, q1, q2, q3, dst, w)
                bad_rows[y] = 1 if bad else 0
        else:
            count = float(n * n)
            # a power of two: x / count == x * (1 / count)
            exact_inverse = (n * n) & (n * n - 1) == 0
            inverse = 1.0 / count
            flat = rgba.reshape(rgba.size)
            row_len = 4 * w * n  # floats per sample row
            for y in range(lo, hi):
                bad = False
                for x in range(w):
                    s0 = 0.0
                    s1 = 0.0
                    s2 = 0.0
                    s3 = 0.0
                    for j in range(n):  # sample row by sample row, left to right
                        base = (y * n + j) * row_len + 4 * x * n
                        for i in range(n):
                            o0, o1, o2, o3, bad_s = _over(flat, base + 4 * i, bg0, bg1, bg2, bg3)
                            bad |= bad_s
                            if j == 0 and i == 0:  # not 0.0 + o: that would turn -0.0 into 0.0
                                s0 = o0
                                s1 = o1
                                s2 = o2
                                s3 = o3
                            else:
                                s0 += o0
                                s1 += o1
                                s2 += o2
                                s3 += o3
                    if exact_inverse:
                        s0 = s0 * inverse
                        s1 = s1 * inverse
                        s2 = s2 * inverse
                        s3 = s3 * inverse
                    else:
                        s0 = s0 / count
                        s1 = s1 / count
                        s2 = s2 / count
                        s3 = s3 / count
                    p0, p1, p2, p3 = _unpremultiply(s0, s1, s2, s3)
                    bad |= _nonfinite(p0, p1, p2, p3)
                    out[y, x, 0] = p0
                    out[y, x, 1] = p1
                    out[y, x, 2] = p2
                    out[y, x, 3] = p3
                bad_rows[y] = 1 if bad else 0

    return composite_resolve


@njit
def png_unfilter(rows, bpp):
    """Undo a PNG image's row filters in place (PNG sec. 9: None, Sub, Up, Average, Paeth):
    ``rows (h, 1 + n) uint8``, column 0 each row's filter type, the rest its filtered bytes
    (``bpp`` bytes per pixel). Returns the first row whose filter type is not 0-4, else -1.
    Private: :func:`refnpr.image.decode_png16` checks the stream and calls it."""
    h, n = rows.shape
    for y in range(h):
        kind = rows[y, 0]
        if kind > 4:
            return y
        if kind == 0:
            continue
        for x in range(1, n):
            a = np.int64(rows[y, x - bpp]) if x > bpp else 0  # the byte to the left
            b = np.int64(rows[y - 1, x]) if y > 0 else 0  # the byte above
            c = np.int64(rows[y - 1, x - bpp]) if x > bpp and y > 0 else 0  # above left
            if kind == 1:  # Sub
                p = a
            elif kind == 2:  # Up
                p = b
            elif kind == 3:  # Average
                p = (a + b) >> 1
            else:  # Paeth
                q = a + b - c
                pa, pb, pc = abs(q - a), abs(q - b), abs(q - c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            rows[y, x] = np.uint8((np.int64(rows[y, x]) + p) & 0xFF)
    return -1
