"""Property tests over random cameras and hostile triangles: tiny, huge, slivers, degenerate
(zero area, collinear), behind the camera, on the eye plane (w = 0), crossing the near plane,
in a plane through the eye."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, note
from hypothesis import strategies as st

from refnpr.raster import Camera, Mesh, rasterize

from .oracle import View, cast, pixel_centres
from .scenes import BUILTIN_CHANNELS

CHANNELS = BUILTIN_CHANNELS
KINDS = (
    "generic",
    "tiny",
    "huge",
    "sliver",
    "degenerate",
    "behind",
    "near",
    "eye_plane",
    "through_eye",
)


def _unit(draw, lo=-1.0, hi=1.0):
    return draw(st.floats(lo, hi, allow_nan=False, allow_infinity=False))


@st.composite
def cameras(draw):
    eye = np.array([_unit(draw, -5.0, 5.0) for _ in range(3)])
    forward = np.array([_unit(draw) for _ in range(3)])
    assume(np.linalg.norm(forward) > 0.2)
    up = np.array([_unit(draw) for _ in range(3)])
    assume(np.linalg.norm(np.cross(forward, up)) > 0.05 * np.linalg.norm(forward))
    fov = draw(st.floats(5.0, 170.0))
    near = 10.0 ** draw(st.floats(-3.0, 0.5))
    far = near * 10.0 ** draw(st.floats(0.2, 5.0))
    cam = Camera.look_at(eye, eye + forward, up, fov, near, far)
    width = draw(st.integers(1, 24))
    height = draw(st.integers(1, 18))
    return cam, width, height


def _frame(cam: Camera, width: int, height: int):
    """Map (a, b, w): w = view-axis depth, a, b = position across the view (1 = image border)."""
    right, up, back = cam.basis()
    ty = math.tan(math.radians(cam.fov_y) / 2.0)
    tx = ty * width / height

    def point(a, b, w):
        s = max(abs(w), cam.near)
        return cam.eye + (a * s * tx) * right + (b * s * ty) * up - w * back

    return point


@st.composite
def triangles(draw, cam: Camera, width: int, height: int):
    """Three world-space vertices (3, 3) of one of KINDS, mostly in or near the view."""
    kind = draw(st.sampled_from(KINDS))
    point = _frame(cam, width, height)
    lognear, logfar = math.log10(cam.near), math.log10(cam.far)

    def depth():
        return 10.0 ** draw(st.floats(lognear - 0.5, logfar + 0.3))

    def generic():
        return point(_unit(draw, -1.5, 1.5), _unit(draw, -1.5, 1.5), depth())

    if kind == "generic":
        v = [generic() for _ in range(3)]
    elif kind == "tiny":
        base = generic()
        scale = 10.0 ** draw(st.floats(-9.0, -2.0)) * np.linalg.norm(base - cam.eye)
        v = [base] + [base + scale * np.array([_unit(draw) for _ in range(3)]) for _ in range(2)]
    elif kind == "huge":
        e = 10.0 ** draw(st.floats(2.0, 6.0))
        v = [cam.eye + np.array([_unit(draw, -e, e) for _ in range(3)]) for _ in range(3)]
    elif kind == "sliver":
        a, b = generic(), generic()
        s = draw(st.floats(-0.5, 1.5))
        perp = np.array([_unit(draw) for _ in range(3)])
        off = 10.0 ** draw(st.floats(-12.0, -4.0)) * np.linalg.norm(a - cam.eye)
        v = [a, b, a + s * (b - a) + off * perp]
    elif kind == "degenerate":
        a, b = generic(), generic()
        third = draw(st.sampled_from(["repeat", "mid", "beyond", "all_same"]))
        c = {"repeat": a, "mid": a + 0.5 * (b - a), "beyond": a + 2.0 * (b - a), "all_same": a}[
            third
        ]
        if third == "all_same":
            b = a
        v = [a, b, c]
    elif kind == "behind":
        v = [point(_unit(draw, -3, 3), _unit(draw, -3, 3), -depth() * 0.5) for _ in range(3)]
    elif kind == "near":
        w0 = cam.near * draw(st.floats(-2.0, 0.999))
        v = [point(_unit(draw, -1.5, 1.5), _unit(draw, -1.5, 1.5), w0), generic(), generic()]
    elif kind == "through_eye":  # the plane contains the eye: projects to a line
        a, b = generic(), generic()
        s, r = draw(st.floats(-1.0, 2.0)), draw(st.floats(-1.0, 2.0))
        v = [a, b, cam.eye + s * (a - cam.eye) + r * (b - cam.eye)]
    else:  # eye_plane: one vertex with w = 0, the others in front or behind
        w1 = depth() * draw(st.sampled_from([1.0, -1.0]))
        v = [
            point(_unit(draw, -2, 2), _unit(draw, -2, 2), 0.0),
            point(_unit(draw, -1.5, 1.5), _unit(draw, -1.5, 1.5), w1),
            generic(),
        ]
    order = draw(st.permutations([0, 1, 2]))
    return kind, np.array([v[i] for i in order])


@st.composite
def scenes(draw):
    cam, width, height = draw(cameras())
    tris = draw(st.lists(triangles(cam, width, height), min_size=1, max_size=4))
    kinds = [k for k, _ in tris]
    pos = np.concatenate([v for _, v in tris])
    assume(np.all(np.isfinite(pos)))
    spp = draw(st.sampled_from([1, 4]))
    cull = draw(st.booleans())
    dtype = draw(st.sampled_from([np.float32, np.float64]))
    return cam, width, height, kinds, pos, spp, cull, dtype


def _mesh(pos: np.ndarray) -> Mesh:
    faces = np.arange(len(pos)).reshape(-1, 3)
    centre = pos.mean(axis=0)
    normals = pos - centre + np.array([0.3, 0.2, 0.1])
    uv = np.stack([0.3 * pos[:, 0] + 0.1 * pos[:, 1], 0.2 * pos[:, 2] - 0.4 * pos[:, 0]], -1)
    return Mesh(pos, faces, normals=normals, uv=uv)


@pytest.mark.stress
@given(scenes())
def test_hostile_scenes_never_crash_stay_finite_and_agree_with_the_oracle(scene):
    cam, width, height, kinds, pos, spp, cull, dtype = scene
    note(f"kinds={kinds} spp={spp} cull={cull} dtype={np.dtype(dtype).name} size={width}x{height}")
    mesh = _mesh(pos)
    gb = rasterize(
        mesh,
        cam,
        width,
        height,
        CHANNELS,
        spp,
        cull_backfaces=cull,
        texture_size=(64, 32),
        dtype=dtype,
    )
    tri_id = gb["tri_id"]
    n = int(round(spp**0.5))
    assert tri_id.shape == (n * height, n * width) and tri_id.dtype == np.int32
    assert tri_id.min() >= -1 and tri_id.max() < mesh.n_faces
    covered = tri_id >= 0
    for name in CHANNELS:
        arr = gb[name]
        if name in ("tri_id", "mesh_id", "coverage", "coverage_count"):
            continue
        bad = ~np.isfinite(arr[covered])
        assert not bad.any(), (
            f"{name}: non-finite values at covered samples: {arr[covered][bad][:4]}"
        )
    depth = gb["depth"][covered]
    assert np.all(depth > 0), f"depth <= 0 at covered samples: {depth[depth <= 0][:4]}"
    np.testing.assert_array_equal(gb["coverage_count"] > 0, covered)
    assert np.all(np.isfinite(gb["coverage"])) and gb["coverage"].shape == (height, width)
    np.testing.assert_array_equal(gb["mesh_id"], np.where(covered, 0, -1))
    # ids agree with the float64 oracle away from edges and depth ties
    px, py = pixel_centres(width, height, n)
    hits = cast(View.of(cam, width, height), pos, mesh.faces, px, py, cull_backfaces=cull)
    got = tri_id.ravel()
    bad = np.flatnonzero(hits.clear & (got != hits.tri))
    assert bad.size == 0, (
        f"{bad.size} samples disagree with the oracle away from edges; sample "
        f"{np.unravel_index(bad[0], tri_id.shape)}: expected {hits.tri[bad[0]]}, got {got[bad[0]]}"
    )
