"""Raw check (and parse) of OFF files, records one per line or wrapped."""

from __future__ import annotations

import re

import numpy as np

from .common import (
    BadMeshFile,
    _check_faces,
    _check_finite,
    _float,
    _gather,
    _integral,
    _is_count,
    _lines,
    _numbers,
)


def _off_width(key: str) -> int:
    """Numbers per vertex record from the keyword ([ST][C][N][4][n]OFF)."""
    k = key[:-3]
    return 3 + 2 * ("ST" in k) + 4 * ("C" in k) + 3 * ("N" in k) + ("4" in k)


def _check_off(data: bytes) -> dict:
    if b"#" in data:
        data = re.sub(rb"#[^\n]*", b"", data)
    m = re.match(rb"\s*(\S+)", data)
    key = m.group(1).decode("ascii", "replace") if m else ""
    if not key.upper().endswith("OFF") or key[:-3].strip("STCN4n"):
        raise BadMeshFile("not an OFF file (the first line must be 'OFF')")
    hm = re.compile(rb"\s*(\S+)\s+(\S+)(?:[ \t]+\S+)?[ \t]*").match(data, m.end())
    try:
        nv, nf = int(hm.group(1)), int(hm.group(2))
    except (AttributeError, ValueError):
        raise BadMeshFile("header: expected vertex and face counts after 'OFF'") from None
    if nv < 0 or nf < 0:
        raise BadMeshFile(f"header: negative counts ({nv} vertices, {nf} faces)")
    body = data[hm.end() :]
    buf, _, counts = _lines(body)
    lines = np.flatnonzero(counts)
    counts = counts[lines]
    vals = _numbers(buf)
    if vals is None:
        for i, tok in enumerate(buf.decode("ascii", "replace").split()):
            _float(tok, f"value {i} after the header")
        raise BadMeshFile("the body does not parse as numbers")  # pragma: no cover
    if lines.size >= nv + nf and (counts[:nv] >= 3).all():  # one record a line
        verts = _gather(vals, counts[:nv], 0, np.full(nv, 3)).reshape(-1, 3)
        rest = vals[int(counts[:nv].sum()) :]
        fl = counts[nv : nv + nf]
        k = rest[np.cumsum(fl) - fl] if nf else rest[:0]
        if np.all((k >= 0) & (k == np.floor(k)) & (k + 1 <= fl)):
            fcount = k.astype(np.int64)
            flat = _gather(rest[: int(fl.sum())], fl, 1, fcount)
        else:
            verts = None
    else:
        verts = None
    if verts is None:  # records wrapped across lines: a stream of numbers
        verts, fcount, flat = _off_stream(vals, nv, nf, _off_width(key))
    _check_finite(verts, lambda i: f"vertex {i}")
    flat = _integral(fcount, flat)
    _check_faces(fcount, flat, nv, lambda i: f"face {i}")
    if not fcount.size:
        raise BadMeshFile(f"no faces ({nv} vertices; a point cloud?)")
    # fan triangulation (trimesh reads OFF line by line, so load_mesh takes these arrays)
    nt = fcount - 2
    face = np.repeat(np.arange(fcount.size), nt)
    j = np.arange(int(nt.sum())) - np.repeat(np.cumsum(nt) - nt, nt) + 1
    s = (np.cumsum(fcount) - fcount)[face]
    tris = np.stack([flat[s], flat[s + j], flat[s + j + 1]], -1)
    return {"vertices": verts, "faces": tris}


def _off_stream(vals: np.ndarray, nv: int, nf: int, width: int):
    if vals.size < nv * width:
        raise BadMeshFile(
            f"truncated: the header declares {nv} vertices and {nf} faces, but only "
            f"{vals.size} values follow"
        )
    verts = vals[: nv * width].reshape(nv, width)[:, :3]
    lv = vals[nv * width :].tolist()
    counts, flat, k = [], [], 0
    for i in range(nf):
        if k >= len(lv):
            raise BadMeshFile(
                f"truncated: the header declares {nv} vertices and {nf} faces, but only {i} "
                "faces follow"
            )
        n = lv[k]
        if not _is_count(n) or k + 1 + int(n) > len(lv):
            raise BadMeshFile(f"face {i}: declares {n} vertices, the file has fewer")
        counts.append(int(n))
        flat.extend(lv[k + 1 : k + 1 + int(n)])
        k += 1 + int(n)
    return verts, np.array(counts, np.int64), np.array(flat, np.float64)
