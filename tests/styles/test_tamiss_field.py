"""The RPTAM stroke field of the tam/tamiss styles: nesting, ids, hashes, level fade-in.

Oracles are brute force on exact integers: a seed of level l is the lattice point
(7 gx + KX[r], 7 gy + r) in units of 1 / (7 2^l); its presence at level l - 1 is decided by
halving the integers and looking the point up in the base set, independently of the parity rule
the code uses.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.formulas.tamiss.field import (
    KX,
    MAX_LEVEL,
    born_at,
    fade_in,
    hash01,
    key32,
    pack_id,
    salt_offset,
    seed_set,
    splitmix64,
    unpack_id,
)
from refnpr.styles.tamiss.field import SALT_TONE, StrokeField, stroke_geometry

BASE = {(int(KX[r]), r) for r in range(7)}  # S_0 in sevenths


def lattice(level: int) -> set[tuple[int, int]]:
    """S_level of one tile as integer points in units of 1 / (7 * 2^level)."""
    n = 1 << level
    return {(7 * gx + kx, 7 * gy + ky) for gx in range(n) for gy in range(n) for kx, ky in BASE}


def in_coarser(X: int, Y: int) -> bool:
    """Whether the level-l lattice point (X, Y) is a seed of level l - 1 (any cell)."""
    if X % 2 or Y % 2:
        return False
    return ((X // 2) % 7, (Y // 2) % 7) in BASE


@pytest.mark.parametrize("level", [0, 1, 2, 3, 4])
def test_seed_sets_are_nested_and_self_similar(level):
    fine = lattice(level + 1)
    coarse = lattice(level)
    assert len(coarse) == 7 * 4**level and len(fine) == 4 * len(coarse)
    assert {(2 * X, 2 * Y) for X, Y in coarse} <= fine  # every coarse seed persists
    # the same seed set at half scale on a 2 x 2 grid
    n = 7 * (1 << level)
    half = {(X + ox * n, Y + oy * n) for X, Y in coarse for ox in (0, 1) for oy in (0, 1)}
    assert half == fine
    # new rows appear between old ones: rows are evenly spaced at every level
    assert sorted({Y for _, Y in fine}) == list(range(2 * n))
    # seed_set() agrees with the lattice
    pts = seed_set(level + 1) * (2 * n)
    assert {(round(x), round(y)) for x, y in pts} == fine
    np.testing.assert_allclose(pts, np.round(pts), atol=1e-9)


@pytest.mark.parametrize("level", [1, 2, 3])
def test_born_at_matches_brute_force(level):
    n = 1 << level
    gx, gy, r = np.meshgrid(np.arange(-n, 2 * n), np.arange(-n, 2 * n), np.arange(7), indexing="ij")
    gx, gy, r = gx.ravel(), gy.ravel(), r.ravel()
    X, Y = 7 * gx + KX[r], 7 * gy + r
    expected = np.array([not in_coarser(int(a), int(b)) for a, b in zip(X, Y, strict=True)])
    np.testing.assert_array_equal(born_at(level, gx, gy, r), expected)
    assert expected.mean() == pytest.approx(0.75)  # three new seeds for every old one
    assert np.all(born_at(0, gx, gy, r))


@given(
    chart=st.integers(0, 1023),
    layer=st.integers(0, 3),
    level=st.integers(0, MAX_LEVEL),
    gx=st.integers(-(1 << 21), (1 << 21) - 1),
    gy=st.integers(-(1 << 21), (1 << 21) - 1),
    row=st.integers(0, 6),
)
def test_pack_unpack_round_trip(chart, layer, level, gx, gy, row):
    sid = pack_id(chart, layer, level, gx, gy, row)
    assert sid >= 0
    d = unpack_id(sid)
    assert (d["chart"], d["layer"], d["level"], d["gx"], d["gy"], d["row"]) == (
        chart,
        layer,
        level,
        gx,
        gy,
        row,
    )


def test_ids_are_unique_over_a_block():
    rng = np.random.default_rng(3)
    t = [rng.integers(lo, hi, 4000) for lo, hi in ((0, 5), (0, 4), (0, 13), (-50, 50), (-50, 50))]
    t.append(rng.integers(0, 7, 4000))
    tuples = np.stack(t, axis=1)
    ids = pack_id(*tuples.T)
    assert np.unique(tuples, axis=0).shape[0] == np.unique(ids).shape[0]


def test_hash_matches_reference_and_device_function():
    def ref(x: int) -> int:  # SplitMix64 finalizer, Python integers
        m = (1 << 64) - 1
        z = (x + 0x9E3779B97F4A7C15) & m
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & m
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & m
        return z ^ (z >> 31)

    ids = np.array([0, 1, 12345678901, (1 << 62) + 7], dtype=np.int64)
    assert [int(v) for v in splitmix64(ids)] == [ref(int(i)) for i in ids]
    for i in ids:
        salted = (int(i) + SALT_TONE * 0x9E3779B97F4A7C15) & ((1 << 64) - 1)
        expected = (ref(salted) >> 11) / 2.0**53
        assert hash01(i, SALT_TONE)[0] == expected
        assert hash01.scalar(int(i), salt_offset(SALT_TONE)) == expected  # the kernels' function
    assert pack_id.scalar(3, 1, 5, -7, 9, 4) == pack_id(3, 1, 5, -7, 9, 4)


def test_tone_thresholds_are_uniform():
    ids = pack_id(0, 0, 3, np.arange(20000) % 200 - 100, np.arange(20000) // 200, 2)
    tau = hash01(ids, SALT_TONE)
    hist = np.histogram(tau, bins=10, range=(0, 1))[0]
    assert np.all(np.abs(hist - 2000) < 5 * np.sqrt(2000))
    assert np.all((tau >= 0) & (tau < 1))


def test_key32_never_marks_empty():
    k = key32(np.arange(100000, dtype=np.int64))
    assert k.dtype == np.uint32 and np.all(k != np.uint32(0xFFFFFFFF))


def test_stroke_geometry_from_id():
    field = StrokeField.from_params(length=1.5, length_jitter=0.3)
    ids = pack_id(2, 1, 3, np.arange(-20, 20), 5, 6)
    g = stroke_geometry(ids, field)
    p_seed = (np.arange(-20, 20) + KX[6] / 7) / 8
    np.testing.assert_allclose(0.5 * (g.p_start + g.p_end), p_seed)
    np.testing.assert_allclose(g.q, (5 + 6 / 7) / 8)
    assert np.all(g.length >= 1.5 * 0.7 / 8) and np.all(g.length <= 1.5 * 1.3 / 8)
    assert np.all(g.level == 3) and np.all(g.chart == 2) and np.all(g.layer == 1)


def _ink(level: int) -> float:
    """Expected stroke length (cells of level 0) per tile of strokes born at levels <= level,
    counted on the lattice."""
    total = 0.0
    for b in range(level + 1):
        pts = lattice(b)
        born = [p for p in pts if b == 0 or not in_coarser(*p)]
        total += len(born) * 2.0**-b
    return total


def test_fade_in_keeps_ink_per_screen_area():
    assert fade_in(0.0) == 0.0 and fade_in(1.0) == pytest.approx(1.0)
    for big_l in (0, 1, 4):
        base, new = _ink(big_l), _ink(big_l + 1) - _ink(big_l)
        f = np.linspace(0, 1, 11)
        density = (base + fade_in(f) * new) / 2.0 ** (big_l + f)  # ink / screen area
        # the closed form of the module docstring, counted on the lattice
        np.testing.assert_allclose(density, 10.5 - 3.5 / 2.0 ** (big_l + f), rtol=1e-12)
        spread = density.max() / density.min() - 1
        assert spread <= (0.25 if big_l == 0 else 0.1 if big_l == 1 else 0.011) + 1e-9
        # continuous across the boundary: f -> 1 equals the next level at f = 0
        assert density[-1] == pytest.approx(_ink(big_l + 1) / 2.0 ** (big_l + 1))


def test_field_parameter_errors():
    with pytest.raises(ValueError, match="directions: each layer is 'u', 'v' or an angle"):
        StrokeField.from_params(directions=["w"])
    with pytest.raises(ValueError, match=r"directions: expected 1 to 4 hatching layers, got 5"):
        StrokeField.from_params(directions=[0, 1, 2, 3, 4])
    with pytest.raises(ValueError, match=r"layer_tones: expected one darkness per layer \(2\)"):
        StrokeField.from_params(directions=["u", "v"], layer_tones=[0.0])
    with pytest.raises(ValueError, match=r"max_level: expected an integer in \[0, 12\], got 13"):
        StrokeField.from_params(max_level=13)
    with pytest.raises(ValueError, match=r"period: expected a value > 0, got 0.0"):
        StrokeField.from_params(period=0.0)
    f = StrokeField.from_params(directions=["u", "v", 45])
    assert f.directions == (0.0, 90.0, 45.0)
    assert f.layer_tones == pytest.approx((0.0, 1 / 3, 2 / 3))
