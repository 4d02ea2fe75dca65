"""The second round of TAMISS speed kernels against the numpy expressions and naive loops they
replace, bit for bit: the strip bboxes, the strip raster (its per-pixel edge rejection and texel
wrap), the mean speed and the centreline of the fits, and the strip sides of the extrusion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.formulas.tamiss import StrokeFit, StrokeStrip
from refnpr.styles.tamiss import _kernels as K
from refnpr.styles.tamiss.raster import brush_texture, rasterize_strips
from refnpr.styles.tamiss.strokes import Strips, centreline, mean_speed

from ._threads import outputs_per_thread_count


def _bbox_numpy(left, right, nh, nw):
    """The numpy formula raster.py used before ``strip_bbox``."""
    allx = np.concatenate([left[..., 0], right[..., 0]], axis=1)
    ally = np.concatenate([left[..., 1], right[..., 1]], axis=1)
    finite = np.all(np.isfinite(allx), axis=1) & np.all(np.isfinite(ally), axis=1)
    bbox = np.zeros((left.shape[0], 4), dtype=np.int64)
    with np.errstate(invalid="ignore"):
        bbox[:, 0] = np.clip(np.floor(np.where(finite, allx.min(1), 0)), -1, nw)
        bbox[:, 1] = np.clip(np.floor(np.where(finite, ally.min(1), 0)), -1, nh)
        bbox[:, 2] = np.clip(np.floor(np.where(finite, allx.max(1), -1)), -1, nw)
        bbox[:, 3] = np.clip(np.floor(np.where(finite, ally.max(1), -1)), -1, nh)
    bbox[:, 0] = np.maximum(bbox[:, 0], 0)
    bbox[:, 1] = np.maximum(bbox[:, 1], 0)
    bbox[:, 2] = np.minimum(bbox[:, 2], nw - 1)
    bbox[:, 3] = np.minimum(bbox[:, 3], nh - 1)
    bbox[~finite] = (0, 0, -1, -1)
    return bbox


def _random_strips(rng, P, Kv, size, half=(0.3, 2.0)):
    centre = rng.uniform(2, size - 2, (P, 1, 2))
    direction = rng.normal(size=(P, 1, 2))
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    mid = centre + np.linspace(-6, 6, Kv)[None, :, None] * direction
    mid = mid + rng.normal(scale=0.4, size=(P, Kv, 2)).cumsum(1)
    normal = np.stack([-direction[..., 1], direction[..., 0]], -1)
    h = rng.uniform(*half, (P, 1, 1))
    return mid + h * normal, mid - h * normal


def test_strip_bbox_equals_the_numpy_formula():
    rng = np.random.default_rng(3)
    left, right = _random_strips(rng, 400, 7, 40)
    left[::13] *= 30.0  # far off the grid on every side
    left[5::31, 2, 0] = 1e19  # beyond int64
    right[6::37, 1, 1] = -1e300
    right[1::17] -= 80.0
    left[2::19, 3, 0] = np.nan
    right[3::23, 5, 1] = np.inf
    left[4::29, :, 1] = -np.inf
    left[5::31] += 1e12
    left[6::37] = np.round(left[6::37])  # vertices on sample borders
    for nh, nw in ((40, 44), (1, 1), (7, 300)):
        out = np.empty((left.shape[0], 4), dtype=np.int64)
        K.strip_bbox(left, right, nh, nw, out)
        assert np.array_equal(out, _bbox_numpy(left, right, nh, nw))
    assert np.any(out[:, 2] < out[:, 0]) and np.any(out[:, 2] >= out[:, 0])


def _edge(ax, ay, bx, by, px, py):
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


def _naive_raster(left, right, tv, shape, aa, tex, wrap):
    """Every sub-sample of every pixel of each triangle's bbox tested, the brush coordinates from
    the triangle whose barycentric minimum at the pixel centre is largest, bilinear brush with
    Python's % for the wrap: the arithmetic of raster_strips written as plain loops."""
    nh, nw = shape
    alpha = np.zeros(shape)
    touched = np.zeros(shape, dtype=np.int32)
    inv = 1.0 / aa
    hb, wb = tex.shape
    bbox = _bbox_numpy(left, right, nh, nw)
    for pc in range(left.shape[0]):
        x0, y0, x1, y1 = (int(v) for v in bbox[pc])
        inside, best, bu, bv = {}, {}, {}, {}
        for seg in range(left.shape[1] - 1):
            L, R = left[pc], right[pc]
            for tri in range(2):
                if tri == 0:
                    (ax, ay), (bx, by), (cx, cy) = L[seg], R[seg], L[seg + 1]
                    ta, tb, tc = tv[pc, seg], tv[pc, seg], tv[pc, seg + 1]
                    va, vb, vc = 0.0, 1.0, 0.0
                else:
                    (ax, ay), (bx, by), (cx, cy) = R[seg], R[seg + 1], L[seg + 1]
                    ta, tb, tc = tv[pc, seg], tv[pc, seg + 1], tv[pc, seg + 1]
                    va, vb, vc = 1.0, 1.0, 0.0
                ax, ay, bx, by, cx, cy = (float(v) for v in (ax, ay, bx, by, cx, cy))
                area = _edge(ax, ay, bx, by, cx, cy)
                if abs(area) < 1e-12:
                    continue
                sg = 1.0 if area > 0.0 else -1.0
                tx0 = max(x0, math.floor(min(ax, bx, cx)))
                tx1 = min(x1, math.floor(max(ax, bx, cx)))
                ty0 = max(y0, math.floor(min(ay, by, cy)))
                ty1 = min(y1, math.floor(max(ay, by, cy)))
                for y in range(ty0, ty1 + 1):
                    for x in range(tx0, tx1 + 1):
                        bits = inside.setdefault((y, x), set())
                        for sj in range(aa):
                            py = y + (sj + 0.5) * inv
                            for si in range(aa):
                                px = x + (si + 0.5) * inv
                                if (
                                    _edge(bx, by, cx, cy, px, py) * sg >= 0.0
                                    and _edge(cx, cy, ax, ay, px, py) * sg >= 0.0
                                    and _edge(ax, ay, bx, by, px, py) * sg >= 0.0
                                ):
                                    bits.add((sj, si))
                        w0 = _edge(bx, by, cx, cy, x + 0.5, y + 0.5) / area
                        w1 = _edge(cx, cy, ax, ay, x + 0.5, y + 0.5) / area
                        w2 = 1.0 - w0 - w1
                        m = min(w0, w1, w2)
                        if m > best.get((y, x), -math.inf):
                            best[(y, x)] = m
                            w0c, w1c, w2c = max(w0, 0.0), max(w1, 0.0), max(w2, 0.0)
                            ws = w0c + w1c + w2c
                            bu[(y, x)] = (w0c * ta + w1c * tb + w2c * tc) / ws
                            bv[(y, x)] = (w0c * va + w1c * vb + w2c * vc) / ws
        for (y, x), bits in sorted(inside.items()):
            if not bits:
                continue
            cov = len(bits) / (aa * aa)
            fu = bu[(y, x)] * wb - 0.5
            fv = min(max(bv[(y, x)], 0.0), 1.0) * hb - 0.5
            iu, iv = math.floor(fu), math.floor(fv)
            au, av = fu - iu, fv - iv
            val = 0.0
            for dv in range(2):
                rr = min(max(iv + dv, 0), hb - 1)
                wv = av if dv == 1 else 1.0 - av
                for du in range(2):
                    cc = (iu + du) % wb if wrap else min(max(iu + du, 0), wb - 1)
                    wu = au if du == 1 else 1.0 - au
                    val += wu * wv * float(tex[rr, cc])
            a = cov * 1.0 * val
            alpha[y, x] = alpha[y, x] + a * (1.0 - alpha[y, x])
            touched[y, x] += 1
    return alpha, touched


@pytest.mark.parametrize(
    "brush, aa, t_range",
    [(None, 4, (0, 1)), ("pencil", 4, (-2.5, 3.5)), ("dry", 3, (-0.5, 1.5)), ("pen", 2, (0, 1))],
)
def test_strip_raster_equals_naive_loops_bitwise(brush, aa, t_range):
    rng = np.random.default_rng(aa)
    P, Kv = 10, 6
    left, right = _random_strips(rng, P, Kv, 36)
    left[0] = np.round(left[0] * 4) / 4  # vertices on sub-sample rows and columns
    right[0] = np.round(right[0] * 4) / 4
    left[1, 2] = right[1, 2]  # a degenerate pair: zero-area triangles
    tv = np.sort(rng.uniform(*t_range, (P, Kv)), axis=1)
    strips = Strips(
        strip=StrokeStrip(left=left, right=right, t=tv),
        stroke=np.arange(P),
        ids=np.arange(P),
        width=np.ones(P),
    )
    alpha, pieces = rasterize_strips(strips, (40, 44), 1, aa=aa, brush=brush)
    tex, wrap = brush_texture(brush)
    ref_alpha, ref_pieces = _naive_raster(left, right, tv, (40, 44), aa, tex, wrap)
    assert np.array_equal(pieces, ref_pieces)
    assert np.array_equal(alpha, ref_alpha)
    assert pieces.max() >= 2 and 0 < np.mean(alpha > 0) < 0.9


@pytest.mark.parametrize("far", [1e19, -1e19, 1e300, -1e300, 9.3e18])
def test_strip_raster_with_a_vertex_beyond_int64_stays_in_the_grid(far):
    """A vertex outside the int64 range (a diverged fit, a hostile caller): the triangle bounds
    are clamped before they become integers, so nothing is written outside the grid and the
    rest of the image equals the strips without that piece's far triangles."""
    rng = np.random.default_rng(11)
    left, right = _random_strips(rng, 4, 5, 30)
    tv = np.sort(rng.uniform(0, 1, (4, 5)), axis=1)
    left[1, 4] = (far, 12.0)  # x far off
    right[2, 0] = (9.0, far)  # y far off

    def run(lft, rgt):
        strips = Strips(
            strip=StrokeStrip(left=lft, right=rgt, t=tv),
            stroke=np.arange(4),
            ids=np.arange(4),
            width=np.ones(4),
        )
        return rasterize_strips(strips, (32, 34), 1, aa=4, brush=None)

    alpha, pieces = run(left, right)
    assert alpha.shape == (32, 34) and np.all(np.isfinite(alpha))
    assert np.all((alpha >= 0) & (alpha <= 1)) and pieces.max() <= 4
    ref_alpha, ref_pieces = run(left[[0, 3]], right[[0, 3]])  # the two untouched pieces
    untouched = pieces == ref_pieces  # samples no far piece reached agree exactly
    assert untouched.mean() > 0.3
    assert np.array_equal(alpha[untouched & (pieces <= 2)], ref_alpha[untouched & (pieces <= 2)])
    # one wedge (5, 10), (5, 14), (far, 12): it reaches the grid's edge on row 12 (towards +x),
    # or covers nothing in the grid beyond column 5 (towards -x)
    one = Strips(
        strip=StrokeStrip(
            left=np.array([[[5.0, 10.0], [far, 12.0]]]),
            right=np.array([[[5.0, 14.0], [6.0, 14.0]]]),
            t=np.array([[0.0, 1.0]]),
        ),
        stroke=np.arange(1),
        ids=np.arange(1),
        width=np.ones(1),
    )
    wedge, _ = rasterize_strips(one, (32, 34), 1, aa=4, brush=None)
    if far > 0:
        assert wedge[12, 33] > 0.5 and wedge[12, 20] > 0.5 and wedge[:, :5].max() == 0.0
    else:
        assert wedge[12, 0] > 0.5 and wedge[12, 4] > 0.5 and wedge[:, 7:].max() == 0.0


def _mean_speed_numpy(fit):
    lo = np.asarray(fit.t_min, dtype=np.float64).reshape(-1, 1)
    hi = np.asarray(fit.t_max, dtype=np.float64).reshape(-1, 1)
    ts = lo + (hi - lo) * np.linspace(0.0, 1.0, 17)
    px, py = (np.asarray(a, dtype=np.float64) for a in fit.evaluate(ts))
    arc = np.sum(np.hypot(np.diff(px, axis=1), np.diff(py, axis=1)), axis=1)
    span = (hi - lo)[:, 0]
    return np.where(span > 0, arc / np.where(span > 0, span, 1.0), 0.0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_mean_speed_kernel_equals_the_numpy_formula(dtype):
    rng = np.random.default_rng(7)
    S = 3000
    scale = rng.choice([1e-3, 1.0, 1e3, 1e30], (S, 4))
    c = (rng.normal(size=(S, 4)) * scale).astype(dtype)
    c[::50, 2] = np.nan
    c[1::70, 1] = np.inf
    lo = rng.uniform(-0.2, 1.0, S).astype(dtype)
    hi = (lo + rng.choice([0.0, 1e-7, 0.01, 0.5], S)).astype(dtype)
    fit = StrokeFit(c_x=c, c_y=c[::-1].copy(), c_v=c, t_min=lo, t_max=hi, count=np.full(S, 9))
    with np.errstate(all="ignore"):
        got, ref = mean_speed(fit), _mean_speed_numpy(fit)
    assert got.dtype == np.float64 and np.array_equal(got, ref, equal_nan=True)
    assert np.isnan(ref).any() and (ref == 0).any() and (ref > 0).any()


def _centreline_numpy(fit, t, speed):
    """The numpy code of ``strokes.centreline`` (through ``StrokeFit.evaluate``/``derivative``)."""
    lo = np.asarray(fit.t_min, dtype=np.float64)[:, None]
    hi = np.asarray(fit.t_max, dtype=np.float64)[:, None]
    tc = np.clip(t, lo, hi)
    x, y = (np.asarray(a, dtype=np.float64) for a in fit.evaluate(tc))
    dx, dy = (np.asarray(a, dtype=np.float64) for a in fit.derivative(tc))
    (x0, y0), (x1, y1) = fit.evaluate(lo), fit.evaluate(hi)
    fx = np.asarray(x1, dtype=np.float64) - np.asarray(x0, dtype=np.float64)
    fy = np.asarray(y1, dtype=np.float64) - np.asarray(y0, dtype=np.float64)
    n, fn = np.hypot(dx, dy), np.hypot(fx, fy)
    ok, fok = n > 1e-12, fn > 1e-12
    tx = np.where(ok, dx / np.where(ok, n, 1), np.where(fok, fx / np.where(fok, fn, 1), 1.0))
    ty = np.where(ok, dy / np.where(ok, n, 1), np.where(fok, fy / np.where(fok, fn, 1), 0.0))
    below, above = t < lo, t > hi
    if np.any(below | above):
        d_out = np.where(below, t - lo, np.where(above, t - hi, 0.0)) * speed[:, None]
        x, y = x + d_out * tx, y + d_out * ty
    return x, y, tx, ty


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("outside", [False, True])
def test_centreline_kernel_equals_the_fit_methods(dtype, outside):
    rng = np.random.default_rng(13)
    S, Kv = 2000, 12
    c = (rng.normal(size=(S, 4)) * rng.choice([1e-3, 1.0, 1e3, 1e20], (S, 4))).astype(dtype)
    c[::40, 2] = np.nan
    c[1::60, 3] = np.inf
    c[2::30] = 0.0  # zero derivative: the chord, then (1, 0)
    lo = rng.uniform(-0.2, 1.0, S).astype(dtype)
    hi = (lo + rng.choice([0.0, 1e-7, 0.01, 0.5], S)).astype(dtype)
    fit = StrokeFit(c_x=c, c_y=c[::-1].copy(), c_v=c, t_min=lo, t_max=hi, count=np.full(S, 9))
    t = np.sort(rng.uniform(-0.5, 1.5, (S, Kv)), axis=1)
    if not outside:
        t = np.clip(t, lo.astype(np.float64)[:, None], hi.astype(np.float64)[:, None])
    speed = rng.choice([0.0, 1.0, 30.0, np.inf], S)
    with np.errstate(all="ignore"):
        got = centreline(fit, t, speed=speed)
        ref = _centreline_numpy(fit, t, speed)
    for a, b in zip(got, ref, strict=True):
        assert a.dtype == np.float64 and np.array_equal(a, b, equal_nan=True)
    assert np.isfinite(ref[0]).mean() > 0.5


def test_centreline_rejects_non_finite_t_as_before():
    fit = StrokeFit(
        c_x=np.ones((2, 4)), c_y=np.ones((2, 4)), c_v=np.ones((2, 4)),
        t_min=np.zeros(2), t_max=np.ones(2), count=np.full(2, 9),
    )  # fmt: skip
    with pytest.raises(ValueError, match="finite"):
        centreline(fit, np.array([[0.5, np.nan], [0.1, 0.2]]), speed=np.ones(2))


def test_strip_sides_equal_the_numpy_expressions():
    rng = np.random.default_rng(11)
    S, Kv = 200, 9
    a = rng.normal(size=(S, Kv)) * rng.choice([0.0, 1e-13, 1.0, 1e200], (S, Kv))
    ux, uy = np.cos(a), np.sin(a)
    ux[::17, 3] = np.nan
    x, y, h = (rng.normal(size=(S, Kv)) * 100 for _ in range(3))
    left, right = np.empty((S, Kv, 2)), np.empty((S, Kv, 2))
    K.strip_sides((x, y), (-uy, ux), h, (left, right))
    with np.errstate(invalid="ignore"):
        ref_l = np.stack([x + h * -uy, y + h * ux], axis=-1)
        ref_r = np.stack([x - h * -uy, y - h * ux], axis=-1)
    assert np.array_equal(left, ref_l, equal_nan=True)
    assert np.array_equal(right, ref_r, equal_nan=True)


_SCRIPT = """
import json, numpy as np
from refnpr.formulas.tamiss import StrokeFit, StrokeStrip
from refnpr.styles.tamiss.raster import rasterize_strips
from refnpr.styles.tamiss.strokes import Strips, centreline, mean_speed

rng = np.random.default_rng(5)
P, Kv = 300, 8
mid = rng.uniform(0, 90, (P, 1, 2)) + rng.normal(size=(P, Kv, 2)).cumsum(1)
n = rng.normal(size=(P, 1, 2))
strips = Strips(strip=StrokeStrip(left=mid + n, right=mid - n,
                                  t=np.sort(rng.uniform(-1, 2, (P, Kv)), 1)),
                stroke=np.arange(P), ids=np.arange(P), width=np.ones(P))
ink, pieces = rasterize_strips(strips, (90, 96), 1, aa=4, brush="pencil")
c = rng.normal(size=(P, 4)).astype(np.float32)
lo = rng.uniform(0, 0.5, P).astype(np.float32)
fit = StrokeFit(c_x=c, c_y=c[::-1].copy(), c_v=c, t_min=lo, t_max=lo + np.float32(0.3),
                count=np.full(P, 9))
cl = centreline(fit, np.sort(rng.uniform(-0.5, 1.5, (P, Kv)), 1))
out = {k: np.ascontiguousarray(v).tobytes().hex() for k, v in
       (("ink", ink), ("pieces", pieces), ("speed", mean_speed(fit)), ("cx", cl[0]),
        ("ctx", cl[2]))}
print(json.dumps(out))
"""


@pytest.mark.slow
def test_kernel_bits_do_not_depend_on_the_thread_count():
    one, two = outputs_per_thread_count(_SCRIPT)
    assert one == two
