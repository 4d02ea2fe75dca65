"""Raw check of Wavefront OBJ files (continuation lines, v/vt/vn indices, negative indices)."""

from __future__ import annotations

import re
from collections.abc import Callable

import numpy as np

from .common import (
    _SPACE,
    BadMeshFile,
    _check_faces,
    _check_finite,
    _float,
    _gather,
    _lines,
    _numbers,
)


def _obj_text(data: bytes) -> tuple[bytes, Callable[[int], int]]:
    """Continuation lines joined (as trimesh does), comments and leading blanks dropped; and a
    map from a joined line's number (one-based) to the file's."""
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n")
    joined: list[int] = []
    if b"\\\n" in data:
        joined = [i for i, ln in enumerate(data.split(b"\n"), 1) if ln.endswith(b"\\")]
        data = data.replace(b"\\\n", b"")
    if b"#" in data:
        data = re.sub(rb"#[^\n]*", b"", data)
    if re.search(rb"(?m)^[ \t]", data):
        data = re.sub(rb"(?m)^[ \t]+", b"", data)

    def line_of(n: int) -> int:
        for j in joined:
            if j < n:
                n += 1
        return n

    return data, line_of


def _is_key(key: int):
    return lambda c0, c1: (c0 == key) & _SPACE[c1]


def _check_obj(data: bytes) -> None:
    data, line_of = _obj_text(data)
    vbuf, vrows, vcount = _lines(data, _is_key(ord("v")))
    nv = vrows.size
    vals = _numbers(vbuf)
    if vals is None or vals.size != vcount.sum() or (vcount < 3).any():
        for i, ln in enumerate(vbuf.split(b"\n")[:nv]):
            tok = ln.decode("utf-8", "replace").split()
            where = f"line {line_of(int(vrows[i]) + 1)}: vertex {('v ' + ' '.join(tok))[:60]!r}"
            if len(tok) < 3:
                raise BadMeshFile(f"{where} needs 3 coordinates")
            for t in tok:
                _float(t, where)
        raise BadMeshFile("a vertex line does not parse")  # pragma: no cover -- found above
    verts = _gather(vals, vcount, 0, np.full(nv, 3)).reshape(-1, 3)
    _check_finite(verts, lambda i: f"line {line_of(int(vrows[i]) + 1)}: vertex {i + 1}")
    del vals, verts

    fbuf, frows, _ = _lines(data, _is_key(ord("f")))
    fbuf = re.sub(rb"/[^ \t\r\n]*", b"", fbuf)  # "f 1/2/3 ..." -> "f 1 ..."
    fcount = _lines(fbuf)[2] if frows.size else np.zeros(0, np.int64)
    idx = _numbers(fbuf, np.int64)
    if idx is None or idx.size != fcount.sum():
        for i, ln in enumerate(fbuf.split(b"\n")[: frows.size]):
            for tok in ln.decode("utf-8", "replace").split():
                try:
                    int(tok)
                except ValueError:
                    raise BadMeshFile(
                        f"line {line_of(int(frows[i]) + 1)}: face index {tok[:40]!r} is not an "
                        "integer"
                    ) from None
        raise BadMeshFile("a face line does not parse")  # pragma: no cover -- found above
    if not frows.size:
        raise BadMeshFile(f"no faces ({nv} vertices; a point cloud, or not an OBJ file?)")
    face_of = np.repeat(np.arange(frows.size), fcount)
    zero = np.flatnonzero(idx == 0)
    if zero.size:
        row = int(frows[face_of[zero[0]]])
        raise BadMeshFile(f"line {line_of(row + 1)}: face index 0 (OBJ indices start at 1)")
    neg = np.flatnonzero(idx < 0)
    idx -= 1
    if neg.size:  # relative to the vertices so far
        idx[neg] += 1 + np.searchsorted(vrows, frows[face_of[neg]])
    del face_of
    _check_faces(fcount, idx, nv, lambda i: f"line {line_of(int(frows[i]) + 1)}", base=1)
