"""uv projections, require_uv, and loading user meshes through trimesh."""

import numpy as np
import pytest
import trimesh

from refnpr.raster import Mesh
from refnpr.scenes import (
    icosphere,
    load_mesh,
    project_uv,
    require_uv,
    teapot,
    torus,
    torus_knot,
)


def _no_uv(mesh):
    return mesh.with_(uv=None)


@pytest.mark.parametrize("kind", ["planar", "box", "spherical", "cylindrical"])
@pytest.mark.parametrize(
    "build",
    [lambda: icosphere(2), lambda: torus(1.0, 0.4, 24, 12), lambda: torus_knot(n_u=64, n_v=8)],
)
def test_projection_keeps_closed_and_continuous(checks, kind, build):
    m = project_uv(_no_uv(build()), kind)
    checks.assert_closed(m)
    assert m.uv.min() >= 0.0
    assert m.uv[:, 1].max() <= 1.0
    assert m.uv[:, 0].max() <= (1.0 if kind in ("planar", "box") else 1.5)
    checks.assert_uv_continuous(m)
    # duplicated vertices carry their source's normal
    assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0)


def test_planar_projection_formula():
    m = teapot(3)
    p = m.positions
    uv = project_uv(m, "planar").uv  # default axis z: u = x, v = y, one common scale
    scale = max(np.ptp(p[:, 0]), np.ptp(p[:, 1]))
    assert np.allclose(uv, (p[:, :2] - p[:, :2].min(axis=0)) / scale)
    uv_y = project_uv(m, "planar", axis="y").uv  # seen from above: u = x, v = -z
    q = np.stack([p[:, 0], -p[:, 2]], axis=1)
    assert np.allclose(uv_y, (q - q.min(axis=0)) / np.ptp(q, axis=0).max())


def test_box_projection_matches_per_face_oracle():
    m = project_uv(_no_uv(torus(1.0, 0.4, 16, 8)), "box")
    p = m.positions
    extent = np.ptp(p, axis=0).max()
    lo, hi = p.min(axis=0), p.max(axis=0)
    for f in m.faces:  # naive loop: each face projects along its dominant normal axis
        n = np.cross(p[f[1]] - p[f[0]], p[f[2]] - p[f[0]])
        a = int(np.argmax(np.abs(n)))
        b, c = [i for i in range(3) if i != a]
        if a == 1:  # seen from +y: u = x, v = -z ; from -y: u = x, v = z
            u = p[f, 0] - lo[0]
            v = (hi[2] - p[f, 2]) if n[1] > 0 else (p[f, 2] - lo[2])
        elif a == 0:  # from +x: u = -z ; from -x: u = z ; v = y
            u = (hi[2] - p[f, 2]) if n[0] > 0 else (p[f, 2] - lo[2])
            v = p[f, 1] - lo[1]
        else:  # from +z: u = x ; from -z: u = -x ; v = y
            u = (p[f, 0] - lo[0]) if n[2] > 0 else (hi[0] - p[f, 0])
            v = p[f, 1] - lo[1]
        assert np.allclose(m.uv[f], np.stack([u, v], axis=1) / extent)


def test_spherical_and_cylindrical_angles():
    m = icosphere(2)
    for kind in ("spherical", "cylindrical"):
        out = project_uv(m, kind)
        p = out.positions
        off_axis = np.hypot(p[:, 0], p[:, 2]) > 1e-9
        ang = np.arctan2(-p[off_axis, 2], p[off_axis, 0]) / (2 * np.pi) % 1.0
        d = np.abs(out.uv[off_axis, 0] - ang)
        assert np.allclose(np.minimum(d, np.abs(d - 1.0)), 0.0, atol=1e-12)
    cyl = project_uv(m, "cylindrical")
    assert np.allclose(cyl.uv[:, 1], (cyl.positions[:, 1] + 1.0) / 2.0)
    sph = project_uv(m, "spherical", axis="z")  # about z: v from the z coordinate
    assert np.allclose(sph.uv[:, 1], np.arcsin(np.clip(sph.positions[:, 2], -1, 1)) / np.pi + 0.5)


def test_require_uv_message():
    m = icosphere(1)
    assert require_uv(m) is m
    with pytest.raises(
        ValueError,
        match=r"mesh 'icosphere' has no uv, which halftone needs; pass "
        r"uv_projection='planar'\|'box'\|'spherical'\|'cylindrical' to load_mesh",
    ):
        require_uv(_no_uv(m), needed_by="halftone")


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(kind="cubic"), ValueError, "kind: unknown uv projection 'cubic'"),
        (dict(kind="planar", axis="w"), ValueError, "axis: expected 'x', 'y' or 'z', got 'w'"),
        (dict(kind="box", axis="x"), ValueError, "axis: the box projection uses all three axes"),
    ],
)
def test_project_uv_validation(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        project_uv(icosphere(0), **kwargs)
    with pytest.raises(ValueError, match="all vertices coincide"):
        project_uv(Mesh(np.zeros((3, 3)), [[0, 1, 2]]), "planar")


def _source_mesh():
    tm = trimesh.creation.icosphere(subdivisions=2)
    rng = np.random.default_rng(7)
    tm.visual = trimesh.visual.TextureVisuals(uv=rng.random((len(tm.vertices), 2)))
    return tm


@pytest.mark.parametrize(
    "ext, has_uv", [("obj", True), ("ply", True), ("stl", False), ("off", False), ("glb", True)]
)
def test_load_mesh_formats(tmp_path, ext, has_uv):
    src = _source_mesh()
    path = tmp_path / f"ball.{ext}"
    src.export(path)
    m = load_mesh(path)
    assert isinstance(m, Mesh)
    assert m.n_faces == len(src.faces)
    # the same surface: same set of (rounded) positions, and closed
    got = np.unique(np.round(m.positions, 6), axis=0)
    assert np.array_equal(got, np.unique(np.round(src.vertices, 6), axis=0))
    assert trimesh.Trimesh(m.positions, m.faces).is_watertight
    assert (m.uv is not None) == has_uv
    if has_uv:  # uv survive: compare per position
        order_src = np.lexsort(np.round(src.vertices, 6).T)
        order_got = np.lexsort(np.round(m.positions, 6).T)
        assert np.allclose(m.uv[order_got], src.visual.uv[order_src], atol=1e-6)
    assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-6)
    assert np.all(np.einsum("ij,ij->i", m.normals, m.positions) > 0)  # outward on a sphere
    if not has_uv:
        with pytest.raises(ValueError, match="has no uv"):
            require_uv(m)
        projected = load_mesh(path, uv_projection="spherical")
        assert projected.uv is not None and projected.uv.min() >= 0.0


def test_load_mesh_multi_geometry_glb(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(), node_name="box", geom_name="box")
    scene.add_geometry(
        trimesh.creation.icosphere(1),
        node_name="ball",
        geom_name="ball",
        transform=trimesh.transformations.translation_matrix([3.0, 0.0, 0.0]),
    )
    path = tmp_path / "two.glb"
    scene.export(path)
    meshes = load_mesh(path, uv_projection="box")
    assert isinstance(meshes, list) and len(meshes) == 2
    by_faces = {m.n_faces: m for m in meshes}
    assert set(by_faces) == {12, 80}
    assert by_faces[80].positions[:, 0].mean() == pytest.approx(3.0, abs=1e-6)  # node transform
    assert all(m.uv is not None for m in meshes)


def test_load_mesh_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="path: mesh file .*nope.obj' does not exist"):
        load_mesh(tmp_path / "nope.obj")
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"\x00garbage")
    with pytest.raises(ValueError, match="path: trimesh could not read|contains no triangle"):
        load_mesh(bad)
    good = tmp_path / "ok.stl"
    trimesh.creation.box().export(good)
    with pytest.raises(ValueError, match="uv_projection: unknown projection 'polar'"):
        load_mesh(good, uv_projection="polar")
