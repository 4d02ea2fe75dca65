"""numba kernels of ``refnpr.render``: compositing, box resolve and unpremultiply in one pass.

Private: :func:`refnpr.render.composite_resolve` validates the arrays and calls these. The
arithmetic is the float64 arithmetic of the numpy code it replaces, operation for operation, so
the result is bit-identical to it (and to itself for any thread count: each output row is owned
by one thread, the samples of a pixel are summed in a fixed order).
"""

from __future__ import annotations

import numpy as np

from ._jit import banded


@banded("out")
def composite_resolve(lo, hi, rgba, n, bg, out, bad_rows):
    """Composite per sample over ``bg``, box-resolve n x n samples, unpremultiply.

    rgba : (n H, n W, 4) float32, straight alpha per sample, as the style returned it.
    n : int, samples per pixel along each axis.
    bg : (4,) float64, straight-alpha background.
    out : (H, W, 4) float32, written: straight-alpha pixels.
    bad_rows : (H,) uint8, written: 1 where a sample or a pixel of that output row is NaN or
        inf (a pixel overflows float32 where finite samples are out of range), so a row of 0s
        means every pixel written is finite.

    Per sample (float64): ``over = (rgb * a, a) + (bg_rgb * bg_a, bg_a) * (1 - a)``; per pixel the
    n x n ``over`` values summed sample row by sample row, left to right, then divided by n * n
    (numpy's ``mean(axis=(1, 3))`` order); ``rgb / alpha`` where alpha > 0, else 0.

    Divisions are the costly part (double division is not pipelined on the CPUs measured): by a
    power-of-two n * n the mean is a multiplication by its exact reciprocal, and where alpha is
    exactly 1 (every pixel over an opaque background) ``rgb / alpha`` is ``rgb``. Both give the
    same bits as the division; at n = 2 (spp 4) the sample loop is written out (26 -> 20 ms at
    1080p, the same operations in the same order). A sample is NaN or inf exactly where ``(r + g + b + a) * 0`` is
    not 0 (the float64 sum of four float32 values cannot overflow), and so is a stored pixel.
    """
    w = out.shape[1]
    bg0 = bg[0] * bg[3]
    bg1 = bg[1] * bg[3]
    bg2 = bg[2] * bg[3]
    bg3 = bg[3]
    count = float(n * n)
    exact_inverse = (n * n) & (n * n - 1) == 0  # a power of two: x / count == x * (1 / count)
    inverse = 1.0 / count
    for y in range(lo, hi):
        probe = 0.0  # stays 0.0 unless a sample is NaN or inf
        for x in range(w):
            if n == 1:  # one sample: no sums (the same values as the loop below gives)
                r = np.float64(rgba[y, x, 0])
                g = np.float64(rgba[y, x, 1])
                b = np.float64(rgba[y, x, 2])
                a = np.float64(rgba[y, x, 3])
                probe += (r + g + b + a) * 0.0
                one_a = 1.0 - a
                s0 = r * a + bg0 * one_a
                s1 = g * a + bg1 * one_a
                s2 = b * a + bg2 * one_a
                s3 = a + bg3 * one_a
            elif n == 2:  # the loop below written out (same operations, same order)
                r0 = y * 2
                c0 = x * 2
                r = np.float64(rgba[r0, c0, 0])
                g = np.float64(rgba[r0, c0, 1])
                b = np.float64(rgba[r0, c0, 2])
                a = np.float64(rgba[r0, c0, 3])
                probe += (r + g + b + a) * 0.0
                one_a = 1.0 - a
                s0 = r * a + bg0 * one_a
                s1 = g * a + bg1 * one_a
                s2 = b * a + bg2 * one_a
                s3 = a + bg3 * one_a
                for k in range(1, 4):
                    row = r0 + (k >> 1)
                    col = c0 + (k & 1)
                    r = np.float64(rgba[row, col, 0])
                    g = np.float64(rgba[row, col, 1])
                    b = np.float64(rgba[row, col, 2])
                    a = np.float64(rgba[row, col, 3])
                    probe += (r + g + b + a) * 0.0
                    one_a = 1.0 - a
                    s0 += r * a + bg0 * one_a
                    s1 += g * a + bg1 * one_a
                    s2 += b * a + bg2 * one_a
                    s3 += a + bg3 * one_a
                s0 = s0 * 0.25  # 1 / 4 exactly: the same as / 4
                s1 = s1 * 0.25
                s2 = s2 * 0.25
                s3 = s3 * 0.25
            else:
                s0 = 0.0
                s1 = 0.0
                s2 = 0.0
                s3 = 0.0
                for j in range(n):
                    row = y * n + j
                    for i in range(n):
                        col = x * n + i
                        r = np.float64(rgba[row, col, 0])
                        g = np.float64(rgba[row, col, 1])
                        b = np.float64(rgba[row, col, 2])
                        a = np.float64(rgba[row, col, 3])
                        probe += (r + g + b + a) * 0.0
                        one_a = 1.0 - a
                        o0 = r * a + bg0 * one_a
                        o1 = g * a + bg1 * one_a
                        o2 = b * a + bg2 * one_a
                        o3 = a + bg3 * one_a
                        if j == 0 and i == 0:
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
            if s3 == 1.0:  # x / 1 == x
                p0 = np.float32(s0)
                p1 = np.float32(s1)
                p2 = np.float32(s2)
            elif s3 > 0.0:
                p0 = np.float32(s0 / s3)
                p1 = np.float32(s1 / s3)
                p2 = np.float32(s2 / s3)
            else:
                p0 = np.float32(0.0)
                p1 = np.float32(0.0)
                p2 = np.float32(0.0)
            p3 = np.float32(s3)
            # and the pixel as stored: float32 overflows where a finite sample is out of range
            probe += ((np.float64(p0) + np.float64(p1)) + (np.float64(p2) + np.float64(p3))) * 0.0
            out[y, x, 0] = p0
            out[y, x, 1] = p1
            out[y, x, 2] = p2
            out[y, x, 3] = p3
        bad_rows[y] = 0 if probe == 0.0 else 1
