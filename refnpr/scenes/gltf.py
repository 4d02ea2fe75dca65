"""glTF 2.0 scenes (``.gltf`` with its buffers, ``.glb``) read as refnpr scenes.

The reader parses the glTF JSON, the GLB container, accessors, buffer views and buffers itself
(``data:`` URIs and files next to the ``.gltf``), so that node hierarchies with TRS or matrix
transforms are exact. What it reads (docs/scenes.md has the full table):

- every mesh primitive of the default scene's node tree as one :class:`SceneObject` with its
  node's world matrix: triangles (indexed or not), strips and fans (converted to triangles);
  ``POSITION``, ``NORMAL`` (flat normals when absent, as the glTF spec requires) and
  ``TEXCOORD_0`` (verbatim: glTF's uv origin is the image's first row, as refnpr's textures);
  accessors dense or sparse (a base, from a buffer view or zeros, with substitutions);
- materials: ``baseColorFactor`` as the diffuse colour, ambient ``AMBIENT_FRACTION`` of it;
  ``baseColorTexture`` as the material's colour map (``Material.color_texture``, multiplying
  the base colour in the styles that shade with it) and its texture (``Material.texture``, the
  image the threshold and halftone styles may sample): an image file beside the scene (its
  path) or an embedded PNG or JPEG (a ``data:`` URI, or a buffer view with a ``mimeType``, as
  in a ``.glb``) as a :class:`~refnpr.texture.EmbeddedImage`, decoded when a style samples it;
- cameras: perspective (``yfov``, ``znear``, ``zfar``), the first camera node of the scene by
  default, another by ``camera=`` (camera or node name, or node index);
- lights of ``KHR_lights_punctual``: directional and point, spot as point; colour x intensity;
  a scene without lights gets a headlight (a directional light from the camera);
- node animations (translation, rotation, scale; LINEAR, STEP, CUBICSPLINE) sampled exactly at
  every frame and stored as refnpr tracks (see :func:`load_gltf`).

glTF is right-handed with +Y up, metres, cameras looking down their node's -Z with +Y up: the
same conventions as refnpr's world and :class:`~refnpr.raster.Camera`, so coordinates are taken
as they are. Everything else (PBR inputs other than the base colour, skins, morph targets,
texture transforms) is ignored and named once in a :class:`GltfWarning`.

The file is untrusted input: every failure is a :class:`GltfError` (a ``ValueError``) that names
the file and the glTF path of the bad field (``model.gltf: accessors[3].count: ...``); sizes are
checked before anything is allocated (an embedded image's from its PNG or JPEG header, before it
is decoded).
"""

from __future__ import annotations

import base64
import binascii
import json
import math
import os
import struct
import sys
import urllib.parse
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._reading import printable, read_regular, short_repr
from ..formulas._validate import BEYOND_FLOAT_RANGE
from ..raster import Camera, Mesh
from ..raster.mesh import MAX_COORDINATE, coordinate_limit_message
from ..texture.embedded import EmbeddedImage, probe_image
from ._mesh_files import zero_area_message
from .animation import MAX_FRAMES, Animation, Track
from .scene import Light, Material, Scene, SceneObject
from .toml_format import SceneFileError
from .tracks import Keyframe, quaternion_from_matrix, quaternion_matrix, slerp

__all__ = [
    "AMBIENT_FRACTION",
    "GLTF_EXTENSIONS",
    "GltfError",
    "GltfWarning",
    "MAX_ANIMATION_KEYS",
    "MAX_ANIMATION_WORK",
    "MAX_ZERO_ACCESSOR_BYTES",
    "MAX_FILE_BYTES",
    "MAX_NODES",
    "MAX_PLACED_TRIANGLES",
    "MAX_PLACED_VERTICES",
    "camera_headlight",
    "headlight_track",
    "load_gltf",
]

#: File suffixes read as glTF scenes (case-insensitive).
GLTF_EXTENSIONS = (".gltf", ".glb")
#: The largest ``.glb``, ``.gltf`` or buffer file read (bytes); also the largest buffer
#: (``byteLength``) and the most bytes all the buffers of a file hold together.
MAX_FILE_BYTES = 1 << 31
#: The largest JSON part (bytes).
MAX_JSON_BYTES = 64 << 20
#: The most keys (frames x animated values) an animation may produce.
MAX_ANIMATION_KEYS = 2_000_000
#: The most bytes an accessor without a bufferView (all zeros by the spec) may expand to.
MAX_ZERO_ACCESSOR_BYTES = 64 << 20
#: The most nodes a file may have (each costs a matrix and its work in every animation frame).
MAX_NODES = 100_000
#: The most triangles, and vertices, the objects of a scene may have together: a mesh that
#: several nodes place counts once per node (each placement is an object with its own world
#: mesh). Checked before any object is built.
MAX_PLACED_TRIANGLES = 20_000_000
MAX_PLACED_VERTICES = 3 * MAX_PLACED_TRIANGLES
#: The most frames x (nodes + animation channels) an animation may evaluate (its work).
MAX_ANIMATION_WORK = 20_000_000
#: The material's ambient colour m_a is this fraction of the base colour (so that a base colour
#: of 0.8 grey gives refnpr's default material, ambient 0.15 and diffuse 0.8).
AMBIENT_FRACTION = 0.15 / 0.8

_GLB_MAGIC, _CHUNK_JSON, _CHUNK_BIN = b"glTF", 0x4E4F534A, 0x004E4942
_COMPONENTS = {  # componentType -> (numpy dtype, name)
    5120: (np.dtype("<i1"), "BYTE"),
    5121: (np.dtype("<u1"), "UNSIGNED_BYTE"),
    5122: (np.dtype("<i2"), "SHORT"),
    5123: (np.dtype("<u2"), "UNSIGNED_SHORT"),
    5125: (np.dtype("<u4"), "UNSIGNED_INT"),
    5126: (np.dtype("<f4"), "FLOAT"),
}
_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_MODES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP", 4: "TRIANGLES"}
_MODES.update({5: "TRIANGLE_STRIP", 6: "TRIANGLE_FAN"})
_FLOAT = 5126
_UNORM = (5121, 5123)  # normalized unsigned types glTF allows for uv and rotations
_SNORM = (5120, 5122)
_INTERPOLATIONS = ("LINEAR", "STEP", "CUBICSPLINE")
_PATH_WIDTH = {"translation": 3, "rotation": 4, "scale": 3}
_MATERIAL_READ = {"name", "pbrMetallicRoughness", "extras"}
_PBR_READ = {"baseColorFactor", "baseColorTexture", "extras"}
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
#: How much of an image file beside the scene is read to find its size (a JPEG's frame header
#: follows its metadata segments).
_IMAGE_HEAD_BYTES = 4 << 20


class GltfError(SceneFileError):
    """A glTF file that cannot be read as a scene; the message starts with the file and the glTF
    path of the bad field."""


class GltfWarning(UserWarning):
    """Something in a glTF file that refnpr reads differently or not at all (ignored inputs, a
    spot light read as a point light, the headlight added to a scene without lights)."""


def _num(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _finite(v) -> bool:
    """Whether ``v`` is a JSON number that is a finite float64 (an integer beyond the float
    range, about 1.8e308, is not)."""
    if not _num(v):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _beyond_float(v) -> str:
    """A note for a number that ``_finite`` refuses: an integer beyond the float range."""
    return f" ({BEYOND_FLOAT_RANGE})" if _int(v) else ""


#: glTF's largest integer (JSON integers must lie in [-(2^53 - 1), 2^53 - 1]).
_MAX_JSON_INT = (1 << 53) - 1


@dataclass
class _Node:
    index: int
    name: str
    local: np.ndarray  # (4, 4)
    trs: tuple[np.ndarray, np.ndarray, np.ndarray] | None  # None: given as a matrix
    parent: int | None


class _Reader:
    """One glTF document: validated access to its fields, accessors and buffers."""

    def __init__(self, path: Path, label: str) -> None:
        self.path, self.label, self.base = path, label, path.parent
        self.ignored: list[str] = []  # glTF inputs not read, named once in a warning
        self._buffers: dict[int, memoryview] = {}
        self._buffer_bytes = 0  # the byteLength of the buffers read so far, together
        self._glb_bin: bytes | None = None
        # images read, by index: file paths or EmbeddedImages (shared by the materials)
        self.images: dict[int, str | EmbeddedImage] = {}
        self.doc = self._load()

    # -- errors and fields ---------------------------------------------------------------------
    def fail(self, where: str, message: str) -> GltfError:
        return GltfError(f"{self.label}: {where}: {message}")

    def ignore(self, what: str) -> None:
        """Name ``what`` (it may quote the file's own keys) in the warning of inputs not read,
        once, with its control and format characters escaped (no terminal escapes)."""
        what = printable(what)
        if what not in self.ignored:
            self.ignored.append(what)

    def array(self, key: str) -> list:
        value = self.doc.get(key, [])
        if not isinstance(value, list):
            raise self.fail(key, f"expected a JSON array, got {type(value).__name__}")
        return value

    def item(self, key: str, index: Any, where: str) -> dict:
        """``doc[key][index]`` as an object, with a clear error for a bad or missing index."""
        items = self.array(key)
        if not _int(index) or not 0 <= index < len(items):
            raise self.fail(
                where,
                f"{short_repr(index)} is not an index of {key} (the file has {len(items)}: valid "
                f"indices are 0 to {len(items) - 1})"
                if items
                else f"refers to {key}[{short_repr(index)}], but the file has no {key}",
            )
        value = items[index]
        if not isinstance(value, dict):
            raise self.fail(
                f"{key}[{index}]", f"expected a JSON object, got {type(value).__name__}"
            )
        return value

    def get_int(self, obj: dict, key: str, where: str, default=None, lo=0, hi=None) -> int:
        value = obj.get(key, default)
        if value is None:
            raise self.fail(f"{where}.{key}", "missing (an integer is required)")
        top = _MAX_JSON_INT if hi is None else hi
        if not _int(value) or value < lo or value > top:
            rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
            if hi is None and _int(value) and value > top:
                rng += " and at most 2^53 - 1 (glTF's largest integer)"
            raise self.fail(f"{where}.{key}", f"expected an integer {rng}, got {short_repr(value)}")
        return value

    def get_numbers(self, obj: dict, key: str, where: str, n: int, default) -> np.ndarray:
        value = obj.get(key, default)
        if not isinstance(value, list) or len(value) != n or not all(map(_finite, value)):
            bad = (
                next((x for x in value if not _finite(x)), None)
                if isinstance(value, list)
                else None
            )
            raise self.fail(
                f"{where}.{key}",
                f"expected {n} finite numbers, got {short_repr(value)}{_beyond_float(bad)}",
            )
        return np.array(value, dtype=np.float64)

    def get_real(self, obj: dict, key: str, where: str, default=None, *, positive=False) -> float:
        value = obj.get(key, default)
        if value is None:
            raise self.fail(f"{where}.{key}", "missing (a number is required)")
        if not _finite(value) or (positive and value <= 0):
            what = "a positive finite number" if positive else "a finite number"
            raise self.fail(
                f"{where}.{key}", f"expected {what}, got {short_repr(value)}{_beyond_float(value)}"
            )
        return float(value)

    def name_of(self, obj: dict, where: str, default: str) -> str:
        name = obj.get("name")
        if name is None or name == "":
            return default
        if not isinstance(name, str):
            raise self.fail(f"{where}.name", f"expected a string, got {name!r}")
        return name.replace('"', "'")

    # -- the file --------------------------------------------------------------------------------
    def _load(self) -> dict:
        try:  # a regular file only: a FIFO would block, a device (/dev/zero) never end
            real = self.path.resolve()
            raw = read_regular(real, what=f"{self.label}: the file", max_bytes=MAX_FILE_BYTES)
        except (OSError, RuntimeError) as exc:  # resolve(): a symbolic link loop
            raise GltfError(f"{self.label}: cannot read the file ({exc})") from None
        except ValueError as exc:
            raise GltfError(str(exc)) from None
        if raw[:4] == _GLB_MAGIC:
            text = self._glb_chunks(raw)
        elif self.path.suffix.lower() == ".glb":
            raise GltfError(
                f"{self.label}: not a binary glTF file (it does not start with the magic bytes "
                f"'glTF' but with {raw[:4]!r}); re-export the scene as .glb"
            )
        else:
            text = raw
        if len(text) > MAX_JSON_BYTES:
            raise GltfError(
                f"{self.label}: the JSON part has {len(text)} bytes, more than the "
                f"{MAX_JSON_BYTES} refnpr reads; keep geometry in buffers"
            )
        try:
            doc = json.loads(text.decode("utf-8"))
        except UnicodeDecodeError as exc:
            raise GltfError(
                f"{self.label}: the glTF JSON is not UTF-8 (byte {exc.start}); re-export the scene"
            ) from None
        except json.JSONDecodeError as exc:
            raise GltfError(f"{self.label}: invalid glTF JSON: {exc}") from None
        except ValueError as exc:  # an integer with more digits than Python converts
            raise GltfError(
                f"{self.label}: invalid glTF JSON: {str(exc).split(';')[0]} (glTF integers have "
                "at most 16 digits); repair or re-export the file"
            ) from None
        except RecursionError:
            raise GltfError(
                f"{self.label}: invalid glTF JSON: arrays or objects nested too deeply"
            ) from None
        if not isinstance(doc, dict):
            raise GltfError(
                f"{self.label}: the glTF JSON must be an object, got a {type(doc).__name__}"
            )
        asset = doc.get("asset")
        if not isinstance(asset, dict) or not isinstance(asset.get("version"), str):
            raise GltfError(f"{self.label}: asset.version: missing; this is not a glTF 2.0 file")
        version = asset["version"]
        if version.split(".")[0] != "2":
            raise GltfError(
                f"{self.label}: asset.version: {version!r}; refnpr reads glTF 2.0 (convert "
                "glTF 1.0 files with a current exporter)"
            )
        required = doc.get("extensionsRequired", [])
        if not isinstance(required, list):
            raise GltfError(f"{self.label}: extensionsRequired: expected an array")
        unknown = [e for e in required if e != "KHR_lights_punctual"]
        if unknown:
            raise GltfError(
                f"{self.label}: extensionsRequired: {unknown[0]!r} is required by the file but "
                "refnpr does not implement it (it reads KHR_lights_punctual); re-export without it"
            )
        return doc

    def _glb_chunks(self, raw: bytes) -> bytes:
        if len(raw) < 20:
            raise GltfError(f"{self.label}: GLB header: the file is truncated ({len(raw)} bytes)")
        _, version, length = struct.unpack_from("<4sII", raw, 0)
        if version != 2:
            raise GltfError(f"{self.label}: GLB header: version {version}; refnpr reads GLB 2")
        if length > len(raw):
            raise GltfError(
                f"{self.label}: GLB header: declares {length} bytes but the file has {len(raw)} "
                "(truncated?)"
            )
        chunks, offset = [], 12
        while offset + 8 <= length:
            size, kind = struct.unpack_from("<II", raw, offset)
            if offset + 8 + size > length:
                raise GltfError(
                    f"{self.label}: GLB chunk {len(chunks)}: declares {size} bytes, beyond the "
                    f"end of the file ({length} bytes)"
                )
            chunks.append((kind, raw[offset + 8 : offset + 8 + size]))
            offset += 8 + size + (-size % 4)
        if not chunks or chunks[0][0] != _CHUNK_JSON:
            raise GltfError(f"{self.label}: GLB chunk 0: the first chunk must be the JSON chunk")
        if len(chunks) > 1 and chunks[1][0] == _CHUNK_BIN:
            self._glb_bin = chunks[1][1]
        return chunks[0][1]

    def buffer(self, index: int, where: str) -> memoryview:
        if index in self._buffers:
            return self._buffers[index]
        buf = self.item("buffers", index, where)
        bw = f"buffers[{index}]"
        length = self.get_int(buf, "byteLength", bw, lo=1)
        if length > MAX_FILE_BYTES - self._buffer_bytes:  # checked before anything is read
            others = (
                f" (with the {self._buffer_bytes} bytes of the buffers read before it, "
                f"{self._buffer_bytes + length})"
                if self._buffer_bytes
                else ""
            )
            raise self.fail(
                f"{bw}.byteLength",
                f"{length} bytes{others}, more than the {MAX_FILE_BYTES} bytes refnpr reads of "
                "a file's buffers; split the scene or reduce its geometry",
            )
        uri = buf.get("uri")
        if uri is None:
            if index != 0 or self._glb_bin is None:
                raise self.fail(
                    f"{bw}.uri",
                    "missing, and only buffer 0 of a .glb may omit it (it is the GLB's BIN "
                    "chunk)"
                    + ("" if self._glb_bin is not None else "; this file has no BIN chunk"),
                )
            data = self._glb_bin
        elif not isinstance(uri, str):
            raise self.fail(f"{bw}.uri", f"expected a string, got {uri!r}")
        elif uri.startswith("data:"):
            data = self.data_uri(uri, f"{bw}.uri")  # at least byteLength bytes: the first used
        else:
            data = self._external(uri, length, f"{bw}.uri")
        if len(data) < length:
            raise self.fail(
                f"{bw}.byteLength",
                f"declares {length} bytes but the buffer holds {len(data)} (truncated?)",
            )
        view = memoryview(data)[:length]
        self._buffers[index] = view
        self._buffer_bytes += length
        return view

    def data_uri(self, uri: str, where: str) -> bytes:
        """The bytes of a base64 ``data:`` URI (a buffer's or an image's). Its size is bounded
        by the JSON that holds it (at most MAX_JSON_BYTES); a buffer reads the first
        byteLength of them, as glTF allows a resource longer than its byteLength."""
        head, sep, payload = uri.partition(",")
        if not sep or not head.endswith(";base64"):
            raise self.fail(where, "a data: URI must be base64 (data:...;base64,...)")
        try:
            return base64.b64decode(payload, validate=True)
        except (binascii.Error, ValueError) as exc:
            raise self.fail(where, f"invalid base64 data ({exc})") from None

    def resolve_uri(self, uri: str, where: str) -> Path:
        """A relative URI as a path inside the file's directory (absolute, remote or ``..`` URIs
        that leave it are refused)."""
        parsed = urllib.parse.urlsplit(uri)
        if parsed.scheme or parsed.netloc:
            raise self.fail(
                where,
                f"{uri!r} is not a relative file reference; refnpr reads only buffers and "
                "images beside the .gltf file (or embedded as data: URIs)",
            )
        rel = urllib.parse.unquote(parsed.path)
        if "\x00" in rel:
            raise self.fail(where, f"{uri!r} holds a NUL character; give a plain file name")
        if not rel or Path(rel).is_absolute() or rel.startswith(("/", "\\")):
            raise self.fail(
                where, f"{uri!r} is an absolute path; give a path relative to the .gltf file"
            )
        try:
            base = self.base.resolve()
            full = (self.base / rel).resolve()
        except (OSError, RuntimeError) as exc:  # resolve(): a symbolic link loop
            raise self.fail(where, f"{uri!r} cannot be resolved ({exc})") from None
        if not full.is_relative_to(base):
            raise self.fail(
                where,
                f"{uri!r} points outside the directory of the .gltf file ({str(base)!r}); "
                "refnpr reads only files in that directory or below it",
            )
        return full

    def _external(self, uri: str, length: int, where: str) -> bytes:
        """The first ``length`` bytes of the buffer file ``uri`` (a regular file beside the
        .gltf of at most MAX_FILE_BYTES, holding at least ``length`` bytes)."""
        full = self.resolve_uri(uri, where)
        if not full.exists():
            raise self.fail(
                where, f"buffer file {uri!r} not found beside the .gltf ({str(full)!r})"
            )
        try:
            data = read_regular(
                full, what=f"buffer file {uri!r}", max_bytes=MAX_FILE_BYTES, head=length
            )
        except ValueError as exc:
            raise self.fail(where, str(exc)) from None
        if len(data) < length:
            raise self.fail(
                where,
                f"buffer file {uri!r} has {len(data)} bytes, but byteLength declares {length}",
            )
        return data

    def view(self, index: Any, where: str) -> tuple[memoryview, dict, str]:
        """Buffer view ``index`` (referenced at ``where``): its bytes (bounds-checked against its
        buffer), its JSON object and its glTF path (``bufferViews[i]``)."""
        view = self.item("bufferViews", index, where)
        vw = f"bufferViews[{index}]"
        buf = self.buffer(self.get_int(view, "buffer", vw), f"{vw}.buffer")
        v_off = self.get_int(view, "byteOffset", vw, default=0)
        v_len = self.get_int(view, "byteLength", vw, lo=1)
        if v_off + v_len > len(buf):
            raise self.fail(
                vw,
                f"byteOffset {v_off} + byteLength {v_len} = {v_off + v_len} lies beyond the end "
                f"of its buffer ({len(buf)} bytes)",
            )
        return buf[v_off : v_off + v_len], view, vw

    def packed_view(self, index: Any, where: str, what: str) -> tuple[memoryview, str]:
        """Buffer view ``index`` that holds ``what`` (sparse indices or values, an image), which
        glTF stores tightly packed: a ``byteStride`` is refused."""
        data, view, vw = self.view(index, where)
        if "byteStride" in view:
            raise self.fail(
                where,
                f"{vw} has a byteStride ({view['byteStride']!r}); {what} must be tightly "
                "packed (byteStride is for vertex attributes only): remove it",
            )
        return data, vw

    # -- accessors -------------------------------------------------------------------------------
    def accessor(
        self,
        index: Any,
        where: str,
        types: tuple[str, ...],
        components: tuple[int, ...],
        *,
        count: int | None = None,
        indices: bool = False,
    ) -> np.ndarray:
        """Accessor ``index`` (referenced at ``where``) as an (count, width) float64 array
        (integer accessors as int64, normalized ones scaled to [0, 1] or [-1, 1]); a sparse
        accessor with its substitutions applied. ``indices``: it holds vertex indices, which
        glTF never normalizes."""
        acc = self.item("accessors", index, where)
        aw = f"accessors[{index}]"
        ctype = acc.get("componentType")
        if not _int(ctype) or ctype not in _COMPONENTS:
            raise self.fail(
                f"{aw}.componentType",
                f"{short_repr(ctype)} is not a glTF component type (an integer: "
                f"{', '.join(map(str, _COMPONENTS))})",
            )
        if ctype not in components:
            names = ", ".join(_COMPONENTS[c][1] for c in components)
            raise self.fail(
                f"{aw}.componentType",
                f"{_COMPONENTS[ctype][1]} cannot be used at {where}; expected {names}",
            )
        kind = acc.get("type")
        if not isinstance(kind, str) or kind not in types:
            raise self.fail(
                f"{aw}.type", f"{short_repr(kind)} at {where}; expected {' or '.join(types)}"
            )
        n = self.get_int(acc, "count", aw, lo=1)
        if count is not None and n != count:
            raise self.fail(
                f"{aw}.count", f"{n} at {where}, which needs {count} (one per vertex/key)"
            )
        normalized = acc.get("normalized", False)
        if not isinstance(normalized, bool) or (normalized and ctype == _FLOAT):
            raise self.fail(
                f"{aw}.normalized", f"{short_repr(normalized)} is not valid for this accessor"
            )
        if normalized and indices:
            raise self.fail(
                f"{aw}.normalized",
                f"true for the indices of {where}; glTF indices are plain unsigned integers "
                "(never normalized): remove `normalized`",
            )
        dtype = _COMPONENTS[ctype][0]
        width = _WIDTHS[kind]
        elem = dtype.itemsize * width
        if "bufferView" not in acc:  # all zeros (spec): no file data bounds it, so a cap does
            if n * width * 8 > MAX_ZERO_ACCESSOR_BYTES:  # int64 / float64 as read below
                raise self.fail(
                    f"{aw}.count",
                    f"{n} elements without a bufferView (all zeros) would take "
                    f"{n * width * 8} bytes, more than the {MAX_ZERO_ACCESSOR_BYTES} refnpr "
                    "allows; store the data in a bufferView",
                )
            raw = np.zeros((n, width), dtype=dtype)
        else:
            data, view, vw = self.view(acc["bufferView"], f"{aw}.bufferView")
            stride = elem
            if "byteStride" in view:
                stride = self.get_int(view, "byteStride", vw, lo=4, hi=252)
                if stride < elem:
                    raise self.fail(
                        f"{vw}.byteStride",
                        f"{stride} is smaller than one element of accessors[{index}] ({elem} "
                        "bytes)",
                    )
            a_off = self._offset(acc, aw, dtype.itemsize)
            end = a_off + stride * (n - 1) + elem
            if end > len(data):
                raise self.fail(
                    f"{aw}.count",
                    f"{n} elements of {elem} bytes (stride {stride}, byteOffset {a_off}) need "
                    f"{end} bytes, beyond the end of {vw} ({len(data)} bytes)",
                )
            raw = np.ndarray(
                (n, width),
                dtype=dtype,
                buffer=data,
                offset=a_off,
                strides=(stride, dtype.itemsize),
            )
        if "sparse" in acc:
            raw = self._sparse(acc["sparse"], f"{aw}.sparse", raw)
        if ctype == _FLOAT:
            out = raw.astype(np.float64)
            bad = ~np.isfinite(out)
            if bad.any():
                i = int(np.argwhere(bad)[0][0])
                raise self.fail(
                    aw, f"element {i} at {where} is not finite ({out[i].tolist()}); repair the file"
                )
            return out
        if not normalized:
            return raw.astype(np.int64)
        scale = float(np.iinfo(dtype).max)
        return np.maximum(raw.astype(np.float64) / scale, -1.0)

    def _offset(self, obj: dict, where: str, size: int) -> int:
        """``obj.byteOffset`` (default 0), a multiple of the component ``size``."""
        offset = self.get_int(obj, "byteOffset", where, default=0)
        if offset % size:
            raise self.fail(
                f"{where}.byteOffset", f"{offset} is not a multiple of the component size {size}"
            )
        return offset

    def _sparse(self, sparse: Any, sw: str, base: np.ndarray) -> np.ndarray:
        """``base`` (count, width) with the substitutions of a sparse accessor (glTF 2.0 sec.
        3.6.2.3): ``sparse.count`` element indices, strictly increasing, and their values, each
        tightly packed in a buffer view."""
        n, width = base.shape
        if not isinstance(sparse, dict):
            raise self.fail(sw, f"expected a JSON object, got {type(sparse).__name__}")
        k = self.get_int(sparse, "count", sw, lo=1)
        if k > n:
            raise self.fail(
                f"{sw}.count",
                f"{k} substitutions for an accessor of {n} elements; expected 1 to {n}",
            )
        parts = {}
        for key in ("indices", "values"):
            part = sparse.get(key)
            if not isinstance(part, dict):
                raise self.fail(
                    f"{sw}.{key}",
                    "missing (a sparse accessor needs `indices` and `values` objects)"
                    if part is None
                    else f"expected a JSON object, got {type(part).__name__}",
                )
            parts[key] = part
        iw, vw = f"{sw}.indices", f"{sw}.values"
        ictype = parts["indices"].get("componentType")
        if not _int(ictype) or ictype not in (5121, 5123, 5125):
            raise self.fail(
                f"{iw}.componentType",
                f"{short_repr(ictype)}; expected 5121 (UNSIGNED_BYTE), 5123 (UNSIGNED_SHORT) or "
                "5125 (UNSIGNED_INT)",
            )
        idx = self._packed(parts["indices"], iw, "sparse indices", _COMPONENTS[ictype][0], k, 1)
        idx = idx[:, 0].astype(np.int64)
        values = self._packed(parts["values"], vw, "sparse values", base.dtype, k, width)
        if k > 1 and np.any(np.diff(idx) <= 0):
            j = int(np.argmax(np.diff(idx) <= 0)) + 1
            raise self.fail(
                iw,
                f"index {int(idx[j])} at position {j} is not greater than the one before it "
                f"({int(idx[j - 1])}); sparse indices must be strictly increasing",
            )
        if idx[-1] >= n:
            j = int(np.argmax(idx >= n))
            raise self.fail(
                iw,
                f"index {int(idx[j])} at position {j} is out of range for the accessor's {n} "
                f"elements (0 to {n - 1})",
            )
        out = np.array(base)  # a copy: the base may be a view of the file's buffer
        out[idx] = values
        return out

    def _packed(
        self, part: dict, where: str, what: str, dtype: np.dtype, k: int, width: int
    ) -> np.ndarray:
        """(k, width) elements of ``dtype`` tightly packed at ``part.byteOffset`` of the buffer
        view ``part.bufferView``."""
        if "bufferView" not in part:
            raise self.fail(f"{where}.bufferView", "missing (an index of bufferViews is required)")
        data, vname = self.packed_view(part["bufferView"], f"{where}.bufferView", what)
        offset = self._offset(part, where, dtype.itemsize)
        need = offset + k * width * dtype.itemsize
        if need > len(data):
            raise self.fail(
                f"{where}.byteOffset",
                f"{k} elements of {width * dtype.itemsize} bytes at byteOffset {offset} need "
                f"{need} bytes, beyond the end of {vname} ({len(data)} bytes)",
            )
        return np.ndarray((k, width), dtype=dtype, buffer=data, offset=offset)


def _trs_matrix(t: np.ndarray, q: np.ndarray, s: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = quaternion_matrix(q) @ np.diag(s)
    m[:3, 3] = t
    return m


def _unit_quaternion(r: _Reader, q: np.ndarray, where: str) -> np.ndarray:
    norm = float(np.linalg.norm(q))
    if not abs(norm - 1.0) <= 1e-3:
        raise r.fail(
            where, f"{q.tolist()} has length {norm:.6g}; glTF rotations are unit quaternions"
        )
    return q / norm


def _nodes(r: _Reader) -> list[_Node]:
    """Every node with its local matrix and parent; cycles and shared children refused."""
    raw = r.array("nodes")
    if len(raw) > MAX_NODES:
        raise r.fail(
            "nodes",
            f"the file has {len(raw)} nodes, more than the {MAX_NODES} refnpr reads; merge "
            "nodes (e.g. join static meshes) or split the scene",
        )
    nodes: list[_Node] = []
    for i, node in enumerate(raw):
        w = f"nodes[{i}]"
        if not isinstance(node, dict):
            raise r.fail(w, f"expected a JSON object, got {type(node).__name__}")
        name = r.name_of(node, w, f"node{i}")
        if "matrix" in node:
            if any(k in node for k in ("translation", "rotation", "scale")):
                raise r.fail(w, "has both `matrix` and translation/rotation/scale; give one")
            m = r.get_numbers(node, "matrix", w, 16, None).reshape(4, 4).T  # column-major
            if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
                raise r.fail(
                    f"{w}.matrix",
                    f"the last row is {m[3].tolist()}, expected (0, 0, 0, 1): glTF node matrices "
                    "are affine",
                )
            nodes.append(_Node(i, name, m, None, None))
        else:
            t = r.get_numbers(node, "translation", w, 3, [0.0, 0.0, 0.0])
            q = _unit_quaternion(
                r, r.get_numbers(node, "rotation", w, 4, [0.0, 0.0, 0.0, 1.0]), f"{w}.rotation"
            )
            s = r.get_numbers(node, "scale", w, 3, [1.0, 1.0, 1.0])
            nodes.append(_Node(i, name, _trs_matrix(t, q, s), (t, q, s), None))
    for i, node in enumerate(raw):
        children = node.get("children", [])
        if not isinstance(children, list):
            raise r.fail(
                f"nodes[{i}].children", f"expected an array of node indices, got {children!r}"
            )
        for j, c in enumerate(children):
            where = f"nodes[{i}].children[{j}]"
            if not _int(c) or not 0 <= c < len(nodes):
                raise r.fail(where, f"{c!r} is not a node index (0 to {len(nodes) - 1})")
            if c == i:
                raise r.fail(where, f"node {i} lists itself as a child (a cycle)")
            if nodes[c].parent is not None:
                raise r.fail(
                    where,
                    f"node {c} is already a child of nodes[{nodes[c].parent}]; a glTF node has "
                    "at most one parent (the node graph must be a forest)",
                )
            nodes[c].parent = i
    state = [0] * len(nodes)  # 0 unseen, 1 on the current path, 2 done (reaches a root)
    for start in range(len(nodes)):
        path, i = [], start
        while i is not None and state[i] == 0:
            state[i] = 1
            path.append(i)
            i = nodes[i].parent
        if i is not None and state[i] == 1:
            raise r.fail(
                f"nodes[{i}].children",
                "the node graph has a cycle (" + " -> ".join(f"nodes[{k}]" for k in path) + ")",
            )
        for k in path:
            state[k] = 2
    return nodes


def _scene_roots(r: _Reader, nodes: list[_Node]) -> list[int]:
    scenes = r.array("scenes")
    if not scenes:
        return [n.index for n in nodes if n.parent is None]
    index = r.doc.get("scene", 0)
    scene = r.item("scenes", index, "scene")
    roots = scene.get("nodes", [])
    if not isinstance(roots, list):
        raise r.fail(f"scenes[{index}].nodes", f"expected an array of node indices, got {roots!r}")
    seen: dict[int, int] = {}  # node -> its position in the list
    for j, n in enumerate(roots):
        where = f"scenes[{index}].nodes[{j}]"
        if not _int(n) or not 0 <= n < len(nodes):
            raise r.fail(where, f"{short_repr(n)} is not a node index (0 to {len(nodes) - 1})")
        if nodes[n].parent is not None:
            raise r.fail(
                where, f"node {n} is not a root node (its parent is nodes[{nodes[n].parent}])"
            )
        if n in seen:
            raise r.fail(
                where,
                f"node {n} is listed twice (also at scenes[{index}].nodes[{seen[n]}]); a glTF "
                "scene lists each root node once: remove the repetition",
            )
        seen[n] = j
    return list(roots)


def _traverse(r: _Reader, nodes: list[_Node], roots: list[int]) -> list[int]:
    """Node indices of the scene in depth-first order (children in their listed order)."""
    order, stack = [], list(reversed(roots))
    while stack:
        i = stack.pop()
        order.append(i)
        children = r.doc["nodes"][i].get("children", [])
        stack.extend(reversed(children))
    return order


def _world(nodes: list[_Node], order: list[int], local=None) -> dict[int, np.ndarray]:
    """World matrices by node; an overflow leaves non-finite entries, which the objects, the
    camera and the lights that use them report (:func:`_placement_error`, :func:`_axis`)."""
    local = local or {}
    world: dict[int, np.ndarray] = {}
    with np.errstate(over="ignore", invalid="ignore"):
        for i in order:  # parents come before children in depth-first order
            m = local.get(i, nodes[i].local)
            p = nodes[i].parent
            world[i] = m if p is None else world[p] @ m
    return world


def _chain(nodes: list[_Node], i: int) -> list[int]:
    """Node ``i`` and its ancestors, nearest first."""
    out = [i]
    while nodes[out[-1]].parent is not None:
        out.append(nodes[out[-1]].parent)
    return out


def _field(nodes: list[_Node], j: int, trs_key: str) -> str:
    """The glTF path of node ``j``'s ``trs_key`` (``matrix`` for a node given as a matrix)."""
    return f"nodes[{j}].{trs_key if nodes[j].trs is not None else 'matrix'}"


def _zero_scale_field(nodes: list[_Node], i: int, local=None) -> str:
    """The glTF path of the scale (or matrix) that makes node ``i``'s world matrix singular: the
    nearest node on its path to the root whose own linear part is singular."""
    local = local or {}
    for j in _chain(nodes, i):
        a = local.get(j, nodes[j].local)[:3, :3]
        if np.any(np.linalg.norm(a, axis=0) == 0) or _singular(a):
            return _field(nodes, j, "scale")
    return f"nodes[{i}]"


def _large_field(nodes: list[_Node], i: int) -> str:
    """The glTF path that most likely carries node ``i``'s geometry beyond the coordinate
    limit: a translation beyond it, else the largest scale on the node's path to the root."""
    chain = _chain(nodes, i)
    for j in chain:
        if np.abs(nodes[j].local[:3, 3]).max() > MAX_COORDINATE:
            return _field(nodes, j, "translation")
    j = max(chain, key=lambda k: float(np.abs(nodes[k].local[:3, :3]).max()))
    if np.abs(nodes[j].local[:3, :3]).max() > 1.0:
        return _field(nodes, j, "scale")
    return f"nodes[{i}]"


def _nonzero_fix(field: str) -> str:
    """How to repair the zero scale at ``field`` (a node's ``scale`` or ``matrix``)."""
    if field.endswith(".scale"):
        return f"make every component of {field} non-zero"
    if field.endswith(".matrix"):
        return f"make {field} invertible (a non-zero scale on every axis)"
    return "give the node and its parents non-zero scales"


def _singular(a: np.ndarray) -> bool:
    """Whether a 3x3 linear part has a zero (or underflowing) determinant: a zero scale."""
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        return bool(abs(np.linalg.det(a)) < 1e-300)


def _axis(r: _Reader, nodes: list[_Node], i: int, world: np.ndarray, k: int, what: str, **at):
    """Column ``k`` of node ``i``'s world matrix, unit length: the axis that gives ``what``
    (a camera's view or up direction, a light's direction); an error naming the node's zero
    scale (or its overflowing transform) where it has no length. ``at``: ``local`` (the node
    matrices of an animation frame) and ``t`` (its time)."""
    col = world[:3, k]
    with np.errstate(over="ignore", invalid="ignore"):
        n = float(np.linalg.norm(col))
    if n > 0 and math.isfinite(n) and np.all(np.isfinite(col)):
        return col / n
    when = "" if at.get("t") is None else f" at time {at['t']:g} s"
    if n == 0:
        field = _zero_scale_field(nodes, i, at.get("local"))
        raise r.fail(
            field,
            f"{what} of nodes[{i}] {nodes[i].name!r} has a zero scale{when}: the node's world "
            f"matrix maps its {'XYZ'[k]} axis to zero, so it has no direction; "
            + _nonzero_fix(field)
            + " (a camera's or light's scale does not change what it does)",
        )
    raise r.fail(
        _large_field(nodes, i),
        f"{what} of nodes[{i}] {nodes[i].name!r}{when}: its world matrix (the node's transform "
        "composed with its parents') is not finite (it overflows float64); give the nodes "
        "scales and translations of a reasonable size",
    )


def _placement_error(
    r: _Reader, nodes: list[_Node], i: int, mesh: Mesh, m: np.ndarray, what: str
) -> GltfError | None:
    """The error for an object whose node's world matrix ``m`` places ``mesh`` beyond the
    coordinate limit (or overflows), naming the field that carries it there; None if it fits."""
    subject = f"{what}, placed by the world transform of nodes[{i}] {nodes[i].name!r},"
    msg = _reach_message(subject, mesh, m)
    return None if msg is None else r.fail(_large_field(nodes, i), msg)


def _reach_message(subject: str, mesh: Mesh, m: np.ndarray) -> str | None:
    """The refusal of ``mesh`` placed by the world matrix ``m`` beyond the coordinate limit
    (or beyond float64), naming ``subject``; None if every vertex fits."""
    with np.errstate(over="ignore", invalid="ignore"):
        pos = mesh.positions @ m[:3, :3].T + m[:3, 3]
    if np.all(np.isfinite(pos)):
        return coordinate_limit_message(subject, pos)
    return (
        f"{subject} has vertex coordinates beyond float64 (the node's transform composed "
        "with its parents' overflows); rescale the model (e.g. to metres or kilometres) "
        f"so that every |coordinate| is <= {MAX_COORDINATE:.0e}"
    )


def _triangles(r: _Reader, mode: int, idx: np.ndarray, where: str) -> np.ndarray:
    n = idx.shape[0]
    if mode == 4:
        if n % 3:
            raise r.fail(where, f"{n} indices (or vertices) is not a multiple of 3 for TRIANGLES")
        return idx.reshape(-1, 3)
    if n < 3:
        raise r.fail(where, f"{n} indices (or vertices) make no triangle ({_MODES[mode]})")
    k = np.arange(n - 2)
    if mode == 5:  # strip: {v_i, v_{i+1+i%2}, v_{i+2-i%2}} (glTF 2.0 sec. 3.7.2.1)
        odd = k % 2
        return np.stack([idx[k], idx[k + 1 + odd], idx[k + 2 - odd]], axis=1)
    return np.stack([idx[k + 1], idx[k + 2], np.full(n - 2, idx[0])], axis=1)  # fan


def _flat(positions, faces, uv):
    """Unshared vertices with flat face normals (glTF: no NORMAL means flat shading)."""
    p = positions[faces].reshape(-1, 3)
    e = np.cross(p[1::3] - p[0::3], p[2::3] - p[0::3])
    length = np.linalg.norm(e, axis=1, keepdims=True)
    n = np.divide(e, length, out=np.zeros_like(e), where=length > 0)
    normals = np.repeat(n, 3, axis=0)
    uv = None if uv is None else uv[faces].reshape(-1, 2)
    return p, np.arange(p.shape[0], dtype=np.int64).reshape(-1, 3), normals, uv


def _primitive_mesh(r: _Reader, mi: int, pi: int, prim: Any, name: str, node_w: str) -> Mesh:
    w = f"meshes[{mi}].primitives[{pi}]"
    if not isinstance(prim, dict):
        raise r.fail(w, f"expected a JSON object, got {type(prim).__name__}")
    mode = r.get_int(prim, "mode", w, default=4, hi=6)  # the modes of _MODES
    if mode < 4:
        raise r.fail(
            f"{w}.mode",
            f"{mode} ({_MODES[mode]}) in {node_w} {name!r}: refnpr renders triangles only "
            "(modes 4, 5, 6); remove the points/lines primitive or export it as a mesh",
        )
    attrs = prim.get("attributes")
    if not isinstance(attrs, dict) or "POSITION" not in attrs:
        raise r.fail(f"{w}.attributes", "missing POSITION (every primitive needs positions)")
    pos = r.accessor(attrs["POSITION"], f"{w}.attributes.POSITION", ("VEC3",), (_FLOAT,))
    nv = pos.shape[0]
    normals = uv = None
    if "NORMAL" in attrs:
        normals = r.accessor(
            attrs["NORMAL"], f"{w}.attributes.NORMAL", ("VEC3",), (_FLOAT,), count=nv
        )
    if "_UV" in attrs:  # refnpr's kit stores its uv exactly here (docs/kit.md)
        uv = r.accessor(attrs["_UV"], f"{w}.attributes._UV", ("VEC2",), (_FLOAT,), count=nv)
    elif "TEXCOORD_0" in attrs:
        uv = r.accessor(
            attrs["TEXCOORD_0"],
            f"{w}.attributes.TEXCOORD_0",
            ("VEC2",),
            (_FLOAT, *_UNORM),
            count=nv,
        )
        if uv.dtype != np.float64:
            raise r.fail(
                f"{w}.attributes.TEXCOORD_0", "integer texture coordinates must be normalized"
            )
    for key in attrs:
        if key not in ("POSITION", "NORMAL", "TEXCOORD_0", "_UV"):
            r.ignore(f"vertex attribute {key}")
    if "targets" in prim:
        r.ignore("morph targets")
    if "indices" in prim:
        idx = r.accessor(
            prim["indices"], f"{w}.indices", ("SCALAR",), (5121, 5123, 5125), indices=True
        )[:, 0]
        if idx.size and (idx.max() >= nv):
            bad = int(np.argmax(idx >= nv))
            raise r.fail(
                f"accessors[{prim['indices']}]",
                f"index {int(idx[bad])} at position {bad} (the indices of {w}) is out of range "
                f"for {nv} vertices",
            )
    else:
        idx = np.arange(nv, dtype=np.int64)
    faces = _triangles(
        r, mode, idx, f"{w}.indices" if "indices" in prim else f"{w}.attributes.POSITION"
    )
    if normals is None:
        pos, faces, normals, uv = _flat(pos, faces, uv)
    try:
        mesh = Mesh(pos, faces, normals, uv, name=name)
    except (TypeError, ValueError) as exc:
        raise r.fail(w, str(exc)) from None
    flat = zero_area_message(f"{w} (the mesh of {node_w} {name!r})", mesh.positions, mesh.faces)
    if flat is not None:
        raise GltfError(
            f"{r.label}: {flat}; remove the primitive, or re-export the file from its source"
        )
    return mesh


def _material(r: _Reader, index: Any, where: str, cache: dict) -> Material:
    if index is None:  # refnpr's default material (glTF's default white, scaled by 0.8)
        return Material()
    if _int(index) and index in cache:  # 0.0 == 0: only an integer index may hit the cache
        return cache[index]
    mat = r.item("materials", index, where)
    mw = f"materials[{index}]"
    for key in mat:
        if key not in _MATERIAL_READ:
            r.ignore(f"material {key}")
    pbr = mat.get("pbrMetallicRoughness", {})
    if not isinstance(pbr, dict):
        raise r.fail(f"{mw}.pbrMetallicRoughness", "expected a JSON object")
    for key in pbr:
        if key not in _PBR_READ:
            r.ignore(f"pbrMetallicRoughness.{key}")
    base = r.get_numbers(pbr, "baseColorFactor", f"{mw}.pbrMetallicRoughness", 4, [1.0] * 4)
    if np.any(base < 0.0) or np.any(base > 1.0):
        raise r.fail(
            f"{mw}.pbrMetallicRoughness.baseColorFactor", f"{base.tolist()} must lie in [0, 1]"
        )
    texture = _base_texture(
        r, pbr.get("baseColorTexture"), f"{mw}.pbrMetallicRoughness.baseColorTexture"
    )
    rgb = base[:3]
    out = Material(
        ambient=tuple(AMBIENT_FRACTION * rgb),
        diffuse=tuple(rgb),
        texture=texture,
        color_texture=texture,
    )
    cache[index] = out
    return out


def _base_texture(r: _Reader, info: Any, where: str) -> str | EmbeddedImage | None:
    """The image of ``baseColorTexture``: a file beside the scene (its path), an embedded image
    (an :class:`~refnpr.texture.EmbeddedImage`), or None (with a note)."""
    if info is None:
        return None
    if not isinstance(info, dict):
        raise r.fail(where, "expected a JSON object (a textureInfo)")
    if info.get("texCoord", 0) != 0:
        r.ignore("baseColorTexture with texCoord other than 0")
        return None
    tex = r.item("textures", info.get("index"), f"{where}.index")
    ti = info["index"]
    ext = info.get("extensions")
    for key in ext if isinstance(ext, dict) else ():
        r.ignore(f"baseColorTexture extension {key}")  # KHR_texture_transform: uv as stored
    if "sampler" in tex:  # refnpr samples GL_REPEAT, linear, trilinear between levels
        sampler = r.item("samplers", tex["sampler"], f"textures[{ti}].sampler")
        defaults = {"wrapS": 10497, "wrapT": 10497, "magFilter": 9729, "minFilter": 9987}
        if any(sampler.get(k, v) != v for k, v in defaults.items()):
            r.ignore("texture sampler wrap and filter modes (refnpr samples GL_REPEAT, trilinear)")
    if "source" not in tex:
        r.ignore("textures without a source image")
        return None
    return _image(r, tex["source"], f"textures[{ti}].source")


def _image(r: _Reader, src: Any, where: str) -> str | EmbeddedImage:
    """``images[src]``: the path of its file beside the scene, or its embedded PNG or JPEG (a
    ``data:`` URI, or a buffer view with a ``mimeType``) as an EmbeddedImage."""
    image = r.item("images", src, where)
    if src in r.images:
        return r.images[src]
    iw = f"images[{src}]"
    uri, vi = image.get("uri"), image.get("bufferView")
    mime = image.get("mimeType")
    if (uri is None) == (vi is None):
        raise r.fail(
            iw,
            "has both `uri` and `bufferView`; give one"
            if uri is not None
            else "has neither `uri` nor `bufferView` (an image needs one)",
        )
    if mime is not None and not isinstance(mime, str):
        raise r.fail(f"{iw}.mimeType", f"expected a string, got {mime!r}")
    if vi is not None:
        if mime is None:
            raise r.fail(
                f"{iw}.mimeType",
                "missing: an image stored in a bufferView needs a mimeType ('image/png' or "
                "'image/jpeg')",
            )
        data, _ = r.packed_view(vi, f"{iw}.bufferView", "image data")
        found = _embedded(r, data, mime, f"{iw}.bufferView", f"{r.path.name}#{iw}")
    elif not isinstance(uri, str):
        raise r.fail(f"{iw}.uri", f"expected a string, got {uri!r}")
    elif uri.startswith("data:"):
        media = uri[5:].partition(",")[0].partition(";")[0]
        if media in ("", "application/octet-stream"):  # untyped: the data's signature tells
            media = None
        if mime is not None and media is not None and media != mime:
            raise r.fail(f"{iw}.uri", f"a data: URI of type {media!r}, but mimeType is {mime!r}")
        data = r.data_uri(uri, f"{iw}.uri")
        found = _embedded(r, data, media or mime, f"{iw}.uri", f"{r.path.name}#{iw}")
    else:
        path = r.resolve_uri(uri, f"{iw}.uri")
        if path.suffix.lower() not in _IMAGE_SUFFIXES:
            raise r.fail(f"{iw}.uri", f"{uri!r} is not a PNG or JPEG image (glTF's image types)")
        if not path.is_file():
            raise r.fail(f"{iw}.uri", f"image file {uri!r} not found beside the .gltf")
        with open(path, "rb") as f:  # its size from its header, as an embedded image's
            head = f.read(_IMAGE_HEAD_BYTES)
        try:
            probe_image(head, mime)
        except ValueError as exc:
            raise r.fail(f"{iw}.uri", f"{uri!r}: {exc}") from None
        found = str(path)
    r.images[src] = found
    return found


def _embedded(r: _Reader, data: Any, mime: str | None, where: str, name: str) -> EmbeddedImage:
    """The bytes of an embedded image, its type and size checked from its header."""
    data = bytes(data)
    try:
        probe_image(data, mime)
    except ValueError as exc:
        raise r.fail(where, str(exc)) from None
    return EmbeddedImage(name, data, mime)


def _lights(r: _Reader) -> list[dict]:
    ext = r.doc.get("extensions", {})
    if not isinstance(ext, dict):
        raise r.fail("extensions", "expected a JSON object")
    for key in ext:
        if key != "KHR_lights_punctual":
            r.ignore(f"extension {key}")
    lp = ext.get("KHR_lights_punctual", {})
    if not isinstance(lp, dict) or not isinstance(lp.get("lights", []), list):
        raise r.fail("extensions.KHR_lights_punctual.lights", "expected an array of lights")
    out = []
    for i, light in enumerate(lp.get("lights", [])):
        w = f"extensions.KHR_lights_punctual.lights[{i}]"
        if not isinstance(light, dict):
            raise r.fail(w, "expected a JSON object")
        kind = light.get("type")
        if kind not in ("directional", "point", "spot"):
            raise r.fail(f"{w}.type", f"{kind!r}; expected 'directional', 'point' or 'spot'")
        color = r.get_numbers(light, "color", w, 3, [1.0, 1.0, 1.0])
        intensity = r.get_real(light, "intensity", w, 1.0)
        if np.any(color < 0) or intensity < 0:
            raise r.fail(w, "color and intensity must be >= 0")
        with np.errstate(over="ignore"):
            product = color * intensity
        if not np.all(np.isfinite(product)):
            raise r.fail(
                w,
                f"color {color.tolist()} x intensity {intensity:g} (the light's colour) is "
                "beyond float64; give a smaller intensity or colour",
            )
        if "range" in light:
            r.ignore("light range (refnpr lights do not fall off)")
        out.append(
            {
                "kind": kind,
                "color": tuple(product),
                "name": r.name_of(light, w, f"light{i}"),
            }
        )
    return out


@dataclass
class _Placed:
    """What a node places: objects (node, primitive), its camera, its light."""

    node: int
    kind: str  # "object", "camera", "light"
    index: int  # camera / light index; primitive index for objects


def _camera_from(
    r: _Reader, nodes: list[_Node], i: int, world: np.ndarray, params: dict, distance: float, **at
) -> Camera:
    """The camera of node ``i`` (world matrix ``world``); ``at`` as :func:`_axis` takes it."""
    eye = world[:3, 3]
    forward = -_axis(r, nodes, i, world, 2, "the camera", **at)
    up = _axis(r, nodes, i, world, 1, "the camera", **at)
    try:
        return Camera.look_at(
            eye, eye + distance * forward, up, params["fov_y"], params["near"], params["far"]
        )
    except ValueError as exc:
        when = "" if at.get("t") is None else f" at time {at['t']:g} s"
        raise r.fail(f"nodes[{i}]", f"camera{when}: {exc}") from None


def _light_from(r: _Reader, nodes: list[_Node], pl: _Placed, world: np.ndarray, info, **at):
    """The direction (directional: the node's +Z, the light shining along -Z) or position of
    the light ``pl`` places; ``at`` as :func:`_axis` takes it."""
    if info["kind"] == "directional":
        what = f"directional light {info['name']!r}"
        return {"direction": tuple(_axis(r, nodes, pl.node, world, 2, what, **at))}
    position = world[:3, 3]
    if not np.all(np.isfinite(position)):
        raise r.fail(
            _large_field(nodes, pl.node),
            f"{info['kind']} light {info['name']!r} of nodes[{pl.node}]: its world position is "
            "not finite (the node's transform composed with its parents' overflows float64)",
        )
    return {"position": tuple(position)}


def camera_headlight(camera: Camera) -> Light:
    """The light of a scene whose file has none: white, directional, from the camera (towards
    ``camera.eye - camera.target``)."""
    return Light(direction=tuple(np.asarray(camera.eye) - np.asarray(camera.target)))


def load_gltf(
    path: str | os.PathLike,
    *,
    camera: str | int | None = None,
    animation: str | int | None = None,
    fps: float = 24.0,
    headlight: bool = True,
) -> Scene:
    """Read a glTF 2.0 file (``.gltf`` or ``.glb``) as a :class:`Scene`.

    Parameters
    ----------
    path : str or PathLike
        The file; a ``.gltf``'s buffers and images are read from its directory (or ``data:``
        URIs), never from outside it.
    camera : str or int, optional
        The camera to use: a camera's or a camera node's name, or a node index. Default: the
        first node with a camera in the scene's depth-first order; a scene without cameras gets
        one that frames its bounds from +Z (with a :class:`GltfWarning`).
    animation : str or int, optional
        The animation to play (name or index); default the first. Nodes it moves (and their
        descendants, cameras and lights among them) become tracks of :attr:`Scene.animation`
        with one key per frame, each the glTF sampler's exact value at ``frame / fps``;
        between frames the tracks interpolate linearly (slerp for rotations).
    fps : float
        Frames per second of the animation (> 0).
    headlight : bool
        Whether a file without lights gets a headlight (:func:`camera_headlight` of the camera,
        following its animation), with a :class:`GltfWarning`. False: the scene has no lights
        then (a TOML scene over the file adds the headlight of its own camera).

    Returns
    -------
    Scene
        Objects named after their nodes (``node[p]`` for primitive p of a node with several),
        the camera, the lights (a headlight when the file has none), ``style = {}``.

    Raises
    ------
    GltfError
        A ``ValueError`` naming the file and the glTF path of the bad field.
    FileNotFoundError
        If ``path`` does not exist.
    """
    given = os.fsdecode(path) if isinstance(path, (str, bytes, os.PathLike)) else None
    if given is None:
        raise TypeError(f"path: expected a file path (str or Path), got {type(path).__name__}")
    if not isinstance(headlight, bool):
        raise TypeError(f"headlight: expected True or False, got {headlight!r}")
    p = Path(given)
    if not p.exists():
        raise FileNotFoundError(f"scene: glTF file {given!r} does not exist")
    if p.is_dir():
        raise GltfError(f"scene: {given!r} is a directory; expected a .gltf or .glb file")
    if not _finite(fps) or fps <= 0:
        raise ValueError(
            f"fps: expected a positive number of frames per second, got {short_repr(fps)}"
        )
    r = _Reader(p, given)
    for key in ("skins",):
        if r.array(key):
            r.ignore("skins (meshes are drawn in their bind pose)")
    nodes = _nodes(r)
    roots = _scene_roots(r, nodes)
    order = _traverse(r, nodes, roots)
    world = _world(nodes, order)
    light_infos = _lights(r)

    placed: list[_Placed] = []
    meshes: dict[tuple[int, int], Mesh] = {}
    materials: dict = {}
    obj_names: dict[tuple[int, int], str] = {}
    obj_materials: dict[tuple[int, int], Material] = {}
    used_names: set[str] = set()
    for i in order:
        node = r.doc["nodes"][i]
        w = f"nodes[{i}]"
        for key in node:
            if key in ("skin", "weights"):
                r.ignore(f"node {key}")
        if "mesh" in node:
            mi = node["mesh"]
            mesh = r.item("meshes", mi, f"{w}.mesh")
            prims = mesh.get("primitives")
            if not isinstance(prims, list) or not prims:
                raise r.fail(f"meshes[{mi}].primitives", "expected a non-empty array of primitives")
            base = (
                nodes[i].name if "name" in node else r.name_of(mesh, f"meshes[{mi}]", nodes[i].name)
            )
            for pi, prim in enumerate(prims):
                name = base if len(prims) == 1 else f"{base}[{pi}]"
                while name in used_names:  # another node may be named "box (nodes[i])" too
                    name = f"{name} (nodes[{i}])"
                used_names.add(name)
                if (mi, pi) not in meshes:
                    meshes[(mi, pi)] = _primitive_mesh(r, mi, pi, prim, name, w)
                obj_names[(i, pi)] = name
                obj_materials[(i, pi)] = _material(
                    r, prim.get("material"), f"meshes[{mi}].primitives[{pi}].material", materials
                )
                placed.append(_Placed(i, "object", pi))
        if "camera" in node:
            r.item("cameras", node["camera"], f"{w}.camera")
            placed.append(_Placed(i, "camera", node["camera"]))
        ext = node.get("extensions", {})
        if isinstance(ext, dict) and "KHR_lights_punctual" in ext:
            li = (
                ext["KHR_lights_punctual"].get("light")
                if isinstance(ext["KHR_lights_punctual"], dict)
                else None
            )
            if not _int(li) or not 0 <= li < len(light_infos):
                raise r.fail(
                    f"{w}.extensions.KHR_lights_punctual.light",
                    f"{li!r} is not a light index (the file has {len(light_infos)} lights)",
                )
            placed.append(_Placed(i, "light", li))

    objects_at = [pl for pl in placed if pl.kind == "object"]
    if not objects_at:
        raise GltfError(
            f"{given}: the scene has no mesh nodes (nothing to render); a scene needs at least "
            "one triangle mesh"
        )

    # a colour map is sampled at uv, which the rasterizer interpolates for every mesh of a
    # frame: where some material has one, a primitive without TEXCOORD_0 whose own material has
    # none gets uv (0, 0) (never sampled); one whose material has a map is refused
    mapped = any(mat.color_texture is not None for mat in obj_materials.values())

    def instance(pl: _Placed, m: np.ndarray) -> SceneObject:
        mi = r.doc["nodes"][pl.node]["mesh"]
        mesh = meshes[(mi, pl.index)]
        name = obj_names[(pl.node, pl.index)]
        material = obj_materials[(pl.node, pl.index)]
        uv = mesh.uv
        if uv is None and material.color_texture is not None:
            raise r.fail(
                f"meshes[{mi}].primitives[{pl.index}].attributes",
                "the material has a baseColorTexture but the primitive has no TEXCOORD_0",
            )
        if uv is None and mapped:
            uv = np.zeros((mesh.positions.shape[0], 2))
        if mesh.name != name or uv is not mesh.uv:
            mesh = Mesh(mesh.positions, mesh.faces, mesh.normals, uv, mesh.attributes, name)
        try:
            obj = SceneObject(mesh, m, material, name)
            obj.world_mesh()  # memoized: the bounds below use it
            return obj
        except (TypeError, ValueError) as exc:
            what = f"object {name!r} (meshes[{mi}].primitives[{pl.index}])"
            placement = _placement_error(r, nodes, pl.node, mesh, m, what)
            raise placement or r.fail(f"nodes[{pl.node}]", f"object {name!r}: {exc}") from None

    hidden = [pl for pl in objects_at if _singular(world[pl.node][:3, :3])]
    objects_at = [pl for pl in objects_at if pl not in hidden]
    if hidden:
        _warn(f"{given}: {len(hidden)} object(s) with a zero scale are not drawn")
    if not objects_at:
        raise GltfError(
            f"{given}: every mesh node has a zero scale; nothing to render (refnpr leaves an "
            "object of zero scale out of the scene; one that an animation scales up needs a tiny "
            "non-zero rest scale instead, e.g. 1e-6)"
        )
    _check_placed(r, [meshes[(r.doc["nodes"][pl.node]["mesh"], pl.index)] for pl in objects_at])
    objects = [instance(pl, world[pl.node]) for pl in objects_at]
    bounds_lo = np.min([o.world_mesh().positions.min(axis=0) for o in objects], axis=0)
    bounds_hi = np.max([o.world_mesh().positions.max(axis=0) for o in objects], axis=0)

    cam_at = _choose_camera(r, nodes, placed, camera)
    cam_params, cam_distance = None, 1.0
    if cam_at is not None:
        cam_params = _perspective(r, cam_at.index, nodes[cam_at.node].name)
        eye = world[cam_at.node][:3, 3]
        centre = (bounds_lo + bounds_hi) / 2
        fwd = -_axis(r, nodes, cam_at.node, world[cam_at.node], 2, "the camera")
        along = float((centre - eye) @ fwd)
        cam_distance = along if along > cam_params["near"] else 1.0
        if cam_params["far"] is None:
            corners = (
                np.array(np.meshgrid(*zip(bounds_lo, bounds_hi, strict=True))).reshape(3, -1).T
            )
            reach = float(np.max(np.linalg.norm(corners - eye, axis=1)))
            cam_params["far"] = max(2.0 * reach, 100.0 * cam_params["near"])
        cam = _camera_from(r, nodes, cam_at.node, world[cam_at.node], cam_params, cam_distance)
    else:
        cam = _framing_camera(bounds_lo, bounds_hi)
        _warn(f"{given}: the file has no camera; refnpr frames the scene's bounds from +Z")

    lights_at = [pl for pl in placed if pl.kind == "light"]
    lights = []
    for pl in lights_at:
        info = light_infos[pl.index]
        if info["kind"] == "spot":
            _warn(f"{given}: spot light {info['name']!r} is read as a point light (no cone)")
        kind = "directional" if info["kind"] == "directional" else "point"
        placed_at = _light_from(r, nodes, pl, world[pl.node], info)
        with _located(r, f"extensions.KHR_lights_punctual.lights[{pl.index}]"):
            lights.append(Light(kind=kind, color=info["color"], **placed_at))
    headlight = headlight and not lights
    if headlight:
        lights.append(camera_headlight(cam))
        defined = (
            f"KHR_lights_punctual defines {len(light_infos)} light(s) ("
            + ", ".join(repr(info["name"]) for info in light_infos[:5])
            + (", ..." if len(light_infos) > 5 else "")
            + ") but no node of the scene places one (a node's extensions.KHR_lights_punctual"
            ".light)"
            if light_infos
            else "no KHR_lights_punctual lights"
        )
        _warn(
            f"{given}: {defined}; refnpr adds a headlight (a white directional light from the "
            "camera)"
        )
    scene = Scene(
        objects=tuple(objects),
        camera=cam,
        lights=tuple(lights),
        name=p.stem,
    )
    anim = _animation(
        r,
        nodes,
        order,
        animation,
        fps,
        objects_at=objects_at,
        hidden=hidden,
        names=[o.name for o in objects],
        meshes=[o.mesh for o in objects],
        cam_at=cam_at,
        cam_params=cam_params,
        cam_distance=cam_distance,
        lights_at=lights_at,
        light_infos=light_infos,
        headlight=headlight,
    )
    if r.ignored:
        _warn(f"{given}: not read (ignored): {', '.join(r.ignored)}")
    if anim is None:
        return scene
    try:
        return Scene(**{**_fields(scene), "animation": anim})
    except ValueError as exc:
        raise GltfError(f"{given}: animations: {exc}") from None


def _check_placed(r: _Reader, placed: list[Mesh]) -> None:
    """Refuse objects (the meshes their nodes place, one per object) with more than
    MAX_PLACED_TRIANGLES triangles or MAX_PLACED_VERTICES vertices together: each is an object
    of its own (its world mesh, its share of every render), so a small file that places one
    mesh many times would exhaust memory."""
    triangles = sum(m.n_faces for m in placed)
    vertices = sum(m.n_vertices for m in placed)
    if triangles <= MAX_PLACED_TRIANGLES and vertices <= MAX_PLACED_VERTICES:
        return
    which = (
        f"{triangles} triangles, more than the {MAX_PLACED_TRIANGLES}"
        if triangles > MAX_PLACED_TRIANGLES
        else f"{vertices} vertices, more than the {MAX_PLACED_VERTICES}"
    )
    shared = len(placed) - len({id(m) for m in placed})
    raise GltfError(
        f"{r.label}: the scene's {len(placed)} objects have {which} refnpr renders in one scene"
        + (f" ({shared} of the objects place a mesh that another one places too)" if shared else "")
        + "; place fewer copies of the meshes, or simplify them"
    )


def _fields(scene: Scene) -> dict:
    return {
        k: getattr(scene, k)
        for k in ("objects", "camera", "lights", "ambient", "background", "name", "style")
    }


_PACKAGE = str(Path(__file__).resolve().parents[1])  # .../refnpr


def _warn(message: str) -> None:
    """A :class:`GltfWarning` attributed to the first caller outside refnpr (the user's script or
    the ``refnpr`` command), where Python's default filters show it."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, GltfWarning, stacklevel=level)


def _choose_camera(r: _Reader, nodes: list[_Node], placed: list[_Placed], camera) -> _Placed | None:
    cams = [pl for pl in placed if pl.kind == "camera"]
    if camera is None:
        return cams[0] if cams else None

    def label(pl):
        cam_name = r.doc["cameras"][pl.index].get("name")
        return f"{nodes[pl.node].name!r}" + (f" (camera {cam_name!r})" if cam_name else "")

    for pl in cams:
        if _int(camera) and pl.node == camera:
            return pl
        if isinstance(camera, str) and camera in (
            nodes[pl.node].name,
            r.doc["cameras"][pl.index].get("name"),
        ):
            return pl
    listed = ", ".join(label(pl) for pl in cams) or "none"
    raise GltfError(
        f"{r.label}: camera: no camera node named {camera!r} in the scene; camera nodes: {listed}"
    )


def _perspective(r: _Reader, index: int, node_name: str) -> dict:
    cam = r.item("cameras", index, "camera")
    w = f"cameras[{index}]"
    kind = cam.get("type")
    if kind == "orthographic":
        raise r.fail(
            f"{w}.type",
            f"camera {r.name_of(cam, w, node_name)!r} (node {node_name!r}) is orthographic; "
            "refnpr's rasterizer has perspective cameras only: choose a perspective camera "
            "(camera=NAME) or add one to the file",
        )
    if kind != "perspective":
        raise r.fail(f"{w}.type", f"{kind!r}; expected 'perspective' or 'orthographic'")
    persp = cam.get("perspective")
    if not isinstance(persp, dict):
        raise r.fail(f"{w}.perspective", "missing (a perspective camera needs yfov and znear)")
    pw = f"{w}.perspective"
    yfov = r.get_real(persp, "yfov", pw, positive=True)
    if not yfov < math.pi:
        raise r.fail(f"{pw}.yfov", f"{yfov} radians; expected an angle in (0, pi)")
    near = r.get_real(persp, "znear", pw, positive=True)
    far = None
    if "zfar" in persp:
        far = r.get_real(persp, "zfar", pw, positive=True)
        if far <= near:
            raise r.fail(f"{pw}.zfar", f"{far} must be greater than znear ({near})")
    if "aspectRatio" in persp:
        aspect = r.get_real(persp, "aspectRatio", pw, positive=True)
        _warn(
            f"{r.label}: {pw}.aspectRatio {aspect:g}: refnpr takes the aspect ratio from the "
            f"image size; render at a size of that ratio (e.g. {round(480 * aspect)}x480) to "
            "see what the camera frames"
        )
    return {"fov_y": math.degrees(yfov), "near": near, "far": far}


def _framing_camera(lo: np.ndarray, hi: np.ndarray) -> Camera:
    centre = (lo + hi) / 2
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 1e-6)
    direction = np.array([0.35, 0.3, 1.0])
    direction /= np.linalg.norm(direction)
    distance = radius / math.sin(math.radians(22.5)) * 1.05
    return Camera.look_at(
        centre + distance * direction,
        centre,
        (0, 1, 0),
        45.0,
        max(distance - radius, distance * 1e-3) * 0.5,
        (distance + radius) * 2,
    )


# -- animation -------------------------------------------------------------------------------------


@dataclass
class _Sampler:
    times: np.ndarray  # (K,)
    values: np.ndarray  # (K, C) or (K, 3, C) for CUBICSPLINE (in-tangent, value, out-tangent)
    interpolation: str


def _sample(s: _Sampler, t: float, rotation: bool) -> np.ndarray:
    """The glTF sampler's value at time ``t`` (glTF 2.0 appendix C), clamped outside its keys."""
    times, cubic = s.times, s.interpolation == "CUBICSPLINE"
    vals = s.values[:, 1] if cubic else s.values
    if t <= times[0]:
        return vals[0].copy()
    if t >= times[-1]:
        return vals[-1].copy()
    k = int(np.searchsorted(times, t, side="right")) - 1
    t0, t1 = times[k], times[k + 1]
    if s.interpolation == "STEP":
        return vals[k].copy()
    u = (t - t0) / (t1 - t0)
    if s.interpolation == "LINEAR":
        if rotation:
            return np.array(slerp(vals[k], vals[k + 1], u))
        return (1.0 - u) * vals[k] + u * vals[k + 1]
    td = t1 - t0
    p0, m0 = s.values[k, 1], s.values[k, 2] * td  # value and out-tangent of key k
    p1, m1 = s.values[k + 1, 1], s.values[k + 1, 0] * td  # value and in-tangent of key k + 1
    u2, u3 = u * u, u * u * u
    v = (
        (2 * u3 - 3 * u2 + 1) * p0
        + (u3 - 2 * u2 + u) * m0
        + (-2 * u3 + 3 * u2) * p1
        + (u3 - u2) * m1
    )
    if rotation:
        n = np.linalg.norm(v)
        v = v / n if n > 0 else vals[k]
    return v


def _pick_animation(r: _Reader, animation) -> int | None:
    anims = r.array("animations")
    if not anims:
        if animation is not None:
            raise GltfError(
                f"{r.label}: animation: {animation!r} given, but the file has no animations"
            )
        return None
    names = [a.get("name") if isinstance(a, dict) else None for a in anims]
    if animation is None:
        if len(anims) > 1:
            _warn(
                f"{r.label}: the file has {len(anims)} animations; refnpr plays the first "
                f"({names[0] or 'animations[0]'!r}); choose another with animation=NAME"
            )
        return 0
    if _int(animation) and 0 <= animation < len(anims):
        return animation
    if isinstance(animation, str) and animation in names:
        return names.index(animation)
    listed = ", ".join(repr(n or f"animations[{i}]") for i, n in enumerate(names))
    raise GltfError(f"{r.label}: animation: no animation {animation!r}; the file has {listed}")


def _channels(r: _Reader, ai: int, nodes: list[_Node]) -> dict[int, dict[str, _Sampler]]:
    anim = r.item("animations", ai, "animation")
    aw = f"animations[{ai}]"
    samplers, channels = anim.get("samplers"), anim.get("channels")
    if not isinstance(samplers, list) or not isinstance(channels, list):
        raise r.fail(aw, "needs arrays `samplers` and `channels`")
    out: dict[int, dict[str, _Sampler]] = {}
    for c, ch in enumerate(channels):
        cw = f"{aw}.channels[{c}]"
        if not isinstance(ch, dict) or not isinstance(ch.get("target"), dict):
            raise r.fail(cw, "expected an object with `sampler` and `target`")
        target = ch["target"]
        path = target.get("path")
        if path == "weights":
            r.ignore("morph target weight animations")
            continue
        if not isinstance(path, str) or path not in _PATH_WIDTH:
            raise r.fail(
                f"{cw}.target.path",
                f"{short_repr(path)}; expected translation, rotation, scale or weights",
            )
        if "node" not in target:
            continue  # spec: no node means an extension animates something else
        ni = target["node"]
        if not _int(ni) or not 0 <= ni < len(nodes):
            raise r.fail(f"{cw}.target.node", f"{ni!r} is not a node index (0 to {len(nodes) - 1})")
        if nodes[ni].trs is None:
            raise r.fail(
                f"{cw}.target.node",
                f"node {ni} ({nodes[ni].name!r}) has a `matrix`; glTF animates only nodes given "
                "by translation/rotation/scale",
            )
        si = ch.get("sampler")
        if not _int(si) or not 0 <= si < len(samplers) or not isinstance(samplers[si], dict):
            raise r.fail(f"{cw}.sampler", f"{si!r} is not a sampler index of {aw}")
        sw = f"{aw}.samplers[{si}]"
        smp = samplers[si]
        interp = smp.get("interpolation", "LINEAR")
        if interp not in _INTERPOLATIONS:
            raise r.fail(f"{sw}.interpolation", f"{interp!r}; expected one of {_INTERPOLATIONS}")
        times = r.accessor(smp.get("input"), f"{sw}.input", ("SCALAR",), (_FLOAT,))[:, 0]
        if times[0] < 0 or np.any(np.diff(times) <= 0):
            bad = 0 if times[0] < 0 else int(np.argmax(np.diff(times) <= 0)) + 1
            raise r.fail(
                f"accessors[{smp['input']}]",
                f"key time {times[bad]:g} at position {bad} ({sw}.input): key times must be >= 0 "
                "and strictly increasing",
            )
        k = times.shape[0]
        width = _PATH_WIDTH[path]
        comps = (_FLOAT, *_UNORM, *_SNORM) if path == "rotation" else (_FLOAT,)
        n_out = 3 * k if interp == "CUBICSPLINE" else k
        values = r.accessor(smp.get("output"), f"{sw}.output", (f"VEC{width}",), comps, count=n_out)
        if interp == "CUBICSPLINE":
            if k < 2:
                raise r.fail(f"{sw}.input", "a CUBICSPLINE sampler needs at least 2 keys")
            values = values.reshape(k, 3, width)
        elif path == "rotation":
            norms = np.linalg.norm(values, axis=1)
            if np.any(np.abs(norms - 1.0) > 1e-2):
                bad = int(np.argmax(np.abs(norms - 1.0) > 1e-2))
                raise r.fail(
                    f"accessors[{smp['output']}]",
                    f"rotation key {bad} {values[bad].tolist()} is not a unit quaternion "
                    f"({sw}.output)",
                )
            values = values / norms[:, None]
        if path in out.get(ni, {}):
            raise r.fail(f"{cw}.target", f"a second channel animates nodes[{ni}].{path}")
        out.setdefault(ni, {})[path] = _Sampler(times, values, interp)
    return out


def _box_corners(positions: np.ndarray) -> np.ndarray:
    """(8, 3) corners of the axis-aligned box of ``positions`` (N, 3)."""
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    return np.array([[(lo, hi)[k >> a & 1][a] for a in range(3)] for k in range(8)])


def _check_reach(r: _Reader, ai: int, name: str, mesh: Mesh, corners, m: np.ndarray, at) -> None:
    """An error naming the animation, the object and the time ``at = (t, frame)`` where the
    world matrix ``m`` places ``mesh`` beyond the coordinate limit (its box's ``corners``
    first: an affine map keeps the vertices inside their box's image)."""
    with np.errstate(over="ignore", invalid="ignore"):
        if np.all(np.abs(corners @ m[:3, :3].T + m[:3, 3]) <= MAX_COORDINATE):
            return
    t, f = at
    msg = _reach_message(f"object {name!r} at time {t:g} s (frame {f})", mesh, m)
    if msg is not None:
        raise r.fail(
            f"animations[{ai}]", msg + "; or give the animation smaller scales and translations"
        )


def _locals_at(nodes: list[_Node], channels: dict, t: float) -> dict[int, np.ndarray]:
    """The local matrices of the animated nodes at time ``t`` (their channels sampled)."""
    local = {}
    for ni, paths in channels.items():
        tr, q, s = nodes[ni].trs
        tr = _sample(paths["translation"], t, False) if "translation" in paths else tr
        q = _sample(paths["rotation"], t, True) if "rotation" in paths else q
        s = _sample(paths["scale"], t, False) if "scale" in paths else s
        local[ni] = _trs_matrix(tr, q, s)
    return local


def _animation(
    r: _Reader,
    nodes,
    order,
    animation,
    fps,
    *,
    objects_at,
    hidden,
    names,
    meshes,
    cam_at,
    cam_params,
    cam_distance,
    lights_at,
    light_infos,
    headlight,
) -> Animation | None:
    """Tracks with one key per frame: the sampled world transforms of everything the glTF
    animation moves."""
    ai = _pick_animation(r, animation)
    if ai is None:
        return None
    channels = _channels(r, ai, nodes)
    if not channels:
        return None
    duration = max(float(s.times[-1]) for ch in channels.values() for s in ch.values())
    span = duration * fps
    if span > MAX_FRAMES - 1:
        raise r.fail(
            f"animations[{ai}]",
            f"lasts {duration:g} s, {span:.0f} frames at {fps:g} fps, more than refnpr's "
            f"{MAX_FRAMES} frames; use a lower fps",
        )
    frames = int(math.ceil(span - 1e-9)) + 1
    in_scene = set(order)
    moved = set()  # nodes whose world matrix changes: animated ones and their descendants
    for i in order:
        if i in channels or (nodes[i].parent is not None and nodes[i].parent in moved):
            moved.add(i)
    moved &= in_scene
    objs = [(j, pl) for j, pl in enumerate(objects_at) if pl.node in moved]
    cam_moves = cam_at is not None and cam_at.node in moved
    lts = [(j, pl) for j, pl in enumerate(lights_at) if pl.node in moved]
    values = (
        3 * len(objs) + (3 if cam_moves else 0) + len(lts) + (1 if headlight and cam_moves else 0)
    )
    work = frames * (len(order) + len(channels))
    if work > MAX_ANIMATION_WORK:
        raise r.fail(
            f"animations[{ai}]",
            f"{frames} frames x {len(order)} nodes and {len(channels)} animated nodes is more "
            f"than the {MAX_ANIMATION_WORK} node evaluations refnpr allows; use a lower fps",
        )
    if frames * values > MAX_ANIMATION_KEYS:
        raise r.fail(
            f"animations[{ai}]",
            f"{frames} frames x {values} animated values is more than {MAX_ANIMATION_KEYS} keys; "
            "use a lower fps",
        )
    for f in range(frames) if any(pl.node in moved for pl in hidden) else ():
        world = _world(nodes, order, _locals_at(nodes, channels, f / fps))
        for pl in hidden:
            if pl.node in moved and not _singular(world[pl.node][:3, :3]):
                field = _zero_scale_field(nodes, pl.node)
                raise r.fail(
                    field,
                    f"node {nodes[pl.node].name!r} has a zero scale at rest, and animations[{ai}] "
                    f"gives it a non-zero one at time {f / fps:g} s (frame {f}); refnpr leaves "
                    "an object of zero scale out of the scene, so it would never appear: give "
                    f"{field} a tiny non-zero value instead (e.g. 1e-6, far below a pixel)",
                )
    aw = f"animations[{ai}]"
    if values == 0:
        with _located(r, aw):
            return Animation(frames, fps)
    keys: dict[str, list[Keyframe]] = {}

    def add(target: str, frame: int, value) -> None:
        keys.setdefault(target, []).append(Keyframe(frame, tuple(float(x) for x in value)))

    corners = {j: _box_corners(meshes[j].positions) for j, _ in objs}
    with _located(r, aw):  # a Keyframe refusal names no file (one block for every key)
        for f in range(frames):
            t = f / fps
            local = _locals_at(nodes, channels, t)
            world = _world(nodes, order, local)
            for j, pl in objs:
                tr, q, s = _decompose(r, nodes, pl.node, world[pl.node], ai, t, f, local)
                _check_reach(r, ai, names[j], meshes[j], corners[j], world[pl.node], (t, f))
                add(f'object "{names[j]}".translation', f, tr)
                add(f'object "{names[j]}".rotation', f, q)
                add(f'object "{names[j]}".scale', f, s)
            if cam_moves:
                cam = _camera_from(
                    r,
                    nodes,
                    cam_at.node,
                    world[cam_at.node],
                    cam_params,
                    cam_distance,
                    local=local,
                    t=t,
                )
                add("camera.eye", f, cam.eye)
                add("camera.target", f, cam.target)
                add("camera.up", f, cam.up)
            for j, pl in lts:
                placed_at = _light_from(
                    r, nodes, pl, world[pl.node], light_infos[pl.index], local=local, t=t
                )
                for attr, value in placed_at.items():
                    add(f"light[{j}].{attr}", f, value)
    with _located(r, aw):  # a Track or Animation refusal names no file
        tracks = []
        for target, ks in keys.items():
            interp = "slerp" if target.endswith(".rotation") else "linear"
            tracks.append(Track(target, tuple(ks), interp))
        if headlight:
            tracks += headlight_track(tracks)
        return Animation(frames, fps, tuple(tracks))


@contextmanager
def _located(r: _Reader, where: str) -> Iterator[None]:
    """A ``ValueError`` or ``TypeError`` of the block (a refnpr constructor's, which names no
    file) as a :class:`GltfError` naming the file and ``where``."""
    try:
        yield
    except GltfError:
        raise
    except (TypeError, ValueError) as exc:
        raise r.fail(where, str(exc)) from None


def headlight_track(tracks: Sequence[Track]) -> tuple[Track, ...]:
    """The track of the headlight (:func:`camera_headlight`) of a moving camera:
    ``light[0].direction`` = eye - target at every key of the ``camera.eye`` and
    ``camera.target`` tracks (one key per frame, as a glTF animation gives them); nothing
    where the camera does not move."""
    by_target = {t.target: t for t in tracks}
    eye, target = by_target.get("camera.eye"), by_target.get("camera.target")
    if eye is None or target is None:
        return ()
    keys = tuple(
        Keyframe(e.frame, tuple(a - b for a, b in zip(e.value, t.value, strict=True)))
        for e, t in zip(eye.keys, target.keys, strict=True)
    )
    return (Track("light[0].direction", keys, "linear"),)


def _decompose(
    r: _Reader, nodes: list[_Node], i: int, m: np.ndarray, ai: int, t: float, frame: int, local
):
    """Translation, rotation and scale of node ``i``'s world matrix ``m`` at animation time
    ``t`` (frame ``frame``; ``local``: the frame's node matrices)."""
    name = nodes[i].name
    if not np.all(np.isfinite(m)):
        raise r.fail(
            f"animations[{ai}]",
            f"node {name!r} has a world transform that is not finite at time {t:g} s (frame "
            f"{frame}): its translation or scale, composed with its parents', overflows float64; "
            "give the nodes scales and translations of a reasonable size",
        )
    a = m[:3, :3]
    s = np.linalg.norm(a, axis=0)
    if np.any(s == 0) or _singular(a):
        field = _zero_scale_field(nodes, i, local)
        raise r.fail(
            f"animations[{ai}]",
            f"{field} of node {name!r} reaches zero at time {t:g} s (frame {frame}); refnpr "
            "cannot hide an object on some frames only (a scene has the same objects in every "
            "frame, which styles match from frame to frame): animate the scale to a tiny "
            "non-zero value instead (e.g. 1e-6, far below a pixel), or end the animation "
            "before that key",
        )
    rot = a / s
    if np.linalg.det(rot) < 0:
        s[0], rot[:, 0] = -s[0], -rot[:, 0]
    if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-9):
        raise r.fail(
            f"animations[{ai}]",
            f"node {name!r} has a sheared world transform at time {t:g} s (a non-uniform scale "
            "under a rotated parent), which refnpr's translation/rotation/scale tracks cannot "
            "hold",
        )
    return m[:3, 3], quaternion_from_matrix(rot), s


def is_gltf_path(value: Any) -> bool:
    """Whether ``value`` (a str or PathLike) names a glTF file by its suffix."""
    if not isinstance(value, (str, os.PathLike)):
        return False
    return Path(os.fsdecode(value)).suffix.lower() in GLTF_EXTENSIONS
