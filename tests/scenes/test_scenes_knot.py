"""Torus knot tube: closed, outward, volume, rotation-minimising frames, validation."""

import math

import numpy as np
import pytest

from refnpr.scenes import rotation_minimising_frames, torus_knot, torus_knot_curve


@pytest.mark.parametrize("p, q", [(2, 3), (3, 2), (3, 5), (1, 1), (2, 5)])
def test_torus_knot_closed_outward(checks, p, q):
    m = torus_knot(p, q, tube_radius=0.1, n_u=200, n_v=12)
    checks.assert_closed(m)
    assert m.n_faces == 2 * 200 * 12
    checks.assert_normals_match_winding(m, min_dot=0.8)
    assert m.uv.min() == 0.0 and m.uv.max() == 1.0
    checks.assert_uv_continuous(m)
    # tube: every vertex lies tube_radius from the curve along its normal
    t = 2 * np.pi * np.arange(200) / 200
    c, _ = torus_knot_curve(t, p, q, 1.0, 0.4)
    pos = m.positions.reshape(201, 13, 3)[:-1, :-1]
    nrm = m.normals.reshape(201, 13, 3)[:-1, :-1]
    assert np.allclose(pos - 0.1 * nrm, c[:, None, :], atol=1e-12)


def test_torus_knot_volume_is_tube_area_times_length(checks):
    n_u, n_v, a = 1024, 64, 0.12
    m = torus_knot(2, 3, tube_radius=a, n_u=n_u, n_v=n_v)
    tm = checks.weld_exact(m)
    # oracle: curve length by a fine Riemann sum of |c'(t)| (the integrand is smooth, periodic)
    t = 2 * np.pi * np.arange(200_000) / 200_000
    pts, _ = torus_knot_curve(t, 2, 3, 1.0, 0.4)
    length = np.linalg.norm(np.diff(np.vstack([pts, pts[:1]]), axis=0), axis=1).sum()
    polygon_area = 0.5 * n_v * a * a * math.sin(2 * math.pi / n_v)
    assert tm.volume == pytest.approx(polygon_area * length, rel=2e-3)


def test_curve_tangents_match_finite_differences():
    t = np.linspace(0.1, 6.0, 50)
    h = 1e-6
    p0, tan = torus_knot_curve(t, 3, 5, 1.2, 0.3)
    fd = (
        torus_knot_curve(t + h, 3, 5, 1.2, 0.3)[0] - torus_knot_curve(t - h, 3, 5, 1.2, 0.3)[0]
    ) / (2 * h)
    fd /= np.linalg.norm(fd, axis=1, keepdims=True)
    assert np.allclose(tan, fd, atol=1e-8)


def _rotate(v, axis, angle):
    return (
        v * math.cos(angle)
        + np.cross(axis, v) * math.sin(angle)
        + axis * (axis @ v) * (1 - math.cos(angle))
    )


def test_rotation_minimising_frames_twist_is_uniform():
    """Oracle: carry each frame to the next sample by the minimal rotation taking T_i to T_i+1
    (Rodrigues); the remaining rotation about T_i+1 is the twist. An RMF has zero twist up to
    O(h^2); the closed variant adds the same twist per step (the spread holonomy)."""
    n = 400
    t = 2 * np.pi * np.arange(n) / n
    pts, tan = torus_knot_curve(t, 2, 3, 1.0, 0.4)
    r = rotation_minimising_frames(pts, tan, closed=True)
    assert np.allclose(np.einsum("ij,ij->i", r, tan), 0.0, atol=1e-12)
    assert np.allclose(np.linalg.norm(r, axis=1), 1.0)
    twist = []
    for i in range(n):
        j = (i + 1) % n
        axis = np.cross(tan[i], tan[j])
        s = np.linalg.norm(axis)
        carried = _rotate(r[i], axis / s, math.atan2(s, tan[i] @ tan[j])) if s > 0 else r[i]
        twist.append(math.atan2(np.cross(carried, r[j]) @ tan[j], carried @ r[j]))
    twist = np.array(twist)
    assert np.ptp(twist) < 1e-4  # constant twist per step ...
    assert abs(twist.mean()) < math.pi / n  # ... and less than half a turn in total
    open_r = rotation_minimising_frames(pts, tan, closed=False)
    assert np.allclose(np.einsum("ij,ij->i", open_r, tan), 0.0, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(p=2, q=4), r"p, q: must be coprime .* got p=2, q=4 \(common factor 2\)"),
        (dict(p=0), "p: expected an integer >= 1, got 0"),
        (dict(R=1.0, r=1.5), r"r: must be smaller than R \(1.0\), got 1.5"),
        (dict(tube_radius=0.5), "tube_radius: 0.5 makes the tube intersect itself"),
        (dict(n_u=4), "n_u: expected an integer >= 8, got 4"),
    ],
)
def test_torus_knot_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        torus_knot(**kwargs)
