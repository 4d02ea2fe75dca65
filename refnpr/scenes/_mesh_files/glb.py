"""Raw check of the binary glTF (GLB) header."""

from __future__ import annotations

import struct

from .common import BadMeshFile


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
