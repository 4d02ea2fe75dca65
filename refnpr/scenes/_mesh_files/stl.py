"""Raw check of STL files: binary size against the header's count, ASCII structure."""

from __future__ import annotations

import re
import struct

import numpy as np

from .common import BadMeshFile, _float, _numbers


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
        text = data.decode("ascii", errors="replace").lower()  # keywords in any case
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
        vals = _numbers(" ".join(verts).encode())
        if vals is None or vals.size != 3 * len(verts) or not np.isfinite(vals).all():
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
