"""Writing a glTF document and its binary buffer as the tests need it: a .glb, or a .gltf with
the buffer as a data: URI or a file beside it."""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path


def write_gltf(doc: dict, blob: bytes, path: Path, form: str = "glb") -> Path:
    """Write ``doc`` (a glTF JSON object; its ``buffers`` are set here) with the binary buffer
    ``blob`` to ``path``: ``form`` "glb" (one GLB container), "data" (a .gltf whose buffer is a
    base64 data: URI) or "file" (a .gltf beside ``model.bin``). Returns ``path``."""
    doc = json.loads(json.dumps(doc))
    if form == "glb":
        doc["buffers"] = [{"byteLength": len(blob)}]
        js = json.dumps(doc).encode()
        js += b" " * (-len(js) % 4)
        out = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(blob))
        out += struct.pack("<I4s", len(js), b"JSON") + js
        out += struct.pack("<I4s", len(blob), b"BIN\0") + blob
        path.write_bytes(out)
    elif form == "data":
        uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
        doc["buffers"] = [{"byteLength": len(blob), "uri": uri}]
        path.write_text(json.dumps(doc))
    else:
        (path.parent / "model.bin").write_bytes(blob)
        doc["buffers"] = [{"byteLength": len(blob), "uri": "model.bin"}]
        path.write_text(json.dumps(doc))
    return path
