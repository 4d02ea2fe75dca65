"""glTF 2.0 binary (.glb) writer for one world-space triangle mesh, with numpy only.

One mesh, one primitive (mode TRIANGLES), one node without a transform, one default material
(so that loaders such as trimesh keep ``TEXCOORD_0``); vertex data float32 as refnpr has it (no
renormalized normals, no flipped uv), extra attributes as ``"_" + NAME.upper()``, indices
UNSIGNED_INT in refnpr's face order. ``_UV`` repeats ``TEXCOORD_0``, which trimesh flips on load
(``1 - v``, not exact in float): loaders return custom attributes verbatim (docs/kit.md).
"""

from __future__ import annotations

import json
import os
import re
import struct
from pathlib import Path
from typing import Any

import numpy as np

from ..image import atomic_file

__all__ = ["write_glb", "glb_attribute_name", "GLB_UV_EXACT"]

#: The custom attribute holding refnpr's uv exactly.
GLB_UV_EXACT = "_UV"
_FLOAT, _UINT = 5126, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
_NAME = re.compile(r"^[A-Za-z0-9_]+$")


def glb_attribute_name(name: str) -> str:
    """The glTF attribute of refnpr vertex attribute ``name``: ``"_" + name.upper()``."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"attribute name: expected letters, digits and _, got {name!r}")
    return "_" + name.upper()


def write_glb(
    path: str | os.PathLike,
    positions: np.ndarray,
    faces: np.ndarray,
    *,
    normals: np.ndarray | None = None,
    uv: np.ndarray | None = None,
    attributes: dict[str, np.ndarray] | None = None,
    name: str = "mesh",
    extras: dict[str, Any] | None = None,
) -> Path:
    """Write a triangle mesh as a glTF 2.0 binary file (atomic rename).

    Parameters
    ----------
    path : path
        Target ``.glb``.
    positions : (N, 3) float
        World-space vertex positions (stored as float32).
    faces : (M, 3) int
        Zero-based vertex indices (stored as UNSIGNED_INT in this order).
    normals : (N, 3) float, optional
    uv : (N, 2) float, optional
        Stored as ``TEXCOORD_0`` and as ``_UV`` (the same accessor).
    attributes : {name: (N,) or (N, C) float}, optional
        C in 1-4; stored as ``glb_attribute_name(name)``.
    name : str
        Mesh and node name.
    extras : dict, optional
        JSON data stored as the mesh's ``extras``.

    Returns
    -------
    Path
    """
    pos = np.ascontiguousarray(positions, dtype=np.float32)
    n = pos.shape[0]
    if pos.ndim != 2 or pos.shape[1] != 3 or n == 0:
        raise ValueError(f"positions: expected (N, 3) with N > 0, got {np.shape(positions)}")
    idx = np.asarray(faces)
    if idx.ndim != 2 or idx.shape[1] != 3 or idx.shape[0] == 0:
        raise ValueError(f"faces: expected (M, 3) with M > 0, got {idx.shape}")
    if idx.min() < 0 or idx.max() >= n:
        raise ValueError(f"faces: indices must lie in [0, {n - 1}], got [{idx.min()}, {idx.max()}]")
    idx = np.ascontiguousarray(idx, dtype=np.uint32)

    blobs: list[bytes] = []
    views: list[dict[str, Any]] = []
    accessors: list[dict[str, Any]] = []

    def add(arr: np.ndarray, comp: int, target: int, *, minmax: bool = False) -> int:
        offset = sum(len(b) for b in blobs)
        data = arr.tobytes()
        blobs.append(data + b"\0" * (-len(data) % 4))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data), "target": target})
        count = arr.shape[0] if comp == _FLOAT else arr.size
        acc: dict[str, Any] = {
            "bufferView": len(views) - 1,
            "componentType": comp,
            "count": int(count),
            "type": "SCALAR" if comp == _UINT else _TYPES[1 if arr.ndim == 1 else arr.shape[1]],
        }
        if minmax:
            acc["min"] = [float(v) for v in arr.min(axis=0)]
            acc["max"] = [float(v) for v in arr.max(axis=0)]
        accessors.append(acc)
        return len(accessors) - 1

    def vertex_array(key: str, value: np.ndarray, widths: tuple[int, ...]) -> np.ndarray:
        a = np.ascontiguousarray(value, dtype=np.float32)
        if a.ndim == 2 and a.shape[1] == 1:
            a = a[:, 0].copy()
        width = 1 if a.ndim == 1 else a.shape[1]
        if a.shape[0] != n or a.ndim not in (1, 2) or width not in widths:
            raise ValueError(
                f"{key}: expected {n} rows of {'/'.join(map(str, widths))} components for mesh "
                f"{name!r}, got shape {np.shape(value)}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{key}: mesh {name!r} has non-finite values")
        return a

    attrs: dict[str, int] = {"POSITION": add(pos, _FLOAT, _ARRAY_BUFFER, minmax=True)}
    if normals is not None:
        attrs["NORMAL"] = add(vertex_array("normals", normals, (3,)), _FLOAT, _ARRAY_BUFFER)
    if uv is not None:
        uv32 = vertex_array("uv", uv, (2,))
        attrs["TEXCOORD_0"] = attrs[GLB_UV_EXACT] = add(uv32, _FLOAT, _ARRAY_BUFFER)
    for key, value in (attributes or {}).items():
        gl_name = glb_attribute_name(key)
        if gl_name in attrs:
            raise ValueError(f"attributes: {key!r} maps to {gl_name!r}, which is already used")
        attrs[gl_name] = add(
            vertex_array(f"attributes[{key!r}]", value, (1, 2, 3, 4)), _FLOAT, _ARRAY_BUFFER
        )
    indices = add(idx.reshape(-1), _UINT, _ELEMENT_ARRAY_BUFFER)

    binary = b"".join(blobs)
    mesh: dict[str, Any] = {
        "name": name,
        "primitives": [{"attributes": attrs, "indices": indices, "mode": 4, "material": 0}],
    }
    if extras:
        mesh["extras"] = extras
    doc = {
        "asset": {"version": "2.0", "generator": "refnpr kit"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [mesh],
        "materials": [{"name": "default", "doubleSided": True}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(binary)
    out = struct.pack("<4sII", b"glTF", 2, total)
    out += struct.pack("<I4s", len(js), b"JSON") + js
    out += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    path = Path(path)
    with atomic_file(path, suffix=".glb") as tmp:
        tmp.write_bytes(out)
    return path
