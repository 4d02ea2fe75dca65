"""Raw checks of mesh files before trimesh reads them, and of what it read.

trimesh silently drops non-finite vertices with their faces, reads a truncated ASCII PLY as a
partial mesh and reports a truncated binary STL with an unrelated message; these parsers check
each file against its own format first. Every check raises :class:`BadMeshFile` (what is wrong)
and never anything else; :func:`refnpr.scenes.load_mesh` adds the path.
"""

from __future__ import annotations

import math
import re
import struct

import numpy as np

from ..raster.mesh import MAX_COORDINATE

__all__ = ["BadMeshFile", "CHECKS", "FIX", "check_geometry"]


class BadMeshFile(Exception):
    """What is wrong with a file (the caller adds the path)."""


FIX = "re-export the file from its source, or repair it"


def _float(tok: str, where: str) -> float:
    try:
        v = float(tok)
    except ValueError:
        raise BadMeshFile(f"{where}: {tok[:40]!r} is not a number") from None
    if not math.isfinite(v):
        raise BadMeshFile(
            f"{where}: non-finite coordinate {tok[:40]!r}; every vertex must be finite"
        )
    return v


def _check_faces(faces: list[list[int]] | np.ndarray, nv: int, where: str) -> None:
    for i, f in enumerate(faces):
        if len(f) < 3:
            raise BadMeshFile(f"{where} {i}: a face needs at least 3 vertices, got {len(f)}")
        for j in f:
            if not 0 <= j < nv:
                raise BadMeshFile(
                    f"{where} {i}: vertex index {j} is out of range for {nv} vertices (missing "
                    "vertices? the file may be truncated or corrupt)"
                )


def _check_obj(data: bytes) -> None:
    text = data.decode("utf-8", errors="replace")
    nv = 0
    faces: list[tuple[int, list[int]]] = []  # (line number, indices made zero-based)
    for ln, line in enumerate(text.splitlines(), 1):
        parts = line.split("#", 1)[0].split()
        if not parts:
            continue
        if parts[0] == "v":
            if len(parts) < 4:
                raise BadMeshFile(f"line {ln}: vertex {line.strip()[:60]!r} needs 3 coordinates")
            for tok in parts[1:4]:
                _float(tok, f"line {ln}: vertex {line.strip()[:60]!r}")
            nv += 1
        elif parts[0] == "f":
            idx = []
            for tok in parts[1:]:
                head = tok.split("/", 1)[0]
                try:
                    k = int(head)
                except ValueError:
                    raise BadMeshFile(
                        f"line {ln}: face index {tok[:40]!r} is not an integer"
                    ) from None
                if k == 0:
                    raise BadMeshFile(f"line {ln}: face index 0 (OBJ indices start at 1)")
                idx.append(k - 1 if k > 0 else nv + k)  # negative: relative to the vertices so far
            faces.append((ln, idx))
    for ln, idx in faces:
        if len(idx) < 3:
            raise BadMeshFile(f"line {ln}: a face needs at least 3 vertices, got {len(idx)}")
        for j in idx:
            if not 0 <= j < nv:
                raise BadMeshFile(
                    f"line {ln}: face references vertex {j + 1}, but the file has {nv} vertices"
                )
    if not faces:
        raise BadMeshFile(f"no faces ({nv} vertices; a point cloud, or not an OBJ file?)")


_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip


def _ply_header(data: bytes):
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise BadMeshFile("not a PLY file (no 'ply' ... 'end_header' header)")
    nl = data.find(b"\n", end)
    body_start = len(data) if nl < 0 else nl + 1
    fmt = None
    elements: list[tuple[str, int, list]] = []  # (name, count, [(prop, dtype | (count, item))])
    for raw in data[:end].decode("ascii", errors="replace").splitlines()[1:]:
        w = raw.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "format" and len(w) >= 2:
            fmt = w[1]
        elif w[0] == "element" and len(w) == 3:
            try:
                count = int(w[2])
            except ValueError:
                raise BadMeshFile(f"header: element count {w[2]!r} is not an integer") from None
            if count < 0:
                raise BadMeshFile(f"header: negative element count {count}")
            elements.append((w[1], count, []))
        elif w[0] == "property" and elements:
            if len(w) == 5 and w[1] == "list" and w[2] in _PLY_TYPES and w[3] in _PLY_TYPES:
                elements[-1][2].append((w[4], (_PLY_TYPES[w[2]], _PLY_TYPES[w[3]])))
            elif len(w) == 3 and w[1] in _PLY_TYPES:
                elements[-1][2].append((w[2], _PLY_TYPES[w[1]]))
            else:
                raise BadMeshFile(f"header: malformed property line {raw.strip()[:60]!r}")
        else:
            raise BadMeshFile(f"header: unexpected line {raw.strip()[:60]!r}")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise BadMeshFile(f"header: unknown format {fmt!r}")
    return fmt, elements, body_start


def _check_ply(data: bytes) -> None:
    fmt, elements, start = _ply_header(data)
    verts: np.ndarray | None = None
    faces: list = []
    if fmt == "ascii":
        lines = [ln for ln in data[start:].decode("ascii", errors="replace").splitlines()]
        lines = [ln.split() for ln in lines if ln.strip() and not ln.startswith("comment")]
        pos = 0
        for name, count, props in elements:
            if pos + count > len(lines):
                raise BadMeshFile(
                    f"truncated: the header declares {count} {name} elements, but only "
                    f"{len(lines) - pos} lines follow (the file was cut short?)"
                )
            rows = []
            for r in range(count):
                tok, k, row = lines[pos + r], 0, {}
                for pname, typ in props:
                    if isinstance(typ, tuple):
                        try:
                            n = int(tok[k])
                        except (IndexError, ValueError):
                            raise BadMeshFile(
                                f"{name} {r}: bad list length in line {tok[:8]}"
                            ) from None
                        if n < 0 or k + 1 + n > len(tok):
                            raise BadMeshFile(
                                f"{name} {r}: list of {n} items does not fit the line"
                            )
                        try:
                            row[pname] = [int(t) for t in tok[k + 1 : k + 1 + n]]
                        except ValueError:
                            row[pname] = [float("nan")]  # non-integer index list
                        k += 1 + n
                    else:
                        if k >= len(tok):
                            raise BadMeshFile(f"{name} {r}: too few values in line {tok[:8]}")
                        try:
                            row[pname] = float(tok[k])
                        except ValueError:
                            raise BadMeshFile(
                                f"{name} {r}: {tok[k][:40]!r} is not a number"
                            ) from None
                        k += 1
                rows.append(row)
            pos += count
            if name == "vertex":
                verts = np.array(
                    [[row.get(c, 0.0) for c in ("x", "y", "z")] for row in rows], dtype=np.float64
                ).reshape(-1, 3)
            elif name == "face":
                key = next((p for p, t in props if isinstance(t, tuple)), None)
                faces = [row[key] for row in rows] if key else []
    else:
        order = "<" if fmt == "binary_little_endian" else ">"
        off = start
        for name, count, props in elements:
            if not any(isinstance(t, tuple) for _, t in props):
                dt = np.dtype([(p, order + t) for p, t in props])
                need = dt.itemsize * count
                if off + need > len(data):
                    raise BadMeshFile(
                        f"truncated: the header declares {count} {name} elements "
                        f"({need} bytes), but only {len(data) - off} bytes follow"
                    )
                arr = np.frombuffer(data, dtype=dt, count=count, offset=off)
                off += need
                if name == "vertex" and all(c in dt.names for c in ("x", "y", "z")):
                    verts = np.stack([arr[c].astype(np.float64) for c in ("x", "y", "z")], -1)
                continue
            rows = []
            for r in range(count):
                row = None
                for _, typ in props:
                    if isinstance(typ, tuple):
                        cdt, idt = np.dtype(order + typ[0]), np.dtype(order + typ[1])
                        if off + cdt.itemsize > len(data):
                            raise BadMeshFile(
                                f"truncated: the file ends inside {name} {r} of {count}"
                            )
                        n = int(np.frombuffer(data, cdt, 1, off)[0])
                        off += cdt.itemsize
                        if n < 0 or off + n * idt.itemsize > len(data):
                            raise BadMeshFile(
                                f"truncated: the file ends inside {name} {r} of {count}"
                            )
                        vals = np.frombuffer(data, idt, n, off)
                        off += n * idt.itemsize
                        if row is None:
                            row = vals
                    else:
                        off += np.dtype(typ).itemsize
                        if off > len(data):
                            raise BadMeshFile(
                                f"truncated: the file ends inside {name} {r} of {count}"
                            )
                if name == "face":
                    rows.append(row)
            if name == "face":
                faces = rows
    if verts is None:
        raise BadMeshFile("no vertex element with x, y, z properties")
    if not np.all(np.isfinite(verts)):
        i = int(np.argwhere(~np.isfinite(verts))[0][0])
        raise BadMeshFile(
            f"vertex {i} is not finite ({verts[i].tolist()}); every vertex must be finite"
        )
    for i, f in enumerate(faces):
        if any(isinstance(j, float) for j in f):
            raise BadMeshFile(f"face {i}: vertex indices must be integers")
    _check_faces([[int(j) for j in f] for f in faces], len(verts), "face")
    if not faces:
        raise BadMeshFile(f"no faces ({len(verts)} vertices; a point cloud?)")


def _check_stl(data: bytes) -> None:
    if len(data) >= 84:
        n = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * n == len(data):  # binary (even when the header starts with "solid")
            rec = np.frombuffer(data, np.dtype([("nv", "<f4", 12), ("attr", "<u2")]), n, 84)
            bad = ~np.isfinite(rec["nv"][:, 3:])
            if bad.any():
                t = int(np.argwhere(bad)[0][0])
                raise BadMeshFile(
                    f"triangle {t} has a non-finite vertex; every vertex must be finite"
                )
            if n == 0:
                raise BadMeshFile("the binary STL holds 0 triangles")
            return
    head = data.lstrip()[:5].lower()
    if head == b"solid":
        text = data.decode("ascii", errors="replace")
        words = text.split()
        facets = words.count("facet")
        ends = words.count("endfacet")
        verts = [m.group(1) for m in re.finditer(r"\bvertex\b([^\n]*)", text)]
        if facets == 0:
            raise BadMeshFile("the ASCII STL holds no facets")
        if facets != ends or len(verts) != 3 * facets or "endsolid" not in words:
            raise BadMeshFile(
                f"truncated or corrupt ASCII STL: {facets} 'facet', {ends} 'endfacet', "
                f"{len(verts)} 'vertex' lines (3 per facet) and "
                + ("an" if "endsolid" in words else "no")
                + " 'endsolid'"
            )
        for i, v in enumerate(verts):
            tok = v.split()
            if len(tok) != 3:
                raise BadMeshFile(f"vertex line {i} has {len(tok)} coordinates, expected 3")
            for t in tok:
                _float(t, f"vertex line {i}")
        return
    if len(data) < 84:
        raise BadMeshFile(
            f"contains no triangle mesh: a binary STL needs at least 84 bytes (header and "
            f"triangle count), the file has {len(data)}"
        )
    n = struct.unpack_from("<I", data, 80)[0]
    raise BadMeshFile(
        f"binary STL header says {n} triangles ({84 + 50 * n} bytes), but the file has "
        f"{len(data)} bytes (truncated or corrupt)"
    )


def _check_off(data: bytes) -> None:
    lines = [ln.split("#", 1)[0].split() for ln in data.decode("ascii", "replace").splitlines()]
    toks = [t for t in lines if t]
    if not toks or not toks[0][0].upper().endswith("OFF"):
        raise BadMeshFile("not an OFF file (the first line must be 'OFF')")
    counts = toks[0][1:] or (toks[1] if len(toks) > 1 else [])
    body = toks[1:] if toks[0][1:] else toks[2:]
    try:
        nv, nf = int(counts[0]), int(counts[1])
    except (IndexError, ValueError):
        raise BadMeshFile("header: expected vertex and face counts after 'OFF'") from None
    if nv < 0 or nf < 0 or len(body) < nv + nf:
        raise BadMeshFile(
            f"truncated: the header declares {nv} vertices and {nf} faces, but only "
            f"{len(body)} lines follow"
        )
    for i in range(nv):
        if len(body[i]) < 3:
            raise BadMeshFile(f"vertex {i}: expected 3 coordinates, got {len(body[i])}")
        for t in body[i][:3]:
            _float(t, f"vertex {i}")
    faces = []
    for i in range(nf):
        row = body[nv + i]
        try:
            k = int(row[0])
            faces.append([int(t) for t in row[1 : 1 + k]])
        except ValueError:
            raise BadMeshFile(f"face {i}: vertex indices must be integers") from None
        if k < 0 or len(faces[-1]) != k:
            raise BadMeshFile(f"face {i}: declares {k} vertices, the line has {len(faces[-1])}")
    _check_faces(faces, nv, "face")
    if not faces:
        raise BadMeshFile(f"no faces ({nv} vertices; a point cloud?)")


def _check_glb(data: bytes) -> None:
    if len(data) < 20 or data[:4] != b"glTF":
        raise BadMeshFile(
            "not a GLB file (it must start with the 'glTF' magic and a 12-byte header)"
        )
    version, length = struct.unpack_from("<II", data, 4)
    if version != 2:
        raise BadMeshFile(f"glTF version {version}; only glTF 2.0 is supported")
    if length > len(data):
        raise BadMeshFile(
            f"truncated: the header declares {length} bytes, the file has {len(data)}"
        )


CHECKS = {"obj": _check_obj, "ply": _check_ply, "stl": _check_stl, "off": _check_off}
CHECKS["glb"] = _check_glb


def check_geometry(g, what: str) -> None:
    """Checks on what trimesh read (process=False): finite, in range, not all degenerate."""
    v = np.asarray(g.vertices, dtype=np.float64)
    f = np.asarray(g.faces)
    if f.ndim != 2 or f.shape[0] == 0:
        raise BadMeshFile(f"{what} has no triangles (a point cloud or a path?)")
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
        raise BadMeshFile(f"{what} has no vertices")
    if not np.all(np.isfinite(v)):
        i = int(np.argwhere(~np.isfinite(v))[0][0])
        raise BadMeshFile(
            f"{what}: vertex {i} is not finite ({v[i].tolist()}); every vertex must be finite"
        )
    if f.min() < 0 or f.max() >= v.shape[0]:
        raise BadMeshFile(
            f"{what}: face indices span {int(f.min())}..{int(f.max())} for {v.shape[0]} vertices"
        )
    big = float(np.abs(v).max())
    if big > MAX_COORDINATE:
        raise BadMeshFile(
            f"{what}: a vertex coordinate has magnitude {big:.3g}, above the limit "
            f"{MAX_COORDINATE:.0e} beyond which float64 clipping loses geometry; rescale the "
            "model (e.g. to metres or kilometres)"
        )
    tri = v[f]
    area2 = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    if not np.any(area2 > 0):
        raise BadMeshFile(f"{what}: all {f.shape[0]} triangles have zero area (nothing to draw)")
