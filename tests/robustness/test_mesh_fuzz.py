"""Fuzzing the mesh loader: random truncations and byte flips of small valid OBJ, PLY (ASCII and
binary), STL (ASCII and binary), OFF and GLB files.

``load_mesh(path)`` owes one of two outcomes: a ``ValueError``/``TypeError`` whose message
contains the path, or meshes with finite positions (within ``MAX_COORDINATE``) whose faces index
existing vertices. No other exception type may escape.
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.raster import Mesh
from refnpr.raster import mesh as _mesh_module
from refnpr.scenes import load_mesh

#: The Mesh bound on |coordinate| (1e15 where an older refnpr has no such constant).
MAX_COORDINATE = getattr(_mesh_module, "MAX_COORDINATE", 1e15)

FORMATS = ("obj", "ply-ascii", "ply-binary", "stl-ascii", "stl-binary", "off", "glb")


def _source_bytes() -> dict[str, bytes]:
    import trimesh

    tm = trimesh.creation.icosphere(subdivisions=0)  # 12 vertices, 20 faces: small files
    tm.visual = trimesh.visual.TextureVisuals(uv=np.linspace(0, 1, 24).reshape(12, 2))
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in FORMATS:
            ext = fmt.split("-")[0]
            path = Path(tmp) / f"src.{ext}"
            if fmt == "ply-ascii":
                tm.export(path, encoding="ascii")
            elif fmt == "stl-ascii":
                tm.export(path, file_type="stl_ascii")
            else:
                tm.export(path)
            out[fmt] = path.read_bytes()
    return out


SOURCES = _source_bytes()


@st.composite
def mutations(draw, data: bytes) -> bytes:
    buf = bytearray(data)
    if draw(st.booleans()):  # truncate
        buf = buf[: draw(st.integers(0, len(buf)))]
    for _ in range(draw(st.integers(0 if buf else 0, 4))):
        if not buf:
            break
        i = draw(st.integers(0, len(buf) - 1))
        if draw(st.booleans()):
            buf[i] = draw(st.integers(0, 255))  # any byte
        else:  # a plausible text edit: a digit, a sign, a letter of nan/inf, a separator
            buf[i] = draw(st.sampled_from(b"0123456789-+.eEnaif \n/"))
    return bytes(buf)


def _check_outcome(path: Path, data: bytes) -> None:
    path.write_bytes(data)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter(
                "ignore"
            )  # trimesh and numpy warn on odd input; the outcome counts
            result = load_mesh(path)
    except (ValueError, TypeError) as exc:
        assert str(path) in str(exc), f"message does not name the file: {exc}"
        return
    meshes = result if isinstance(result, list) else [result]
    assert meshes
    for m in meshes:
        assert isinstance(m, Mesh)
        assert np.all(np.isfinite(m.positions))
        assert np.abs(m.positions).max() <= MAX_COORDINATE
        assert m.faces.shape[0] > 0 and m.faces.shape[1] == 3
        assert m.faces.min() >= 0 and m.faces.max() < m.n_vertices
        for arr in (m.normals, m.uv):
            assert arr is None or np.all(np.isfinite(arr))


def _run(fmt: str, data: bytes) -> None:
    ext = fmt.split("-")[0]
    with tempfile.TemporaryDirectory() as tmp:
        _check_outcome(Path(tmp) / f"fuzzed.{ext}", data)


@pytest.mark.parametrize("fmt", FORMATS)
def test_unmutated_sources_load(fmt):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"src.{fmt.split('-')[0]}"
        path.write_bytes(SOURCES[fmt])
        m = load_mesh(path)
        assert isinstance(m, Mesh) and m.n_faces == 20


@pytest.mark.parametrize("fmt", FORMATS)
def test_fuzzed_mesh_files_fail_clearly_or_load_valid(fmt):
    @settings(max_examples=25)
    @given(mutations(SOURCES[fmt]))
    def run(data):
        _run(fmt, data)

    run()


@pytest.mark.stress
@pytest.mark.parametrize("fmt", FORMATS)
def test_fuzzed_mesh_files_stress(fmt):
    @given(mutations(SOURCES[fmt]))  # example count from the active profile
    def run(data):
        _run(fmt, data)

    run()
