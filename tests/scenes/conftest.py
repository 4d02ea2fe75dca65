"""Mesh checks shared by the scenes tests (independent of the code under test: exact-position
welding with numpy, topology and volume with trimesh)."""

from types import SimpleNamespace

import numpy as np
import pytest
import trimesh


def weld_exact(mesh):
    """trimesh.Trimesh with vertices merged by bitwise-equal position (no tolerance)."""
    unique, inverse = np.unique(mesh.positions, axis=0, return_inverse=True)
    return trimesh.Trimesh(unique, inverse.reshape(-1)[mesh.faces], process=False)


def edge_use(tm):
    """How many faces use each undirected edge: (E,) counts."""
    _, counts = np.unique(tm.edges_sorted, axis=0, return_counts=True)
    return counts


def assert_closed(mesh):
    """Watertight after exact welding, consistently wound, positive volume, no zero-area faces."""
    tm = weld_exact(mesh)
    assert tm.is_watertight, f"{mesh.name}: not watertight after exact welding"
    assert tm.is_winding_consistent, f"{mesh.name}: inconsistent winding"
    assert np.all(edge_use(tm) == 2)
    assert tm.volume > 0.0, f"{mesh.name}: signed volume {tm.volume} <= 0 (faces inward)"
    assert_no_degenerate(mesh)
    return tm


def assert_no_degenerate(mesh):
    p = mesh.positions[mesh.faces]
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    assert area2.min() > 0.0, f"{mesh.name}: zero-area triangle"


def face_normals(mesh):
    p = mesh.positions[mesh.faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def assert_normals_match_winding(mesh, min_dot=0.5):
    """Vertex normals are unit and on the side the counter-clockwise winding faces."""
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    fn = face_normals(mesh)
    dots = np.einsum("fj,fkj->fk", fn, mesh.normals[mesh.faces])
    assert dots.min() > min_dot, f"{mesh.name}: vertex normal against face normal ({dots.min()})"


def assert_uv_continuous(mesh, max_jump=0.5):
    """No triangle spans more than ``max_jump`` in u or v (seams are split, not wrapped)."""
    fu = mesh.uv[mesh.faces]
    span = fu.max(axis=1) - fu.min(axis=1)
    assert span.max() < max_jump, f"{mesh.name}: a triangle spans {span.max()} in uv"


@pytest.fixture(scope="session")
def checks():
    return SimpleNamespace(
        weld_exact=weld_exact,
        edge_use=edge_use,
        assert_closed=assert_closed,
        assert_no_degenerate=assert_no_degenerate,
        face_normals=face_normals,
        assert_normals_match_winding=assert_normals_match_winding,
        assert_uv_continuous=assert_uv_continuous,
    )
