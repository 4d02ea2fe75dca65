"""UV sphere, icosphere, torus and vase: closed, outward, uv ranges, counts, validation."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.scenes import icosphere, torus, uv_sphere, vase
from refnpr.scenes.revolution import vase_profile


@pytest.mark.parametrize("n_u, n_v", [(3, 2), (4, 3), (64, 32), (17, 5)])
def test_uv_sphere_closed_outward_counts(checks, n_u, n_v):
    m = uv_sphere(2.0, n_u, n_v)
    checks.assert_closed(m)
    assert m.n_faces == 2 * n_u * (n_v - 1)
    checks.assert_normals_match_winding(m, min_dot=0.0 if n_v < 4 else 0.5)
    # convex: normal . (vertex - centre) > 0, and normals are the unit positions
    assert np.all(np.einsum("ij,ij->i", m.normals, m.positions) > 0.0)
    assert np.allclose(m.normals * 2.0, m.positions, atol=1e-12)
    assert m.uv.min() >= 0.0 and m.uv.max() <= 1.0
    span = np.ptp(m.uv[m.faces], axis=1)  # each triangle covers one grid cell
    assert np.all(span[:, 0] <= 1.0 / n_u + 1e-12) and np.all(span[:, 1] <= 1.0 / n_v + 1e-12)


@given(n_u=st.integers(3, 40), n_v=st.integers(2, 30), radius=st.floats(0.01, 100.0))
def test_uv_sphere_closed_property(checks, n_u, n_v, radius):
    m = uv_sphere(radius, n_u, n_v)
    checks.assert_closed(m)
    assert np.allclose(np.linalg.norm(m.positions, axis=1), radius, rtol=1e-12)


def test_uv_sphere_volume_converges():
    tm_volume = uv_sphere(1.0, 256, 128)
    import trimesh

    vol = trimesh.Trimesh(tm_volume.positions, tm_volume.faces, process=True).volume
    assert vol == pytest.approx(4.0 / 3.0 * math.pi, rel=1e-3)


def test_uv_sphere_uv_layout():
    m = uv_sphere(1.0, 8, 4)
    y = m.positions[:, 1]
    # v = latitude / pi + 1/2 (independent: from the positions)
    assert np.allclose(m.uv[:, 1], np.arcsin(np.clip(y, -1, 1)) / np.pi + 0.5, atol=1e-12)
    off_pole = np.abs(y) < 1.0 - 1e-12
    ang = np.arctan2(-m.positions[off_pole, 2], m.positions[off_pole, 0]) / (2 * np.pi) % 1.0
    u = m.uv[off_pole, 0]
    assert np.allclose(np.minimum(np.abs(u - ang), np.abs(np.abs(u - ang) - 1.0)), 0.0, atol=1e-12)


@pytest.mark.parametrize("subdivisions", [0, 1, 2, 3, 4])
def test_icosphere_closed_outward(checks, subdivisions):
    m = icosphere(subdivisions, radius=1.5)
    checks.assert_closed(m)
    assert m.n_faces == 20 * 4**subdivisions
    assert np.allclose(np.linalg.norm(m.positions, axis=1), 1.5, rtol=1e-12)
    assert np.all(np.einsum("ij,ij->i", m.normals, m.positions) > 0.0)
    checks.assert_normals_match_winding(m)
    assert m.uv[:, 0].min() >= 0.0 and m.uv[:, 0].max() < 1.25
    assert m.uv[:, 1].min() >= 0.0 and m.uv[:, 1].max() <= 1.0
    checks.assert_uv_continuous(m)


def test_icosphere_large_counts():
    assert icosphere(6).n_faces == 81_920
    m = icosphere(8)
    assert m.n_faces == 1_310_720
    # Euler characteristic of the welded sphere: V - E + F = 2 with E = 3F/2
    n_unique = np.unique(m.positions, axis=0).shape[0]
    assert n_unique - 3 * m.n_faces // 2 + m.n_faces == 2


def test_icosphere_seam_u_matches_angle():
    m = icosphere(3)
    p = m.positions
    off_pole = np.hypot(p[:, 0], p[:, 2]) > 1e-9
    ang = np.arctan2(-p[off_pole, 2], p[off_pole, 0]) / (2 * np.pi) % 1.0
    d = np.abs(m.uv[off_pole, 0] - ang)
    assert np.allclose(np.minimum(d, np.abs(d - 1.0)), 0.0, atol=1e-12)


@pytest.mark.parametrize(
    "R, r, n_u, n_v", [(1.0, 0.35, 64, 32), (2.0, 0.5, 3, 3), (1.0, 0.9, 7, 11)]
)
def test_torus_closed_outward(checks, R, r, n_u, n_v):
    m = torus(R, r, n_u, n_v)
    tm = checks.assert_closed(m)
    assert m.n_faces == 2 * n_u * n_v
    # outward: normal . (vertex - nearest point of the core circle) > 0
    p = m.positions
    ring = np.hypot(p[:, 0], p[:, 2])
    core = np.stack([p[:, 0] / ring * R, np.zeros_like(ring), p[:, 2] / ring * R], axis=1)
    assert np.allclose(np.einsum("ij,ij->i", m.normals, p - core), r, rtol=1e-9)
    checks.assert_normals_match_winding(m, min_dot=0.0)
    assert m.uv.min() >= 0.0 and m.uv.max() <= 1.0
    checks.assert_uv_continuous(m)
    if n_u >= 64:
        assert tm.volume == pytest.approx(2 * math.pi**2 * R * r * r, rel=1e-2)


def test_vase_closed_outward(checks):
    m = vase(height=2.0, radius=1.0, thickness=0.05, n_u=48, n_v=32)
    tm = checks.assert_closed(m)
    checks.assert_normals_match_winding(m, min_dot=0.5)
    assert m.uv.min() >= 0.0 and m.uv.max() <= 1.0
    checks.assert_uv_continuous(m)
    # the solid is the wall: its volume ~ the shell between outer and inner profile, plus the floor
    s = np.linspace(0.0, 1.0, 20001)
    f, _ = vase_profile(s)
    outer = np.trapezoid(np.pi * f**2, s * 2.0)
    inner_s = s[s * 2.0 >= 0.05]
    f_in, _ = vase_profile(inner_s)
    inner = np.trapezoid(np.pi * (f_in - 0.05) ** 2, inner_s * 2.0)
    assert tm.volume == pytest.approx(outer - inner, rel=2e-2)
    assert m.positions[:, 1].min() == 0.0 and m.positions[:, 1].max() == 2.0


@given(n_u=st.integers(3, 24), n_v=st.integers(1, 12), thickness=st.floats(0.005, 0.2))
def test_vase_closed_property(checks, n_u, n_v, thickness):
    checks.assert_closed(vase(thickness=thickness, n_u=n_u, n_v=n_v))


@pytest.mark.parametrize(
    "call, exc, match",
    [
        (lambda: uv_sphere(0.0), ValueError, "radius: expected a positive number, got 0.0"),
        (lambda: uv_sphere(1.0, 2), ValueError, "n_u: expected an integer >= 3, got 2"),
        (lambda: uv_sphere(1.0, 8, 1.5), TypeError, "n_v: expected an integer, got float"),
        (lambda: icosphere(10), ValueError, "subdivisions: expected an integer <= 9"),
        (lambda: icosphere(True), TypeError, "subdivisions: expected an integer, got bool"),
        (lambda: torus(1.0, 1.0), ValueError, r"r: the tube radius must be smaller than R \(1.0\)"),
        (lambda: torus(1.0, float("nan")), ValueError, "r: expected a finite number, got nan"),
        (lambda: vase(thickness=0.4), ValueError, "thickness: must be smaller than the narrowest"),
        (lambda: vase(height=0.01), ValueError, r"thickness: must be smaller than height \(0.01\)"),
    ],
)
def test_primitive_validation(call, exc, match):
    with pytest.raises(exc, match=match):
        call()
