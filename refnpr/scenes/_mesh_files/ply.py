"""Raw check of PLY files: header, ASCII body, binary body (both byte orders)."""

from __future__ import annotations

import re

import numpy as np

from .common import BadMeshFile, _check_faces, _check_finite, _integral, _is_count, _numbers

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "int64": "i8", "uint64": "u8", "float16": "f2",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip
_FACE_LISTS = ("vertex_indices", "vertex_index")


def _ply_header(data: bytes):
    """(format, [(element, count, [(property, dtype or (count dtype, item dtype))]], body start)."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise BadMeshFile("not a PLY file (no 'ply' ... 'end_header' header)")
    nl = data.find(b"\n", end)
    body_start = len(data) if nl < 0 else nl + 1
    fmt = None
    elements: list[tuple[str, int, list]] = []
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


def _face_list(name: str, props: list) -> int | None:
    """Which property of an element holds the face indices (by name), if this is the face one."""
    if name != "face":
        return None
    return next(
        (k for k, (p, t) in enumerate(props) if isinstance(t, tuple) and p in _FACE_LISTS), None
    )


def _ply_ascii(data: bytes, start: int, elements: list):
    """(vertices or None, face counts, face indices) of an ASCII PLY body, read as one stream
    of numbers (as trimesh reads it)."""
    body = data[start:]
    if b"comment" in body:
        body = re.sub(rb"(?m)^comment[^\n]*", b"", body)
    vals = _numbers(body)
    if vals is None:
        for tok in body.decode("ascii", "replace").split():
            try:
                float(tok)
            except ValueError:
                raise BadMeshFile(f"body: {tok[:40]!r} is not a number") from None
        raise BadMeshFile("the body does not parse as numbers")  # pragma: no cover
    del body
    verts, counts, flat, pos = None, np.zeros(0, np.int64), np.zeros(0, np.int64), 0
    for name, count, props in elements:
        left = vals.size - pos
        nlist = sum(isinstance(t, tuple) for _, t in props)
        width = len(props)
        if nlist and count:
            k, lists = 0, []  # the first row's layout: the count column of each list
            for _, typ in props:
                if pos + k >= vals.size:
                    k = left + 1  # cut inside the first row
                    break
                if isinstance(typ, tuple):
                    n = vals[pos + k]
                    if not _is_count(n):
                        raise BadMeshFile(f"{name} 0: bad list length {n!r}")
                    lists.append(k)
                    k += 1 + int(n)
                else:
                    k += 1
            width = k
        need = width * count
        if need > left and not nlist:
            raise BadMeshFile(
                f"truncated: the header declares {count} {name} elements ({need} values), but "
                f"only {left} values follow (the file was cut short?)"
            )
        block = None  # lists of different lengths (or a cut file): walk the rows
        if need <= left:
            block = vals[pos : pos + need].reshape(count, width)
            if nlist and count and not all((block[:, c] == block[0, c]).all() for c in lists):
                block = None
        pos, rows = _ply_ascii_rows(vals, pos, name, count, props, block, width)
        if name == "vertex":
            names = [p for p, _ in props]
            if all(c in names for c in "xyz"):
                verts = np.stack([rows[names.index(c)] for c in "xyz"], -1)
        key = _face_list(name, props)
        if key is not None:
            counts, flat = rows[key]
    return verts, counts, flat


def _ply_ascii_rows(vals, pos, name, count, props, block, width):
    """Columns of one element: an array per scalar property, (counts, flat items) per list."""
    out: list = []
    if block is not None:
        k = 0
        for _, typ in props:
            if isinstance(typ, tuple):
                n = int(block[0, k]) if count else 0
                out.append((np.full(count, n, np.int64), block[:, k + 1 : k + 1 + n].ravel()))
                k += 1 + n
            else:
                out.append(block[:, k])
                k += 1
        return pos + width * count, out
    cols: list[list] = [[] for _ in props]
    lv = vals[pos:].tolist()
    k = 0
    for r in range(count):
        for j, (_, typ) in enumerate(props):
            if k >= len(lv):
                raise BadMeshFile(
                    f"truncated: the file ends inside {name} {r} of {count} (cut short?)"
                )
            if isinstance(typ, tuple):
                n = lv[k]
                if not _is_count(n):
                    raise BadMeshFile(f"{name} {r}: bad list length {n!r}")
                if k + 1 + int(n) > len(lv):
                    raise BadMeshFile(
                        f"truncated: the file ends inside {name} {r} of {count} (cut short?)"
                    )
                cols[j].append(lv[k + 1 : k + 1 + int(n)])
                k += 1 + int(n)
            else:
                cols[j].append(lv[k])
                k += 1
    for j, (_, typ) in enumerate(props):
        if isinstance(typ, tuple):
            c = np.array([len(x) for x in cols[j]], np.int64)
            out.append((c, np.array([v for x in cols[j] for v in x], np.float64)))
        else:
            out.append(np.array(cols[j], np.float64))
    return pos + k, out


def _ply_binary(data: bytes, start: int, elements: list, order: str):
    """(vertices or None, face counts, face indices) of a binary PLY body."""
    verts, counts, flat, off = None, np.zeros(0, np.int64), np.zeros(0, np.int64), start
    for name, count, props in elements:
        key = _face_list(name, props)
        fields, k = [], off  # the first row's layout decides the structured dtype
        for j, (_, typ) in enumerate(props):
            if isinstance(typ, tuple):
                cdt = np.dtype(order + typ[0])
                if k + cdt.itemsize > len(data):
                    raise BadMeshFile(f"truncated: the file ends inside {name} 0 of {count}")
                n = int(np.frombuffer(data, cdt, 1, k)[0]) if count else 0
                if n < 0:
                    raise BadMeshFile(f"{name} 0: negative list length {n}")
                fields += [(f"n{j}", cdt), (f"p{j}", order + typ[1], (n,))]
                k += cdt.itemsize + n * np.dtype(typ[1]).itemsize
            else:
                fields.append((f"p{j}", order + typ))
                k += np.dtype(typ).itemsize
        dt = np.dtype(fields)
        need = dt.itemsize * count
        arr = None
        if off + need <= len(data):
            arr = np.frombuffer(data, dt, count, off)
            lens = [arr[f"n{j}"] for j, (_, t) in enumerate(props) if isinstance(t, tuple)]
            if all((c == c[0]).all() for c in lens if c.size):
                off += need
            else:
                arr = None  # lists of different lengths
        elif not any(isinstance(t, tuple) for _, t in props):
            raise BadMeshFile(
                f"truncated: the header declares {count} {name} elements ({need} bytes), but "
                f"only {len(data) - off} bytes follow"
            )
        if arr is None:
            off, fc, ff = _ply_binary_rows(data, off, name, count, props, order, key)
        elif key is not None:
            items = arr[f"p{key}"]
            fc = np.full(count, items.shape[1] if items.ndim == 2 else 0, np.int64)
            ff = items.reshape(-1)
        if name == "vertex" and arr is not None:
            names = [p for p, _ in props]
            if all(c in names for c in "xyz"):
                verts = np.stack([arr[f"p{names.index(c)}"].astype(np.float64) for c in "xyz"], -1)
        if key is not None:
            counts, flat = fc, ff
    if flat.dtype.kind == "u" and flat.size and flat.max() > np.iinfo(np.int64).max:
        flat = np.minimum(flat, np.iinfo(np.int64).max)
    return verts, counts, flat if flat.dtype.kind == "f" else flat.astype(np.int64, copy=False)


def _ply_binary_rows(data, off, name, count, props, order, key):
    """Walk an element's rows one by one (lists of different lengths): (end, counts, flat)."""
    fc, ff = [], []
    for r in range(count):
        for j, (_, typ) in enumerate(props):
            if isinstance(typ, tuple):
                cdt, idt = np.dtype(order + typ[0]), np.dtype(order + typ[1])
                n = (
                    int(np.frombuffer(data, cdt, 1, off)[0])
                    if off + cdt.itemsize <= len(data)
                    else -1
                )
                off += cdt.itemsize
                if n < 0 or off + n * idt.itemsize > len(data):
                    raise BadMeshFile(f"truncated: the file ends inside {name} {r} of {count}")
                if j == key:
                    fc.append(n)
                    ff.append(np.frombuffer(data, idt, n, off))
                off += n * idt.itemsize
            else:
                off += np.dtype(typ).itemsize
                if off > len(data):
                    raise BadMeshFile(f"truncated: the file ends inside {name} {r} of {count}")
    flat = np.concatenate(ff) if ff else np.zeros(0, np.int64)
    return off, np.array(fc, np.int64), flat


def _check_ply(data: bytes) -> None:
    fmt, elements, start = _ply_header(data)
    if fmt == "ascii":
        verts, counts, flat = _ply_ascii(data, start, elements)
    else:
        order = "<" if fmt == "binary_little_endian" else ">"
        verts, counts, flat = _ply_binary(data, start, elements, order)
    if flat.dtype.kind == "f":
        flat = _integral(counts, flat)
    if verts is None:
        raise BadMeshFile("no vertex element with x, y, z properties")
    _check_finite(verts, lambda i: f"vertex {i}")
    _check_faces(counts, flat, len(verts), lambda i: f"face {i}")
    if not counts.size:
        raise BadMeshFile(f"no faces ({len(verts)} vertices; a point cloud?)")
