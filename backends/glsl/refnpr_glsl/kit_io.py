"""Reading a refnpr conformance kit: index.json, case.json, glTF 2.0 binary meshes, textures.

Nothing here imports refnpr: a kit directory is self-contained (see refnpr's docs/kit.md).
Meshes are read by a small glTF 2.0 binary reader (numpy only) so that vertex and face order are
kept exactly as exported (``tri_id`` = ``first_tri_id`` + index order) and application-specific
attributes (``_ABSTRACT_NORMAL``, ...) come back by name.
"""

from __future__ import annotations

import functools
import json
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .exr import read_exr
from .png import read_png

__all__ = ["Kit", "Case", "MeshData", "read_glb", "load_kit"]

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32,
              5126: np.float32}  # fmt: skip
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


@dataclass
class MeshData:
    """One scene object's geometry, as exported (world space, float32 in the file).

    Attributes
    ----------
    name : str
    positions : (N, 3) float64
    normals : (N, 3) float64 or None
    uv : (N, 2) float64 or None
    indices : (M, 3) int64, glTF index order (= refnpr's face order)
    attributes : dict name -> (N,) or (N, C) float64
        Application-specific attributes, "_ABSTRACT_NORMAL" -> "abstract_normal".
    mesh_id, first_tri_id : int
    material : dict
        Every Material field of the object (case.json).
    """

    name: str
    positions: np.ndarray
    normals: np.ndarray | None
    uv: np.ndarray | None
    indices: np.ndarray
    attributes: dict[str, np.ndarray] = field(default_factory=dict)
    mesh_id: int = 0
    first_tri_id: int = 0
    material: dict[str, Any] = field(default_factory=dict)

    @property
    def n_faces(self) -> int:
        return int(self.indices.shape[0])


def _accessor(gltf: dict, binary: bytes, index: int, what: str) -> np.ndarray:
    acc = gltf["accessors"][index]
    view = gltf["bufferViews"][acc["bufferView"]]
    if view.get("buffer", 0) != 0:
        raise ValueError(f"{what}: only the GLB's own binary buffer is supported")
    dtype = np.dtype(_COMPONENT[acc["componentType"]])
    width = _WIDTH[acc["type"]]
    count = acc["count"]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride", 0) or dtype.itemsize * width
    if stride == dtype.itemsize * width:
        flat = np.frombuffer(binary, dtype=dtype, count=count * width, offset=start)
        arr = flat.reshape(count, width)
    else:
        rows = [
            np.frombuffer(binary, dtype=dtype, count=width, offset=start + i * stride)
            for i in range(count)
        ]
        arr = np.stack(rows) if rows else np.zeros((0, width), dtype)
    return arr[:, 0] if width == 1 else arr


def read_glb(path: str | Path) -> dict[str, np.ndarray]:
    """Read a glTF 2.0 binary: {"POSITION": (N, 3), "NORMAL", "TEXCOORD_0", "_NAME"..., "indices":
    (M, 3)} over every primitive of every mesh (concatenated, in file order), no node transforms."""
    p = Path(path)
    data = p.read_bytes()
    magic, version, _ = struct.unpack("<III", data[:12])
    if magic != 0x46546C67 or version != 2:
        raise ValueError(f"mesh: {str(path)!r} is not a glTF 2.0 binary (.glb)")
    pos, gltf, binary = 12, None, b""
    while pos < len(data):
        length, kind = struct.unpack("<II", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + length]
        if kind == 0x4E4F534A:
            gltf = json.loads(body.decode("utf-8"))
        elif kind == 0x004E4942:
            binary = body
        pos += 8 + length
    if gltf is None:
        raise ValueError(f"mesh: {str(path)!r} has no JSON chunk")
    parts: dict[str, list[np.ndarray]] = {}
    offset = 0
    for mesh in gltf.get("meshes", []):
        for prim in mesh["primitives"]:
            if prim.get("mode", 4) != 4:
                raise ValueError(f"mesh: {str(path)!r}: only TRIANGLES primitives are supported")
            attrs = {
                k: _accessor(gltf, binary, i, f"mesh {p.name} {k}")
                for k, i in prim["attributes"].items()
            }
            n = attrs["POSITION"].shape[0]
            if "indices" in prim:
                idx = _accessor(gltf, binary, prim["indices"], f"mesh {p.name} indices")
            else:
                idx = np.arange(n)
            parts.setdefault("indices", []).append(idx.astype(np.int64).reshape(-1, 3) + offset)
            for k, a in attrs.items():
                parts.setdefault(k, []).append(a)
            offset += n
    if "POSITION" not in parts:
        raise ValueError(f"mesh: {str(path)!r} has no POSITION attribute")
    return {k: np.concatenate(v) for k, v in parts.items()}


def _attribute_name(key: str) -> str:
    return key[1:].lower()


class Case:
    """One exported case: ``case.json`` and lazy access to its files.

    Attributes
    ----------
    data : dict
        case.json as parsed.
    dir : Path
        The case directory.
    """

    def __init__(self, case_json: str | Path) -> None:
        path = Path(case_json)
        if path.is_dir():
            path = path / "case.json"
        if not path.is_file():
            raise ValueError(f"case: {str(path)!r} does not exist")
        self.path = path
        self.dir = path.parent
        try:
            self.data: dict[str, Any] = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise ValueError(f"case: {str(path)!r} is not valid JSON: {exc}") from None

    def __repr__(self) -> str:
        return f"Case({self.name!r}, kind={self.kind!r}, style={self.style_name!r})"

    # -- plain keys -------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.data["name"]

    @property
    def kind(self) -> str:
        return self.data["kind"]

    @property
    def width(self) -> int:
        return int(self.data["width"])

    @property
    def height(self) -> int:
        return int(self.data["height"])

    @property
    def spp(self) -> int:
        return int(self.data["spp"])

    @property
    def n(self) -> int:
        """Samples per pixel along each axis."""
        return int(round(self.spp**0.5))

    @property
    def sample_size(self) -> tuple[int, int]:
        """(n W, n H): the sample grid (a texture size)."""
        return (self.n * self.width, self.n * self.height)

    @property
    def style(self) -> dict[str, Any] | None:
        return self.data.get("style")

    @property
    def style_name(self) -> str | None:
        s = self.style
        return None if s is None else s["name"]

    @property
    def params(self) -> dict[str, Any]:
        s = self.style
        return {} if s is None else dict(s.get("params", {}))

    @property
    def channels(self) -> list[str]:
        return list(self.data.get("channels", []))

    @property
    def raster_options(self) -> dict[str, Any]:
        return dict(self.data.get("raster_options") or {})

    @property
    def camera(self) -> dict[str, Any]:
        return self.data["camera"]

    def view_matrix(self) -> np.ndarray:
        """(4, 4) float64, row-major as exported."""
        return np.asarray(self.camera["view_matrix"], dtype=np.float64)

    def projection_matrix(self) -> np.ndarray:
        """(4, 4) float64, row-major as exported (aspect W / H)."""
        return np.asarray(self.camera["projection_matrix"], dtype=np.float64)

    @property
    def eye(self) -> np.ndarray:
        return np.asarray(self.camera["eye"], dtype=np.float64)

    @property
    def background(self) -> np.ndarray:
        return np.asarray(self.data.get("background", [0, 0, 0, 0]), dtype=np.float64)

    @property
    def ambient(self) -> np.ndarray:
        return np.asarray(self.data.get("ambient", [0, 0, 0]), dtype=np.float64)

    @property
    def lights(self) -> list[dict[str, Any]]:
        return list(self.data.get("lights", []))

    @property
    def objects(self) -> list[dict[str, Any]]:
        return list(self.data.get("objects", []))

    def materials(self, key: str, default: Any = 0.0) -> np.ndarray:
        """Material field ``key`` of every object, (n_objects,) or (n_objects, C) float64."""
        return np.array(
            [np.asarray(o["material"].get(key, default), dtype=np.float64) for o in self.objects]
        )

    # -- files ------------------------------------------------------------------------------
    def file(self, relative: str) -> Path:
        """A path inside the case directory (``ValueError`` when it does not exist)."""
        p = self.dir / relative
        if not p.exists():
            raise ValueError(f"case {self.name!r}: file {relative!r} does not exist in {self.dir}")
        return p

    @functools.cached_property
    def meshes(self) -> list[MeshData]:
        """Every object's mesh, in object order (mesh_id order)."""
        out = []
        first = 0
        for k, obj in enumerate(self.objects):
            raw = read_glb(self.file(obj["mesh"]))
            f64 = {
                key: np.asarray(a, dtype=np.float64) for key, a in raw.items() if key != "indices"
            }
            # "_UV" is the exporter's verbatim copy of TEXCOORD_0 (same accessor): it is uv
            attrs = {
                _attribute_name(key): a
                for key, a in f64.items()
                if key.startswith("_") and key != "_UV"
            }
            m = MeshData(
                name=obj.get("name", f"object{k}"),
                positions=f64["POSITION"],
                normals=f64.get("NORMAL"),
                uv=f64.get("_UV", f64.get("TEXCOORD_0")),
                indices=raw["indices"],
                attributes=attrs,
                mesh_id=int(obj.get("mesh_id", k)),
                first_tri_id=int(obj.get("first_tri_id", first)),
                material=dict(obj.get("material", {})),
            )
            first = m.first_tri_id + m.n_faces
            out.append(m)
        return out

    def texture_entry(self, role: str) -> dict[str, Any]:
        textures = self.data.get("textures") or {}
        if role not in textures:
            raise KeyError(
                f"case {self.name!r}: no texture role {role!r}; roles are {sorted(textures)}"
            )
        return textures[role]

    def texture(self, role: str) -> list[np.ndarray]:
        """Every mip level of texture ``role``, level 0 first, array layout (row 0 = the file's
        first row), float32 (EXR) or uint8 (PNG)."""
        entry = self.texture_entry(role)
        files = entry.get("levels") or [entry["file"]]
        return [read_image(self.file(f)) for f in files]

    def expected_image(self) -> np.ndarray:
        """Image cases: the expected linear straight-alpha RGBA (H, W, 4) float32."""
        return read_exr(self.file(self.data["expected"]["linear"]))

    def expected_channel(self, channel: str) -> np.ndarray:
        """G-buffer cases: refnpr's array for ``channel``."""
        spec = self.data["expected"]["channels"][channel]
        return np.load(self.file(spec["file"]))


def read_image(path: str | Path) -> np.ndarray:
    """EXR -> float32, PNG -> uint8, NPY -> as stored; array layout."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".exr":
        return read_exr(p)
    if suffix == ".png":
        return read_png(p)
    if suffix == ".npy":
        return np.load(p)
    raise ValueError(f"texture: {str(path)!r}: expected an .exr, .png or .npy file")


class Kit:
    """An exported kit directory: ``index.json`` and its cases."""

    def __init__(self, kit_dir: str | Path) -> None:
        self.dir = Path(kit_dir)
        index = self.dir / "index.json"
        if not index.is_file():
            raise ValueError(f"kit: {str(index)!r} does not exist; export a kit with "
                             "`refnpr kit export DIR`")  # fmt: skip
        self.index: dict[str, Any] = json.loads(index.read_text())
        if self.index.get("format") != "refnpr-kit":
            raise ValueError(f"kit: {str(index)!r} is not a refnpr kit index (format "
                             f"{self.index.get('format')!r})")  # fmt: skip

    @property
    def names(self) -> list[str]:
        return [c["name"] for c in self.index.get("cases", [])]

    def case(self, name: str) -> Case:
        for c in self.index.get("cases", []):
            if c["name"] == name:
                return Case(self.dir / c.get("case", f"{name}/case.json"))
        raise KeyError(f"kit: no case {name!r}; cases are {self.names}")

    def cases(self, only: list[str] | None = None) -> list[Case]:
        names = self.names
        if only:
            unknown = sorted(set(only) - set(names))
            if unknown:
                raise ValueError(f"--only: unknown cases {unknown}; the kit has {names}")
            names = [n for n in names if n in set(only)]
        return [self.case(n) for n in names]


def load_kit(kit_dir: str | Path) -> Kit:
    """Open a kit directory."""
    return Kit(kit_dir)
