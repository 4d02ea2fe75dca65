"""Tests of refnpr.formulas.tamiss (Szécsi, Szirányi, Kacsó, Tonal Art Maps with Image Space Strokes).

Oracles: naive Python loops (regressors, aggregation by a dict of lists, Sum t t^T), numpy.linalg
(solve, pinv, lstsq on the Vandermonde matrix in float64), brute-force sums over evenly spread
points, dense sampling of cubics, a pure-Python-int implementation of the 32-bit hashes and a
naive sequential open-addressing insert.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from refnpr.formulas import tamiss

# ---------------------------------------------------------------------------------------------
# helpers


def cubic(c, s):
    return sum(c[k] * s**k for k in range(4))


def make_stroke(seed: int, span: float, where: float, *, scale=1000.0, offset=(1000.0, 4000.0)):
    """Fragments of a cubic stroke over t in [t0, t0 + span], t0 = where * (1 - span).

    Positions are rounded to pixel centres (as rasterized fragments are) and everything is cast to
    float32, so float32 and float64 fits see identical data.
    """
    rng = np.random.default_rng(seed)
    t0 = where * (1 - span)
    n = int(rng.integers(30, 300))
    t = np.sort(rng.uniform(t0, t0 + span, n))
    c = np.array([rng.uniform(*offset, 2), *rng.uniform(-scale, scale, (3, 2))])
    xy = np.floor(sum(c[k] * t[:, None] ** k for k in range(4))) + 0.5
    return t.astype(np.float32), xy[:, 0].astype(np.float32), xy[:, 1].astype(np.float32)


def lstsq_oracle(t, x, y, tt):
    """float64 least squares on the Vandermonde matrix in the centred parameter."""
    t = np.asarray(t, dtype=np.float64)
    tc, h = (t.min() + t.max()) / 2, (t.max() - t.min()) / 2
    V = np.vander((t - tc) / h, 4, increasing=True)
    cx = np.linalg.lstsq(V, np.asarray(x, np.float64), rcond=None)[0]
    cy = np.linalg.lstsq(V, np.asarray(y, np.float64), rcond=None)[0]
    W = np.vander((np.asarray(tt, np.float64) - tc) / h, 4, increasing=True)
    return W @ cx, W @ cy


def fit_error(fit, t, x, y, n=33):
    tt = np.linspace(float(np.min(t)), float(np.max(t)), n)
    ox, oy = lstsq_oracle(t, x, y, tt)
    ex, ey = fit.evaluate(tt.astype(fit.c_x.dtype))
    return float(np.max(np.hypot(ex - ox, ey - oy)))


# ---------------------------------------------------------------------------------------------
# regressors, normalization, aggregation


def test_fragment_regressors_match_loop():
    rng = np.random.default_rng(0)
    s, x, y = rng.uniform(-1, 1, 7), rng.uniform(0, 2000, 7), rng.uniform(0, 2000, 7)
    R = tamiss.fragment_regressors(s, x, y)
    for i in range(7):
        expect = [s[i] ** k for k in range(7)]
        expect += [s[i] ** k * x[i] for k in range(4)] + [s[i] ** k * y[i] for k in range(4)]
        np.testing.assert_allclose(R[i], expect, rtol=1e-14)
    assert (
        tamiss.fragment_regressors(*(v.astype(np.float32) for v in (s, x, y))).dtype == np.float32
    )
    with pytest.raises(ValueError, match=r"s, x, y: expected equal shapes"):
        tamiss.fragment_regressors(s, x[:3], y)


def test_normalize_t_maps_range_to_unit_interval():
    t = np.array([0.2, 0.25, 0.3])
    np.testing.assert_allclose(tamiss.normalize_t(t, 0.2, 0.3), [-1, 0, 1], atol=1e-15)
    np.testing.assert_array_equal(tamiss.normalize_t(t, 0.5, 0.5), 0.0)
    assert tamiss.normalize_t(t.astype(np.float32), np.float32(0.2), np.float32(0.3)).dtype == (
        np.float32
    )
    with pytest.raises(ValueError, match=r"t_min, t_max: expected t_min <= t_max"):
        tamiss.normalize_t(t, 0.3, 0.2)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_normalize_t_over_a_span_wider_than_the_largest_float_is_finite(dtype):
    # t_max - t_min overflows to inf: (t - c) / h would be inf / inf = NaN
    big = np.finfo(dtype).max
    t = np.array([-big, -big / 2, 0.0, big / 2, big], dtype=dtype)
    got = tamiss.normalize_t(t, dtype(-big), dtype(big))
    assert got.dtype == dtype
    np.testing.assert_array_equal(got, np.array([-1.0, -0.5, 0.0, 0.5, 1.0], dtype=dtype))
    # a span that fits keeps the plain difference: bit for bit the formula (2 t - lo - hi) / (hi - lo)
    lo, hi = dtype(-big / 4), dtype(big / 4)
    got = tamiss.normalize_t(t[1:4], lo, hi)
    np.testing.assert_array_equal(got, np.array([-2.0, 0.0, 2.0], dtype=dtype))


@given(
    ids=hnp.arrays(np.int64, st.integers(1, 60), elements=st.integers(0, 6)),
    seed=st.integers(0, 2**32 - 1),
)
def test_aggregate_matches_dict_of_lists(ids, seed):
    values = np.random.default_rng(seed).normal(0, 100, (ids.size, 3))
    groups = defaultdict(list)
    for i, v in zip(ids.tolist(), values, strict=True):
        groups[i].append(v)
    keys = sorted(groups)
    uid, sums = tamiss.aggregate(ids, values)
    np.testing.assert_array_equal(uid, keys)
    expect = [[math.fsum(v[k] for v in groups[i]) for k in range(3)] for i in keys]
    np.testing.assert_allclose(sums, expect, rtol=1e-12, atol=1e-10)
    _, mins = tamiss.aggregate(ids, values, op="min")
    _, maxs = tamiss.aggregate(ids, values, op="max")
    np.testing.assert_array_equal(mins, [np.min(groups[i], axis=0) for i in keys])
    np.testing.assert_array_equal(maxs, [np.max(groups[i], axis=0) for i in keys])


def test_aggregate_dtype_empty_and_errors():
    ids = np.array([3, 1, 3])
    _, s = tamiss.aggregate(ids, np.ones(3, np.float32))
    assert s.dtype == np.float32 and s.tolist() == [1.0, 2.0]
    uid, s = tamiss.aggregate(np.zeros(0, int), np.zeros((0, 15)))
    assert uid.size == 0 and s.shape == (0, 15)
    with pytest.raises(ValueError, match=r"values: expected 3 rows \(one per fragment\)"):
        tamiss.aggregate(ids, np.ones(4))
    with pytest.raises(ValueError, match=r"op: expected 'sum', 'min' or 'max', got 'mean'"):
        tamiss.aggregate(ids, np.ones(3), op="mean")
    with pytest.raises(TypeError, match=r"ids: expected a 1D integer array"):
        tamiss.aggregate(np.ones(3), np.ones(3))


def test_moment_matrix_is_sum_of_outer_products():
    t = np.random.default_rng(1).uniform(-1, 1, 20)
    P = np.array([np.sum(t**m) for m in range(7)])
    expect = sum(np.outer([1, ti, ti**2, ti**3], [1, ti, ti**2, ti**3]) for ti in t)
    np.testing.assert_allclose(tamiss.moment_matrix(P), expect, rtol=1e-12)
    with pytest.raises(ValueError, match=r"power_sums: expected shape \(\.\.\., 2k - 1\)"):
        tamiss.moment_matrix(np.ones(6))


# ---------------------------------------------------------------------------------------------
# conjugate gradients


def random_spd(rng, k, cond):
    q, _ = np.linalg.qr(rng.normal(size=(k, k)))
    lam = np.geomspace(1.0, cond, k)
    return (q * lam) @ q.T


@given(k=st.integers(1, 6), cond=st.floats(1.0, 1e4), seed=st.integers(0, 2**32 - 1))
def test_cg_solve_exact_after_k_iterations_float64(k, cond, seed):
    rng = np.random.default_rng(seed)
    A = random_spd(rng, k, cond)
    A = (A + A.T) / 2
    b = rng.normal(size=k)
    x = tamiss.cg_solve(A, b, iterations=k)
    ref = np.linalg.solve(A, b)
    assert np.linalg.norm(x - ref) <= 1e-9 * cond * np.linalg.norm(ref)


def test_cg_solve_batched_and_broadcast():
    rng = np.random.default_rng(2)
    A = np.stack([random_spd(rng, 4, 50.0) for _ in range(6)]).reshape(2, 3, 4, 4)
    A = (A + np.swapaxes(A, -1, -2)) / 2
    b = rng.normal(size=(3, 4))  # broadcasts against batch (2, 3)
    x = tamiss.cg_solve(A, b)
    np.testing.assert_allclose(
        x, np.linalg.solve(A, np.broadcast_to(b, (2, 3, 4))[..., None])[..., 0], rtol=1e-8
    )
    np.testing.assert_array_equal(tamiss.cg_solve(A, b, iterations=0), 0.0)
    x32 = tamiss.cg_solve(A.astype(np.float32), b.astype(np.float32))
    assert x32.dtype == np.float32


def test_cg_solve_pseudo_inverse_on_singular_systems():
    # sec. 3.2: "delivers the pseudo-inverse solution even for singular matrices" (b in range(A))
    rng = np.random.default_rng(3)
    for rank in (1, 2, 3):
        V = rng.normal(size=(4, rank))
        A = V @ V.T
        b = A @ rng.normal(size=4)
        x = tamiss.cg_solve(A, b, iterations=4)
        np.testing.assert_allclose(x, np.linalg.pinv(A) @ b, rtol=1e-7, atol=1e-9)
    # two distinct fragment parameters: rank-2 normal matrix of eq. 1
    t = np.array([0.1, 0.1, 0.7, 0.7])
    T = np.vander(t, 4, increasing=True)
    A, b = T.T @ T, T.T @ np.array([5.0, 5.0, 9.0, 9.0])
    np.testing.assert_allclose(tamiss.cg_solve(A, b), np.linalg.pinv(A) @ b, rtol=1e-7)


def test_cg_solve_errors():
    with pytest.raises(ValueError, match=r"A: expected shape \(\.\.\., k, k\)"):
        tamiss.cg_solve(np.ones((3, 4)), np.ones(4))
    with pytest.raises(ValueError, match=r"b: expected shape \(\.\.\., 4\) to match A"):
        tamiss.cg_solve(np.eye(4), np.ones(3))
    with pytest.raises(ValueError, match=r"A: expected symmetric matrices"):
        tamiss.cg_solve(np.triu(np.ones((3, 3))), np.ones(3))
    with pytest.raises(ValueError, match=r"iterations: expected an integer in \[0, inf\], got -1"):
        tamiss.cg_solve(np.eye(2), np.ones(2), iterations=-1)


# ---------------------------------------------------------------------------------------------
# visibility prior


def brute_prior(a, b, n):
    """Sum of t t^T over n evenly spread points (cell midpoints) of [a, b]."""
    pts = a + (np.arange(n) + 0.5) * (b - a) / n
    T = np.vander(pts, 4, increasing=True)
    return T.T @ T


@pytest.mark.parametrize(("a", "b"), [(0.0, 1.0), (0.3, 0.31), (-1.0, 1.0), (0.9, 1.0), (2.0, 5.0)])
def test_visibility_prior_is_the_limit_of_the_brute_force_sum(a, b):
    D = tamiss.visibility_prior(a, b, 1.0)  # per point
    for n in (10, 100, 1000):
        brute = brute_prior(a, b, n) / n
        m = np.add.outer(np.arange(4), np.arange(4))
        # midpoint rule: |error| <= (b - a)^2 / (24 n^2) max |d^2/dt^2 t^m|
        bound = (
            (b - a) ** 2 / (24 * n**2) * m * (m - 1) * max(abs(a), abs(b)) ** np.maximum(m - 2, 0)
        )
        assert np.all(np.abs(brute - D) <= bound + 1e-12 * np.abs(D) + 1e-14)
    np.testing.assert_allclose(
        tamiss.visibility_prior(a, b, 1000), brute_prior(a, b, 1000), rtol=1e-5, atol=1e-9
    )


def test_visibility_prior_paper_formula_omits_the_span():
    # The paper prints D = n * integral(t t^T) dt, d_ij = n (t_max^(i+j-1) - t_min^(i+j-1)) / (i+j-1)
    # (1-based). That is the expected sum times (t_max - t_min): 100x too small on a span of 0.01.
    a, b, n = 0.42, 0.43, 200.0
    i = np.arange(1, 5)
    p = i[:, None] + i[None, :] - 1
    paper = n * (b**p - a**p) / p
    ours = tamiss.visibility_prior(a, b, n)
    np.testing.assert_allclose(paper, ours * (b - a), rtol=1e-9)
    np.testing.assert_allclose(ours, brute_prior(a, b, 200), rtol=1e-4)
    assert paper[0, 0] == pytest.approx(2.0)  # the "200 points" would weigh as 2


def test_visibility_prior_special_cases_and_errors():
    D = tamiss.visibility_prior(-1.0, 1.0, 3.0)
    m = np.add.outer(np.arange(4), np.arange(4))
    np.testing.assert_allclose(D, np.where(m % 2 == 0, 3.0 / (m + 1), 0.0), atol=1e-15)
    pt = tamiss.visibility_prior(0.7, 0.7, 5.0)  # all points at one place
    np.testing.assert_allclose(pt, 5.0 * 0.7**m, rtol=1e-14)
    batch = tamiss.visibility_prior(np.zeros(3, np.float32), np.ones(3, np.float32), 2.0)
    assert batch.shape == (3, 4, 4) and batch.dtype == np.float32
    with pytest.raises(ValueError, match=r"t_min, t_max: expected t_min <= t_max"):
        tamiss.visibility_prior(1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"n: expected a non-negative count"):
        tamiss.visibility_prior(0.0, 1.0, -1.0)


# ---------------------------------------------------------------------------------------------
# stroke fitting


def test_fit_stroke_recovers_a_cubic_float64():
    t = np.linspace(0.3, 0.45, 80)
    cx, cy = [1500.0, 300.0, -200.0, 90.0], [2500.0, -100.0, 40.0, 700.0]
    fit = tamiss.fit_stroke(t, cubic(cx, t), cubic(cy, t))
    tt = np.linspace(0.3, 0.45, 17)
    x, y = fit.evaluate(tt)
    np.testing.assert_allclose(x, cubic(cx, tt), atol=1e-8)
    np.testing.assert_allclose(y, cubic(cy, tt), atol=1e-8)
    dx, dy = fit.derivative(tt)
    np.testing.assert_allclose(dx, cx[1] + 2 * cx[2] * tt + 3 * cx[3] * tt**2, rtol=1e-8)
    np.testing.assert_allclose(dy, cy[1] + 2 * cy[2] * tt + 3 * cy[3] * tt**2, rtol=1e-8)


@pytest.mark.parametrize("basis", ["legendre", "monomial"])
def test_fit_stroke_matches_lstsq_oracle_float64(basis):
    for seed in range(20):
        t, x, y = make_stroke(seed, 10 ** (-2 + 2 * seed / 19), (seed * 0.37) % 1)
        fit = tamiss.fit_stroke(t.astype(float), x.astype(float), y.astype(float), basis=basis)
        assert fit_error(fit, t, x, y) < 1e-6


@given(
    span=st.floats(0.01, 1.0),
    where=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_fit_stroke_float32_under_005_px(span, where, seed):
    t, x, y = make_stroke(seed, span, where)
    fit = tamiss.fit_stroke(t, x, y)
    assert fit.c_x.dtype == np.float32
    assert fit_error(fit, t, x, y) < 0.05


def test_paper_raw_monomials_fail_in_float32_on_the_same_data():
    errs = {"legendre": [], "monomial": [], "raw": [], "raw64": []}
    for seed in range(40):
        t, x, y = make_stroke(seed, 10 ** (-2 + 2 * (seed % 10) / 9), (seed * 0.61) % 1)
        errs["legendre"].append(fit_error(tamiss.fit_stroke(t, x, y), t, x, y))
        # DESIGN's fix alone (centred monomials, no shift of x, y) and the paper verbatim
        mono = tamiss.fit_stroke(t, x, y, basis="monomial", centre_xy=False)
        errs["monomial"].append(fit_error(mono, t, x, y))
        errs["raw"].append(
            fit_error(tamiss.fit_stroke(t, x, y, basis="raw", centre_xy=False), t, x, y)
        )
        raw64 = tamiss.fit_stroke(t.astype(float), x.astype(float), y.astype(float), basis="raw")
        errs["raw64"].append(fit_error(raw64, t, x, y))
    assert max(errs["legendre"]) < 0.005
    assert max(errs["monomial"]) > 0.05  # centring t alone is not enough in 4 float32 steps
    assert min(errs["raw"]) > 0.05 and max(errs["raw"]) > 1.0  # off by pixels
    assert max(errs["raw64"]) > 0.05  # raw t needs more than 4 steps even in float64


def test_fit_fragments_matches_per_stroke_loop():
    rng = np.random.default_rng(4)
    ids, ts, xs, ys, per = [], [], [], [], {}
    for sid in rng.choice(10**6, 6, replace=False):
        t, x, y = make_stroke(int(sid), rng.uniform(0.02, 0.5), rng.uniform(), scale=300.0)
        per[int(sid)] = (t, x, y)
        ids += [sid] * t.size
        ts.append(t), xs.append(x), ys.append(y)
    order = rng.permutation(len(ids))  # fragments arrive in any order
    ids = np.array(ids)[order]
    t, x, y = (np.concatenate(v)[order] for v in (ts, xs, ys))
    uid, fit = tamiss.fit_fragments(ids, t.astype(float), x.astype(float), y.astype(float))
    np.testing.assert_array_equal(uid, sorted(per))
    for k, sid in enumerate(uid):
        single = tamiss.fit_stroke(*(v.astype(float) for v in per[int(sid)]))
        for name in ("c_x", "c_y", "c_v"):
            np.testing.assert_allclose(
                getattr(fit, name)[k], getattr(single, name), rtol=1e-9, atol=1e-6
            )
        assert fit.t_min[k] == single.t_min and fit.t_max[k] == single.t_max
    xb, yb = fit.evaluate(np.linspace(0, 1, 5))
    assert xb.shape == (6, 5)
    xs_, _ = fit.evaluate(fit.t_min[:, None])
    assert xs_.shape == (6, 1)


def test_fit_single_point_and_errors():
    fit = tamiss.fit_stroke(np.full(5, 0.4), np.full(5, 1234.5), np.full(5, 99.5))
    x, y = fit.evaluate(np.array([0.4, 0.9]))
    np.testing.assert_allclose(x, 1234.5) and np.testing.assert_allclose(y, 99.5)
    assert np.all(np.isfinite(fit.c_v))
    with pytest.raises(ValueError, match=r"x: expected shape \(3,\) \(one value per fragment id\)"):
        tamiss.fit_stroke(np.ones(3), np.ones(4), np.ones(3))
    with pytest.raises(
        ValueError, match=r"basis: expected one of \('legendre', 'monomial', 'raw'\)"
    ):
        tamiss.fit_stroke(np.ones(3), np.ones(3), np.ones(3), basis="chebyshev")
    with pytest.raises(ValueError, match=r"t: expected shape \(n,\) with n >= 1"):
        tamiss.fit_stroke(np.ones(0), np.ones(0), np.ones(0))
    with pytest.raises(ValueError, match=r"moments: expected shape \(\.\.\., 15\)"):
        tamiss.fit_strokes(np.ones(14), 0.0, 1.0)


# ---------------------------------------------------------------------------------------------
# visibility and visible segments


def test_visibility_without_prior_is_constant_one():
    t = np.random.default_rng(5).uniform(0.1, 0.9, 50)
    fit = tamiss.fit_stroke(t, t, t, prior_weight=0.0)
    np.testing.assert_allclose(fit.visibility(np.linspace(0.1, 0.9, 9)), 1.0, atol=1e-9)


def test_fully_visible_stroke_is_one_segment():
    t = np.linspace(0.2, 0.7, 300)
    fit = tamiss.fit_stroke(t, 100 * t, 50 * t)
    np.testing.assert_allclose(fit.visibility(t), 0.5, atol=0.01)  # n = N points: v ~ 1/2
    seg, count = fit.visible_segments()
    assert count == 1
    np.testing.assert_allclose(seg[0], [0.2, 0.7], atol=1e-12)
    assert np.all(np.isnan(seg[1]))


def test_wide_hidden_gap_splits_into_two_segments():
    t = np.linspace(0.0, 1.0, 2001)
    vis = (t <= 0.25) | (t >= 0.75)
    fit = tamiss.fit_stroke(t[vis], 300 * t[vis], 20 * t[vis])
    seg, count = fit.visible_segments()
    assert count == 2
    np.testing.assert_allclose(seg[:, 0], [0.0, 0.75], atol=0.1)
    np.testing.assert_allclose(seg[:, 1], [0.25, 1.0], atol=0.1)
    # a stronger prior with its matching threshold resolves a 30 % gap off centre
    vis = (t <= 0.5) | (t >= 0.8)
    fit = tamiss.fit_stroke(t[vis], t[vis], t[vis], prior_weight=2.0)
    seg, count = fit.visible_segments()
    assert count == 2 and seg[0, 1] < 0.6 and seg[1, 0] > 0.7


def test_narrow_gap_is_not_resolved_by_a_cubic():
    # The paper's cubic visibility smooths away gaps narrower than about a third of the range.
    t = np.linspace(0.0, 1.0, 2001)
    vis = (t <= 0.45) | (t >= 0.55)
    _, count = tamiss.fit_stroke(t[vis], t[vis], t[vis]).visible_segments()
    assert count == 1


coef = st.floats(-3, 3, allow_nan=False)


@given(c=st.lists(coef, min_size=4, max_size=4), thr=st.floats(-2, 2))
def test_visible_segments_against_dense_sampling(c, thr):
    seg, count = tamiss.visible_segments(np.array(c), threshold=thr)
    assert 0 <= count <= 2
    s = np.linspace(-1, 1, 4001)
    f = cubic(c, s) - thr
    inside = np.zeros(s.shape, bool)
    for j in range(int(count)):
        a, b = seg[j]
        assert -1 <= a < b <= 1
        inside |= (s >= a) & (s <= b)
    assert np.all(inside[f > 1e-9])
    assert not np.any(inside[f < -1e-9])
    assert np.all(np.isnan(seg[int(count) :]))


def test_visible_segments_degenerate_cubics():
    seg, count = tamiss.visible_segments(
        np.array([[0, 0, 0, 0.0], [1, 0, 0, 0], [0, 1, 0, 0]]), threshold=0.5
    )
    np.testing.assert_array_equal(count, [0, 1, 1])
    np.testing.assert_allclose(seg[1, 0], [-1, 1])
    np.testing.assert_allclose(seg[2, 0], [0.5, 1], atol=1e-15)
    with pytest.raises(ValueError, match=r"c_v: expected shape \(\.\.\., 4\)"):
        tamiss.visible_segments(np.ones(3))


# ---------------------------------------------------------------------------------------------
# extrusion


def test_extrude_straight_stroke_exact_with_taper():
    t = np.linspace(0.0, 1.0, 50)
    fit = tamiss.fit_stroke(t, 100 + 40 * t, 200 + 30 * t)
    strip = tamiss.extrude_stroke(fit, 0.0, 1.0, width=6.0, samples=5, taper=0.25)
    u = np.linspace(0, 1, 5)
    prof = np.minimum(1, np.minimum(u, 1 - u) / 0.25)
    centre = np.stack([100 + 40 * u, 200 + 30 * u], -1)
    normal = np.array([-30.0, 40.0]) / 50.0
    np.testing.assert_allclose(strip.left, centre + 3.0 * prof[:, None] * normal, atol=1e-9)
    np.testing.assert_allclose(strip.right, centre - 3.0 * prof[:, None] * normal, atol=1e-9)
    np.testing.assert_allclose(strip.t, u, atol=1e-15)
    verts, coords = strip.triangle_strip()
    np.testing.assert_array_equal(verts[0::2], strip.left)
    np.testing.assert_array_equal(verts[1::2], strip.right)
    np.testing.assert_array_equal(coords[:, 1], [0, 1] * 5)
    np.testing.assert_array_equal(coords[0::2, 0], strip.t)


def test_extrude_curved_batch_is_perpendicular_and_matches_loop():
    ids = np.repeat([7, 11, 19], 80)
    t = np.tile(np.linspace(0.1, 0.6, 80), 3)
    x = 500 + 300 * t**2 + ids
    y = 800 - 200 * t**3 + 40 * t
    uid, fit = tamiss.fit_fragments(ids, t, x, y)
    width = np.array([2.0, 3.0, 4.0])
    strip = tamiss.extrude_stroke(fit, 0.1, 0.6, width=width, samples=9)
    assert strip.left.shape == (3, 9, 2)
    for k in range(3):
        sel = ids == uid[k]
        single = tamiss.fit_stroke(t[sel], x[sel], y[sel])
        one = tamiss.extrude_stroke(single, 0.1, 0.6, width=width[k], samples=9)
        np.testing.assert_allclose(strip.left[k], one.left, atol=1e-9)
        dx, dy = single.derivative(one.t)
        across = one.left - one.right
        np.testing.assert_allclose(across[:, 0] * dx + across[:, 1] * dy, 0.0, atol=1e-9)
        np.testing.assert_allclose(np.hypot(*across.T), width[k], rtol=1e-12)


def test_extrude_degenerate_tangent_and_errors():
    fit = tamiss.fit_stroke(np.full(4, 0.5), np.full(4, 10.0), np.full(4, 20.0))
    strip = tamiss.extrude_stroke(fit, 0.5, 0.5, width=2.0, samples=3)
    np.testing.assert_allclose(strip.left, [[10.0, 21.0]] * 3)  # fallback direction (1, 0)
    with pytest.raises(ValueError, match=r"width: expected a non-negative width"):
        tamiss.extrude_stroke(fit, 0.5, 0.5, width=-1.0)
    with pytest.raises(ValueError, match=r"taper: expected a value in \[0\.0, 0\.5\], got 0\.7"):
        tamiss.extrude_stroke(fit, 0.5, 0.5, width=1.0, taper=0.7)


# ---------------------------------------------------------------------------------------------
# double hashing and the read-only / write-only table pair

M32 = 0xFFFFFFFF


def py_lowbias32(x: int) -> int:
    x ^= x >> 16
    x = (x * 0x7FEB352D) & M32
    x ^= x >> 15
    x = (x * 0x846CA68B) & M32
    return x ^ (x >> 16)


def py_slot(i: int, k: int, size: int) -> int:
    h1 = py_lowbias32(i)
    h2 = py_lowbias32(i ^ 0x9E3779B9) | 1
    return ((h1 + k * h2) & M32) % size


def test_hash_slot_matches_python_reference():
    rng = np.random.default_rng(7)
    ids = rng.integers(0, 2**32 - 1, 50)
    probes = rng.integers(0, 1000, 50)
    got = tamiss.hash_slot(ids, probes, 4096)
    expect = [py_slot(int(i), int(k), 4096) for i, k in zip(ids, probes, strict=True)]
    np.testing.assert_array_equal(got, expect)
    assert py_lowbias32(0) == 0 and tamiss.hash_slot(np.array([0]), 0, 8)[0] == 0


def test_probe_sequence_visits_every_slot():
    for i in range(20):
        slots = tamiss.hash_slot(np.full(64, i * 7919), np.arange(64), 64)
        assert sorted(slots.tolist()) == list(range(64))


def test_double_hashing_finds_every_id_while_under_half_full():
    size = 1024
    ids = np.random.default_rng(8).choice(2**31, size // 2 - 1, replace=False)
    table = np.full(size, tamiss.EMPTY, dtype=np.uint32)
    where = {}
    for i in ids.tolist():  # naive sequential open-addressing insert
        k = 0
        while table[py_slot(i, k, size)] != tamiss.EMPTY:
            k += 1
        table[py_slot(i, k, size)] = i
        where[i] = py_slot(i, k, size)
    slot, status = tamiss.probe_table(table, ids, max_probes=32)
    assert np.all(status == tamiss.FOUND)
    np.testing.assert_array_equal(slot, [where[i] for i in ids.tolist()])
    absent = np.arange(2**31, 2**31 + 100)
    _, st_absent = tamiss.probe_table(table, absent, max_probes=32)
    assert np.all(st_absent == tamiss.CLAIM)


def test_frame_model_delays_colliding_new_strokes_then_settles():
    size = 256
    ids = np.random.default_rng(9).choice(10**6, 100, replace=False)
    table = tamiss.StrokeHashTable(size)
    frags = np.repeat(ids, 4)
    first = table.route_frame(frags)
    h1 = [py_slot(int(i), 0, size) for i in ids]
    assert first.n_delayed == len(ids) - len(set(h1))  # all claim their first probe
    assert first.n_lost == 0 and not first.found.any()
    assert first.n_contested_slots == sum(1 for s in set(h1) if h1.count(s) > 1)
    np.testing.assert_array_equal(
        first.fragment_slot,
        np.repeat(first.slot, 4)[np.argsort(np.argsort(frags, kind="stable"), kind="stable")],
    )
    for _ in range(10):
        result = table.route_frame(frags)
        if result.found.all():
            break
    assert result.found.all() and result.n_delayed == 0 and result.n_lost == 0
    assert len(set(result.slot.tolist())) == len(ids)  # one slot per stroke
    np.testing.assert_array_equal(
        np.sort(table.read_table[table.read_table != tamiss.EMPTY]), np.sort(ids)
    )
    # strokes that vanish free their slots in the next frame's table
    table.route_frame(ids[:50])
    assert table.occupancy == pytest.approx(50 / size)


def test_frame_model_loses_strokes_when_the_table_is_full():
    table = tamiss.StrokeHashTable(8, max_probes=8)
    ids = np.arange(12)
    for _ in range(12):
        result = table.route_frame(ids)
    assert result.found.sum() == 8 and result.n_lost == 4 and result.n_delayed == 0
    assert np.all(result.slot[result.lost] == -1)


def test_hash_errors():
    with pytest.raises(ValueError, match=r"size: expected a power of two .* got 100; use 128"):
        tamiss.StrokeHashTable(100)
    with pytest.raises(ValueError, match=r"ids: expected ids in \[0, 4294967294\]"):
        tamiss.hash_slot(np.array([-1]), 0, 8)
    with pytest.raises(TypeError, match=r"ids: expected integer stroke ids"):
        tamiss.hash_slot(np.array([1.5]), 0, 8)


# ---------------------------------------------------------------------------------------------
# numerical stress

#: Documented bound: float32 fits stay within 0.01 px of the float64 least-squares solution for
#: t spans down to 1e-4 and pixel coordinates up to 1e4 (measured worst case about 0.002 px).
F32_BOUND_PX = 0.01


@pytest.mark.stress
@given(
    log_span=st.floats(-4.0, 0.0),
    where=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_stress_float32_fit_tiny_spans_large_coordinates(log_span, where, seed):
    t, x, y = make_stroke(seed, 10**log_span, where, scale=5000.0, offset=(0.0, 1e4))
    fit = tamiss.fit_stroke(t, x, y)
    for name in ("c_x", "c_y", "c_v"):
        assert np.all(np.isfinite(getattr(fit, name)))
    tt = np.linspace(float(t.min()), float(t.max()), 33, dtype=np.float32)
    xs, ys = fit.evaluate(tt)
    assert np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))
    assert fit_error(fit, t, x, y) < F32_BOUND_PX
    seg, count = fit.visible_segments()
    assert count >= 1 and np.all(np.isfinite(seg[:count]))
    strip = tamiss.extrude_stroke(fit, fit.t_min, fit.t_max, width=3.0, taper=0.2)
    assert np.all(np.isfinite(strip.left)) and np.all(np.isfinite(strip.right))


@pytest.mark.stress
@given(
    scale=st.floats(-30.0, 30.0),
    k=st.integers(1, 5),
    seed=st.integers(0, 2**32 - 1),
)
def test_stress_cg_float32_no_nan_at_extreme_scales(scale, k, seed):
    rng = np.random.default_rng(seed)
    A = random_spd(rng, k, 100.0) * np.float64(2.0) ** scale
    A = ((A + A.T) / 2).astype(np.float32)
    b = rng.normal(size=k).astype(np.float32) * np.float32(2.0) ** (scale / 2)
    x = tamiss.cg_solve(A, b, iterations=8)
    assert x.dtype == np.float32 and np.all(np.isfinite(x))
    ref = np.linalg.solve(A.astype(np.float64), b.astype(np.float64))
    assert np.linalg.norm(x - ref) <= 1e-3 * np.linalg.norm(ref)


@pytest.mark.stress
@given(c=st.lists(st.floats(-1e300, 1e300), min_size=4, max_size=4))
def test_stress_visible_segments_extreme_coefficients(c):
    c = np.array(c)
    seg, count = tamiss.visible_segments(c, threshold=0.0)
    assert 0 <= count <= 2 and np.all(np.isfinite(seg[: int(count)]))
    scale = np.max(np.abs(c)) or 1.0
    s = np.linspace(-1, 1, 2001)
    f = cubic(c / scale, s)
    inside = np.zeros(s.shape, bool)
    for j in range(int(count)):
        inside |= (s >= seg[j, 0]) & (s <= seg[j, 1])
    assert np.all(inside[f > 1e-9]) and not np.any(inside[f < -1e-9])


# ---------------------------------------------------------------------------------------------
# the RPTAM stroke field (formulas.tamiss.field): each face against a plain Python loop


def _level_rule_by_the_book(v: float, max_level: int) -> tuple[int, float, float]:
    """(L, f, thin) of the docstring's rule, on Python's exact integer floor."""
    big_l, f, thin = math.floor(v), v - math.floor(v), 1.0
    if big_l < 0:
        big_l, f, thin = 0, 0.0, 2.0**v
    if big_l >= max_level:
        big_l, f = max_level, 0.0
    return big_l, f, thin


def test_level_rule_and_fade_in_match_the_definition():
    s = np.array([-2.5, -0.25, 0.0, 0.5, 1.0, 3.75, 9.99, 10.0, 12.5])
    got = tamiss.level_rule(s, 10)
    for (big_l, f, thin), v in zip(got, s, strict=True):
        want_l, want_f, want_thin = _level_rule_by_the_book(v, 10)
        assert (big_l, f) == (want_l, want_f) and thin == pytest.approx(want_thin, rel=1e-15)
    np.testing.assert_allclose(tamiss.fade_in([0.0, 0.5, 1.0]), [0.0, 2**0.5 - 1, 1.0])
    with pytest.raises(ValueError, match="s"):
        tamiss.level_rule(np.array([np.nan]), 10)


def test_layer_frame_and_dyadic_scale_match_python():
    rng = np.random.default_rng(4)
    uv, dx, dy = rng.normal(size=(3, 50, 2))
    dx, dy = dx * 1e-3, dy * 1e-3
    scale = np.tile([2.0, 3.0], (50, 1))
    dx[0] = dy[0] = 0.0  # no gradient: no strokes
    got = tamiss.layer_frame(uv, dx, dy, scale, 30.0)
    ca, sa = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    for i in range(50):
        u, v = uv[i] * scale[i]
        (ux, vx), (uy, vy) = dx[i] * scale[i], dy[i] * scale[i]
        gp = math.hypot(ca * ux + sa * vx, ca * uy + sa * vy)
        gq = math.hypot(-sa * ux + ca * vx, -sa * uy + ca * vy)
        assert got[i, 0] == ca * u + sa * v and got[i, 1] == -sa * u + ca * v
        if i == 0:
            assert np.isnan(got[i, 2:]).all()
        else:
            # Python's hypot is correctly rounded, the C library's within an ulp
            assert (got[i, 2], got[i, 3]) == (
                pytest.approx(1 / gp, rel=1e-15),
                pytest.approx(1 / gq, rel=1e-15),
            )
    s = tamiss.dyadic_scale(got[1:, 3], 4.0)
    np.testing.assert_array_equal(s, [math.log2(d / 28.0) for d in got[1:, 3]])


def test_density_stroke_and_coverage_match_python():
    d = np.linspace(-0.2, 1.2, 15)
    want = [min(max((x - 0.3) / 0.7 * 2.0, 0.0), 1.0) for x in d]
    np.testing.assert_array_equal(tamiss.layer_density(d, 0.3, 2.0), want)
    length = tamiss.stroke_length(np.array([0.0, 0.5, 0.99]), 1.5, 0.3, np.array([0, 1, 3]))
    np.testing.assert_array_equal(length, [1.5 * 0.7, 1.5 * 1.0 / 2, 1.5 * (1 + 0.3 * 0.98) / 8])
    p_start = tamiss.stroke_start(np.array([3, -2]), np.array([1, 4]), np.array([0, 2]), 0.5)
    np.testing.assert_array_equal(p_start, [(3 + 6 / 7) - 0.25, (-2 + 3 / 7) / 4 - 0.25])
    for p in (-1.0, 0.2, 0.5, 0.9, 1.3):
        t, beyond = tamiss.stroke_param(p, 0.25, 0.5, 8.0)
        assert t == (p - 0.25) / 0.5 and beyond == max(-t, t - 1) * 0.5 * 8.0
    assert tamiss.row_distance(0.3, 5, 14.0, 20.0) == abs(0.3 - 5 / 14) * 20.0
    np.testing.assert_array_equal(tamiss.width_factor(np.array([0.0, 1.0]), 0.2), [0.8, 1.2])
    for limit, tau in ((0.5, 0.2), (0.5, 0.6), (0.3, 0.25)):
        assert tamiss.tam_opacity(limit, tau, 0.15, True) == (1.0 if tau < limit else 0.0)
        assert tamiss.tam_opacity(limit, tau, 0.15, False) == min(max((limit - tau) / 0.15, 0), 1)
    for dist, beyond in ((0.0, -3.0), (1.2, 0.1), (2.0, 0.7), (0.4, -0.2)):
        cov = min(max(1.5 * 1.1 / 2 - dist + 0.5, 0), 1) * min(max(0.5 - beyond, 0), 1)
        assert tamiss.tam_coverage(1.5, 1.1, dist, beyond) == cov
    assert tamiss.ink_over(0.25, 0.5) == 0.25 + 0.5 * 0.75


def test_darkness_is_one_minus_the_clipped_luminance():
    rgb = np.array([[0.2, 0.5, 0.9], [2.0, 2.0, 2.0], [-1.0, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    y = (rgb[:, 0] * 0.2126 + rgb[:, 1] * 0.7152) + rgb[:, 2] * 0.0722
    got = tamiss.darkness(rgb)
    np.testing.assert_array_equal(got[:3], 1.0 - np.clip(y[:3], 0.0, 1.0))
    assert np.isnan(got[3])


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_cubic_and_slope_are_horner_in_the_coefficients_type(dtype):
    rng = np.random.default_rng(9)
    c = rng.normal(size=(40, 4)).astype(dtype)
    s = rng.uniform(-1, 1, 40).astype(dtype)
    got, slope = tamiss.cubic(c, s), tamiss.cubic_slope(c, s)
    assert got.dtype == slope.dtype == dtype
    for i in range(40):
        c0, c1, c2, c3 = c[i]
        assert got[i] == ((c3 * s[i] + c2) * s[i] + c1) * s[i] + c0
        k2, k3 = dtype(2), dtype(3)
        assert slope[i] == ((dtype(0) * s[i] + k3 * c3) * s[i] + k2 * c2) * s[i] + c1


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: tamiss.layer_density(0.5, 0.2, "x"), "density"),
        (lambda: tamiss.layer_density(0.5, 1.0, 1.0), "tone_lo"),
        (lambda: tamiss.row_distance(0.5, 1, "x", 1.0), "rows"),
        (lambda: tamiss.stroke_length(0.5, "x", 0.1, 1), "length"),
        (lambda: tamiss.stroke_length(0.5, 1.0, None, 1), "jitter"),
        (lambda: tamiss.dyadic_scale(1.0, None), "period"),
        (lambda: tamiss.dyadic_scale(1.0, 0.0), "period"),
        (lambda: tamiss.level_rule(1.0, "3"), "max_level"),
        (lambda: tamiss.width_factor(0.5, "x"), "jitter"),
        (lambda: tamiss.tam_opacity(0.5, 0.2, "x", False), "fade"),
    ],
)
def test_field_faces_name_a_bad_argument(call, name):
    with pytest.raises((ValueError, TypeError), match=f"^{name}: "):
        call()


def test_level_rule_saturates_for_any_finite_scale():
    """Oracle: the docstring's rule on Python's exact integer floor (no int64 to overflow)."""
    s = np.array(
        [1e19, 1e300, 20.0, 12.0, 11.5, -3.5, -1074.0, -1e19, -1e300, -np.finfo(float).max]
    )
    got = tamiss.level_rule(s, 12)
    for (big_l, f, thin), v in zip(got, s, strict=True):
        assert (big_l, f, thin) == _level_rule_by_the_book(v, 12)


@pytest.mark.parametrize("max_level", [-1, 13, 2**64])
def test_level_rule_refuses_a_max_level_past_the_field(max_level):
    with pytest.raises(ValueError, match=r"^max_level: expected an integer in \[0, 12\]"):
        tamiss.level_rule(1.0, max_level)


_ID_BOUNDS = {
    "chart": (0, 1023),
    "layer": (0, 3),
    "level": (0, 15),
    "gx": (-(2**21), 2**21 - 1),
    "gy": (-(2**21), 2**21 - 1),
    "r": (0, 7),
}


@pytest.mark.parametrize("field", list(_ID_BOUNDS))
def test_pack_id_takes_every_field_to_its_bit_limits_and_no_further(field):
    lo, hi = _ID_BOUNDS[field]
    base = {"chart": 5, "layer": 2, "level": 3, "gx": -7, "gy": 9, "r": 4}
    for v in (lo, hi):  # the limits round-trip (the oracle: unpack_id's shifts and masks)
        sid = tamiss.pack_id(**{**base, field: v})
        got = tamiss.unpack_id(sid)
        assert sid >= 0 and got["row" if field == "r" else field] == v
    for v in (lo - 1, hi + 1):
        match = rf"^{field}: expected integers in \[{lo}, {hi}\], got {v} at flat index 1"
        with pytest.raises(ValueError, match=match):
            tamiss.pack_id(**{**base, field: np.array([lo, v])})


def test_pack_id_fields_no_longer_alias():
    with pytest.raises(ValueError, match="^gx: "):  # would equal pack_id(0, 0, 1, -2**21, 0, 0)
        tamiss.pack_id(0, 0, 0, 2**21, 0, 0)
    with pytest.raises(ValueError, match="^r: "):  # would equal pack_id(0, 0, 0, 0, 1, 0)
        tamiss.pack_id(0, 0, 0, 0, 0, 8)
    with pytest.raises(ValueError, match="^chart: "):  # would be a negative id
        tamiss.pack_id(2000, 0, 0, 0, 0, 0)
    with pytest.raises(TypeError, match="^level: expected integers"):
        tamiss.pack_id(0, 0, 1.0, 0, 0, 0)
    with pytest.raises(ValueError, match="^gy: "):  # an unsigned value past int64
        tamiss.pack_id(0, 0, 0, 0, np.uint64(2**63), 0)


@pytest.mark.parametrize("r", [-1, 7, 9])
def test_born_at_and_stroke_start_refuse_a_row_outside_the_cell(r):
    with pytest.raises(ValueError, match=r"^r: expected integers in \[0, 6\], got -?\d+ at flat"):
        tamiss.born_at(1, 0, 0, r)
    with pytest.raises(ValueError, match=r"^r: expected integers in \[0, 6\]"):
        tamiss.stroke_start(0, np.array([0, r]), 0, 1.0)


def test_hash_faces_name_a_bad_salt_or_input():
    ids = np.arange(3)
    with pytest.raises(TypeError, match="^salt: expected an integer, got None"):
        tamiss.hash01(ids, None)
    with pytest.raises(TypeError, match="^salt: expected an integer, got 5.7"):
        tamiss.hash01(ids, 5.7)
    with pytest.raises(TypeError, match="^salt: expected an integer, got True"):
        tamiss.salt_offset(True)
    with pytest.raises(ValueError, match="^salt: expected an integer in"):
        tamiss.salt_offset(2**64)
    with pytest.raises(TypeError, match="^x: expected integers, got 'abc'"):
        tamiss.splitmix64("abc")
    with pytest.raises(TypeError, match="^x: expected integers"):
        tamiss.splitmix64(np.array([1.5]))
    with pytest.raises(TypeError, match="^ids: expected integers"):
        tamiss.hash01(np.array([1.0]), 1)
    # salts modulo 2^64 (oracle: Python integers), numpy integer salts as Python ones
    assert int(tamiss.salt_offset(2**64 - 1)) == (-0x9E3779B97F4A7C15) % 2**64
    assert int(tamiss.salt_offset(-1)) == int(tamiss.salt_offset(2**64 - 1))
    np.testing.assert_array_equal(tamiss.hash01(ids, np.int64(5)), tamiss.hash01(ids, 5))
    # uint64 inputs are bit patterns: the same hash as the int64 of the same bits
    big = np.array([2**63 + 5, 2**64 - 1], dtype=np.uint64)
    np.testing.assert_array_equal(tamiss.splitmix64(big), tamiss.splitmix64(big.view(np.int64)))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_cg_solve_of_empty_systems_is_the_empty_solution(dtype):
    x = tamiss.cg_solve(np.zeros((0, 0), dtype), np.zeros(0, dtype))
    assert x.shape == (0,) and x.dtype == dtype
    assert tamiss.cg_solve(np.zeros((5, 0, 0), dtype), np.zeros(0, dtype)).shape == (5, 0)
    assert tamiss.cg_solve(np.zeros((0, 4, 4), dtype), np.zeros(4, dtype)).shape == (0, 4)
    with pytest.raises(ValueError, match=r"^b: expected shape \(\.\.\., 0\)"):
        tamiss.cg_solve(np.zeros((0, 0)), np.zeros(1))
