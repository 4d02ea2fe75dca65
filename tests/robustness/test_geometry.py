"""Bad-input catalogue, class "geometry": silently wrong or missing geometry, and mesh files
that are not what they claim (non-finite, truncated, empty, not meshes, wrong paths).

Where a render can be correct the case checks it against an independent expectation (the
fraction of covered pixels a half-plane or a view-filling triangle must give); elsewhere refnpr
owes a ValueError/TypeError (or the CLI's exit 2) that names the parameter or the file, the value
and the fix. Cases call only public APIs and the CLI.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from .catalogue import Case, Correct, Exits, Raises, cli, parametrize

K = "geometry"
_PLY_HEAD = (
    "ply\nformat ascii 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
    "property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
)
_TRI_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"


# ---- helpers -----------------------------------------------------------------------------------
def _sphere():
    import trimesh

    return trimesh.creation.icosphere(subdivisions=1)


def _write(tmp: Path, name: str, data: str | bytes) -> Path:
    p = tmp / name
    if isinstance(data, str):
        p.write_text(data)
    else:
        p.write_bytes(data)
    return p


def _export(tmp: Path, name: str, **kw) -> Path:
    p = tmp / name
    _sphere().export(p, **kw)
    return p


def _load(path: Path):
    from refnpr.scenes import load_mesh

    return load_mesh(path)


def _cam():
    from refnpr.raster import Camera

    return Camera.look_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), 45.0, 0.1, 100.0)


def _raster(pos, faces, size=32):
    from refnpr.raster import Mesh, rasterize

    return rasterize(Mesh(np.asarray(pos, float), faces), _cam(), size, size, ("tri_id",))


def _view_triangle(s: float) -> list:
    """A triangle at z = -1 with vertices ~s: it contains the whole view frustum for s >> 1."""
    return [(-s, -s, -1.0), (s, -s, -1.0), (0.0, s, -1.0)]


def _covers_all(gb, tmp) -> None:
    frac = float((gb["tri_id"] >= 0).mean())
    assert frac == 1.0, f"the triangle contains the view, but covers {frac:.1%} of the pixels"


def _below_line(k: float):
    """Check: the covered pixels are exactly those with centres below y_ndc = k x_ndc."""

    def check(gb, tmp) -> None:
        n = gb["tri_id"].shape[0]
        c = (np.arange(n) + 0.5) / n * 2 - 1
        gap = k * c[None, :] - c[::-1, None]  # rows top-down: y_ndc decreases with the row
        got = gb["tri_id"] >= 0
        bad = (got != (gap > 0)) & (np.abs(gap) > 1e-9)  # on the edge: the fill rule decides
        assert not bad.any(), f"{int(bad.sum())} pixels differ from the half-plane y < {k} x"

    return check


_lower_right_half = _below_line(1.0)


def _covers_nothing(gb, tmp) -> None:
    assert (gb["tri_id"] < 0).all(), "a zero-area triangle covered pixels"


def _binary_ply(verts, faces) -> bytes:
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    body = b"".join(struct.pack("<3f", *v) for v in verts)
    body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    return head + body


def _toml_scene(tmp: Path, obj: str) -> Path:
    _sphere().export(tmp / "ball.obj")
    text = (
        'name = "t"\n[camera]\neye = [0, 0, 4]\ntarget = [0, 0, 0]\n'
        "[[light]]\ndirection = [1, 1, 1]\n[[object]]\n" + obj
    )
    return _write(tmp, "scene.toml", text)


def _cli_render(tmp: Path, obj: str):
    scene = _toml_scene(tmp, obj)
    return cli("render", "--scene", str(scene), "--size", "16x16", "-q", "-o", str(tmp / "o.png"))


def _far_away(offset: float):
    from refnpr.raster import Camera, Mesh, rasterize

    o = offset * np.array([1.0, 0.77, 1.31])  # different roundings per axis
    s, d = 1.2345e6, 1e5
    tri = np.array([(-s, -s / 2, -d), (s, s / 2, -d), (s, -s, -d)]) + o  # edge y = x / 2
    cam = Camera.look_at(o, o - (0.0, 0.0, d), (0.0, 1.0, 0.0), 45.0, 1e4, 1e6)
    return rasterize(Mesh(tri, [[0, 1, 2]]), cam, 64, 64, ("tri_id",))


def _mesh(**kw):
    from refnpr.raster import Mesh

    args = dict(positions=np.eye(3), faces=[[0, 1, 2]])
    args.update(kw)
    return Mesh(**args)


_FILE_ERR = (ValueError, TypeError)
_NAN_PLY = _PLY_HEAD.format(nv=4, nf=2) + "0 0 0\n1 0 0\n0 1 0\nnan 1 0\n3 0 1 2\n3 1 3 2\n"


def _trunc(data: bytes, frac: float) -> bytes:
    return data[: int(len(data) * frac)]


def _export_bytes(tmp: Path, name: str, **kw) -> bytes:
    return _export(tmp, "src_" + name, **kw).read_bytes()


# ---- valid files that must load (each once refused by a raw check) ------------------------------
def _loads(nv: int, nf: int):
    """Check: one Mesh (or the meshes of a scene, summed) with nv vertices and nf triangles."""

    def check(result, tmp) -> None:
        from refnpr.raster import Mesh

        meshes = result if isinstance(result, list) else [result]
        assert all(isinstance(m, Mesh) for m in meshes), f"got {type(result).__name__}"
        got = (sum(m.n_vertices for m in meshes), sum(m.n_faces for m in meshes))
        assert got == (nv, nf), f"loaded {got[0]} vertices and {got[1]} faces, not {nv} and {nf}"

    return check


def _ply(fmt: str, index_type: str, order: str = "<") -> bytes:
    """The subdivided icosahedron (42 vertices, 80 faces) as a PLY with the given index type."""
    tm = _sphere()
    head = (
        f"ply\nformat {fmt} 1.0\nelement vertex {len(tm.vertices)}\nproperty double x\n"
        f"property double y\nproperty double z\nelement face {len(tm.faces)}\n"
        f"property list uint8 {index_type} vertex_indices\nend_header\n"
    ).encode()
    if fmt == "ascii":
        body = "".join(f"{x} {y} {z}\n" for x, y, z in tm.vertices.tolist())
        body += "".join(f"3 {a} {b} {c}\n" for a, b, c in tm.faces)
        return head + body.encode()
    code = {"int64": "q", "uint32": "I", "int32": "i"}[index_type]
    body = b"".join(struct.pack(f"{order}3d", *v) for v in tm.vertices)
    body += b"".join(struct.pack(f"{order}B3{code}", 3, *f) for f in tm.faces)
    return head + body


def _sphere_obj(face) -> str:
    tm = _sphere()
    return "".join(f"v {x} {y} {z}\n" for x, y, z in tm.vertices) + "".join(
        face(i, a + 1, b + 1, c + 1) for i, (a, b, c) in enumerate(tm.faces)
    )


def _off_wrapped() -> str:
    tm = _sphere()
    out = f"OFF\n# wrapped records\n{len(tm.vertices)} {len(tm.faces)} 0\n"
    out += "".join(f"{x} {y}\n  {z}\n" for x, y, z in tm.vertices)
    return out + "".join(f"3 {a}\n{b} {c}\n" for a, b, c in tm.faces)


def _coff() -> str:
    tm = _sphere()
    out = f"COFF\n{len(tm.vertices)} {len(tm.faces)} 0\n"
    out += "".join(f"{x} {y} {z} 255 128 0 255\n" for x, y, z in tm.vertices)
    return out + "".join(f"3 {a} {b} {c} 0.5 0.5 0.5\n" for a, b, c in tm.faces)


def _stl_ascii(tmp: Path, solids: int = 1, upper: bool = False) -> str:
    text = _export_bytes(tmp, "s.stl", file_type="stl_ascii").decode()
    text = "\n".join([text.strip()] * solids) + "\n"
    return text.upper() if upper else text


def _gltf(tmp: Path) -> Path:
    files = _sphere().export(file_type="gltf")
    for name, blob in files.items():
        (tmp / name).write_bytes(blob)
    gltf = next(n for n in files if n.endswith(".gltf"))
    assert any(n.endswith(".bin") for n in files), sorted(files)
    return tmp / gltf


_QUADS_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 5 6 3\n"
_SLASH_OBJ = (
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvn 0 0 1\n"
    "f -4/-4/-1 -3/-3/-1 -2/-2/-1\nf 2//1 4//1 3//1\n"
)

# ---- cases -------------------------------------------------------------------------------------
CASES = [
    # -- huge coordinates: the float64 guard-band clipper -----------------------------------------
    Case(
        "tri-1e20-covers-view",
        K,
        "a triangle with coordinates ~1e20 that contains the whole view (z = -1)",
        lambda tmp: _raster(_view_triangle(1e20), [[0, 1, 2]]),
        Raises(ValueError, r"positions: .*magnitude 1e\+20.*limit 1e\+15.*rescale"),
        "before: drew a quarter of the view (clipped corners off by 2**-53 |NDC| > guard band)",
    ),
    Case(
        "tri-1e17-covers-view",
        K,
        "a view-filling triangle with coordinates ~1e17 (the clipper's failure threshold)",
        lambda tmp: _raster(_view_triangle(1e17), [[0, 1, 2]]),
        Raises(ValueError, r"positions: .*magnitude 1e\+17.*limit"),
    ),
    Case(
        "tri-1e15-covers-view",
        K,
        "a view-filling triangle with coordinates ~1e15 (at the limit)",
        lambda tmp: _raster(_view_triangle(1e15), [[0, 1, 2]]),
        Correct(_covers_all),
    ),
    Case(
        "tri-1e12-diagonal-edge",
        K,
        "a huge triangle (1e12) whose edge y = x crosses the view centre",
        lambda tmp: _raster(
            [(-1e12, -1e12, -1.0), (1e12, 1e12, -1.0), (1e12, -1e12, -1.0)], [[0, 1, 2]]
        ),
        Correct(_lower_right_half),
    ),
    Case(
        "obj-sphere-1e20",
        K,
        "an OBJ sphere whose coordinates are scaled by 1e20",
        lambda tmp: _load(
            _write(
                tmp,
                "huge.obj",
                "".join(f"v {x * 1e20} {y * 1e20} {z * 1e20}\n" for x, y, z in _sphere().vertices)
                + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in _sphere().faces),
            )
        ),
        Raises(ValueError, r"huge\.obj'.*magnitude 1e\+20.*rescale"),
        "before: trimesh merged the 42 vertices into 7 (int64 overflow), render covered 22%",
    ),
    Case(
        "toml-scale-1e20",
        K,
        "a TOML scene object with transform scale = 1e20, rendered by the CLI",
        lambda tmp: _cli_render(tmp, 'path = "ball.obj"\ntransform = { scale = 1e20 }\n'),
        Exits(2, r"error: .*matrix: .*magnitude 1e\+20.*limit"),
    ),
    Case(
        "camera-and-mesh-at-1e20",
        K,
        "a camera at 1e20 and, 1e5 in front of it, a triangle whose edge y = x / 2 crosses the view",
        lambda tmp: _far_away(1e20),
        Raises(ValueError, r"positions: .*magnitude 1\.31e\+20.*limit 1e\+15"),
        "the offset cancels in the view matrix: the same loss as coordinates ~1e20",
    ),
    Case(
        "camera-and-mesh-at-1e9",
        K,
        "the same scene offset by 1e9 (float64 still resolves it)",
        lambda tmp: _far_away(1e9),
        Correct(_below_line(0.5)),
    ),
    Case(
        "transform-1e300",
        K,
        "Mesh.transformed by scale 1e308 and translation 1e308 (positions overflow to inf)",
        lambda tmp: _mesh().transformed(
            np.array([[1e308, 0, 0, 1e308], [0, 1e308, 0, 0], [0, 0, 1e308, 0], [0, 0, 0, 1]])
        ),
        Raises(ValueError, r"matrix: transforming mesh 'mesh' gives non-finite positions"),
    ),
    # -- non-finite vertices in files ---------------------------------------------------------------
    Case(
        "obj-nan-vertex",
        K,
        "an OBJ with a vertex 'v nan 1 1' used by a face",
        lambda tmp: _load(_write(tmp, "nan.obj", _TRI_OBJ + "v nan 1 1\nf 1 2 3\nf 2 4 3\n")),
        Raises(ValueError, r"nan\.obj'.*line 4.*non-finite"),
        "before: the vertex and its face were dropped silently",
    ),
    Case(
        "obj-inf-vertex",
        K,
        "an OBJ with a vertex 'v inf 1 1'",
        lambda tmp: _load(_write(tmp, "inf.obj", _TRI_OBJ + "v inf 1 1\nf 1 2 3\nf 2 4 3\n")),
        Raises(ValueError, r"inf\.obj'.*non-finite"),
    ),
    Case(
        "ply-ascii-nan-vertex",
        K,
        "an ASCII PLY with a NaN vertex",
        lambda tmp: _load(_write(tmp, "nan.ply", _NAN_PLY)),
        Raises(ValueError, r"nan\.ply'.*vertex 3 is not finite"),
    ),
    Case(
        "ply-binary-inf-vertex",
        K,
        "a binary PLY with an inf vertex",
        lambda tmp: _load(
            _write(tmp, "inf.ply", _binary_ply([(0, 0, 0), (1, 0, 0), (np.inf, 1, 0)], [(0, 1, 2)]))
        ),
        Raises(ValueError, r"inf\.ply'.*vertex 2 is not finite"),
    ),
    Case(
        "stl-binary-nan-vertex",
        K,
        "a binary STL with a NaN vertex coordinate",
        lambda tmp: _load(
            _write(
                tmp,
                "nan.stl",
                b"\0" * 80
                + struct.pack("<I", 1)
                + struct.pack("<12fH", *[0.0] * 3, 0, 0, 0, 1, 0, 0, np.nan, 1, 0, 0),
            )
        ),
        Raises(ValueError, r"nan\.stl'.*non-finite"),
    ),
    # -- truncated files ----------------------------------------------------------------------------
    Case(
        "ply-ascii-truncated",
        K,
        "an ASCII PLY cut at two thirds of its length",
        lambda tmp: _load(
            _write(tmp, "cut.ply", _trunc(_export_bytes(tmp, "a.ply", encoding="ascii"), 2 / 3))
        ),
        Raises(ValueError, r"cut\.ply'.*truncated"),
        "before: loaded as a partial mesh",
    ),
    Case(
        "ply-binary-truncated",
        K,
        "a binary PLY cut at 90% of its length",
        lambda tmp: _load(_write(tmp, "cut.ply", _trunc(_export_bytes(tmp, "b.ply"), 0.9))),
        Raises(ValueError, r"cut\.ply'.*truncated"),
    ),
    Case(
        "stl-binary-truncated",
        K,
        "a binary STL with its last 100 bytes cut off",
        lambda tmp: _load(_write(tmp, "cut.stl", _export_bytes(tmp, "c.stl")[:-100])),
        Raises(ValueError, r"cut\.stl'.*binary STL header says 80 triangles.*truncated"),
        "before: \"No module named 'charset_normalizer'\"",
    ),
    Case(
        "stl-ascii-truncated",
        K,
        "an ASCII STL cut in the middle",
        lambda tmp: _load(
            _write(tmp, "cut.stl", _trunc(_export_bytes(tmp, "d.stl", file_type="stl_ascii"), 0.5))
        ),
        Raises(ValueError, r"cut\.stl'.*truncated or corrupt ASCII STL"),
    ),
    Case(
        "glb-truncated",
        K,
        "a GLB cut at half its length",
        lambda tmp: _load(_write(tmp, "cut.glb", _trunc(_export_bytes(tmp, "e.glb"), 0.5))),
        Raises(ValueError, r"cut\.glb'.*truncated"),
    ),
    Case(
        "off-truncated",
        K,
        "an OFF file cut at half its length",
        lambda tmp: _load(_write(tmp, "cut.off", _trunc(_export_bytes(tmp, "f.off"), 0.5))),
        Raises(ValueError, r"cut\.off'.*truncated"),
    ),
    # -- broken topology in files -------------------------------------------------------------------
    Case(
        "obj-missing-vertex",
        K,
        "an OBJ face referencing vertex 7 of 3",
        lambda tmp: _load(_write(tmp, "miss.obj", _TRI_OBJ + "f 1 2 7\n")),
        Raises(ValueError, r"miss\.obj'.*line 4: face references vertex 7, but the file has 3"),
    ),
    Case(
        "obj-index-zero",
        K,
        "an OBJ face with index 0 (OBJ indices are one-based)",
        lambda tmp: _load(_write(tmp, "zero.obj", _TRI_OBJ + "f 0 1 2\n")),
        Raises(ValueError, r"zero\.obj'.*index 0"),
    ),
    Case(
        "ply-two-vertex-face",
        K,
        "an ASCII PLY whose only face has 2 vertices",
        lambda tmp: _load(
            _write(tmp, "two.ply", _PLY_HEAD.format(nv=3, nf=1) + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n")
        ),
        Raises(ValueError, r"two\.ply'.*at least 3 vertices, got 2"),
        "before: 'two: the geometry has no triangles (a point cloud?)' (the stem, not the file)",
    ),
    Case(
        "obj-zero-area-only",
        K,
        "an OBJ whose only triangle has three collinear vertices",
        lambda tmp: _load(_write(tmp, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")),
        Raises(ValueError, r"flat\.obj'.*zero area"),
        "before: loaded; renders nothing",
    ),
    # -- files that are not meshes, and wrong paths -------------------------------------------------
    Case(
        "glb-no-geometry",
        K,
        "a GLB holding only a point cloud",
        lambda tmp: _load(_glb_points(tmp)),
        Raises(ValueError, r"points\.glb' contains no triangle mesh"),
    ),
    Case(
        "obj-not-a-mesh",
        K,
        "a text file named .obj that is no OBJ",
        lambda tmp: _load(_write(tmp, "notes.obj", "hello world\n")),
        Raises(ValueError, r"notes\.obj'.*no faces"),
    ),
    Case(
        "stl-garbage",
        K,
        "an .stl file of 2 kB of random bytes",
        lambda tmp: _load(_write(tmp, "noise.stl", np.random.default_rng(1).bytes(2000))),
        Raises(ValueError, r"noise\.stl'.*(binary STL header says|STL)"),
    ),
    Case(
        "empty-file",
        K,
        "an empty .ply file",
        lambda tmp: _load(_write(tmp, "empty.ply", b"")),
        Raises(ValueError, r"empty\.ply' is empty"),
    ),
    Case(
        "directory-as-mesh",
        K,
        "a directory named model.obj given as the mesh file",
        lambda tmp: (tmp / "model.obj").mkdir() or _load(tmp / "model.obj"),
        Raises(ValueError, r"model\.obj' is a directory; expected a mesh file"),
        "before: reported as 'does not exist'",
    ),
    Case(
        "missing-file",
        K,
        "a mesh path that does not exist",
        lambda tmp: _load(tmp / "nowhere" / "gone.obj"),
        Raises(FileNotFoundError, r"nowhere/gone\.obj' does not exist"),
    ),
    Case(
        "unsupported-extension",
        K,
        "a mesh file with the extension .fbx",
        lambda tmp: _load(_write(tmp, "model.fbx", b"Kaydara FBX Binary  \0")),
        Raises(ValueError, r"model\.fbx' has the unsupported extension '\.fbx'; supported .*\.obj"),
    ),
    Case(
        "cli-toml-truncated-stl",
        K,
        "a TOML scene whose object is a truncated binary STL, rendered by the CLI",
        lambda tmp: (
            (tmp / "cut.stl").write_bytes(_export_bytes(tmp, "g.stl")[:-30]),
            _cli_render(tmp, 'path = "cut.stl"\n'),
        )[1],
        Exits(2, r"error: .*cut\.stl'.*truncated"),
    ),
    # -- meshes built in Python ---------------------------------------------------------------------
    Case(
        "mesh-nan-position",
        K,
        "Mesh(positions with a NaN)",
        lambda tmp: _mesh(positions=[[0, 0, 0], [1, 0, np.nan], [0, 1, 0]]),
        Raises(ValueError, r"positions: contains NaN or inf .*index \(1, 2\)"),
    ),
    Case(
        "mesh-face-out-of-range",
        K,
        "Mesh(faces=[[0, 1, 3]]) for 3 vertices",
        lambda tmp: _mesh(faces=[[0, 1, 3]]),
        Raises(ValueError, r"faces: index out of range \(min 0, max 3\) for 3 vertices"),
    ),
    Case(
        "mesh-face-negative",
        K,
        "Mesh(faces=[[0, -1, 2]])",
        lambda tmp: _mesh(faces=[[0, -1, 2]]),
        Raises(ValueError, r"faces: index out of range \(min -1"),
    ),
    Case(
        "mesh-face-non-integer",
        K,
        "Mesh(faces=[[0.0, 1.5, 2.0]])",
        lambda tmp: _mesh(faces=[[0.0, 1.5, 2.0]]),
        Raises(TypeError, r"faces: expected integer indices, got dtype float64"),
    ),
    Case(
        "mesh-face-nan",
        K,
        "Mesh(faces=[[0, nan, 2]])",
        lambda tmp: _mesh(faces=[[0, np.nan, 2]]),
        Raises(TypeError, r"faces: expected integer indices.*nan"),
    ),
    Case(
        "mesh-face-strings",
        K,
        "Mesh(faces=[['0', '1', '2']])",
        lambda tmp: _mesh(faces=[["0", "1", "2"]]),
        Raises(TypeError, r"faces: expected integer indices, got dtype <U1"),
    ),
    Case(
        "mesh-faces-quads",
        K,
        "Mesh(faces of shape (1, 4))",
        lambda tmp: _mesh(positions=np.eye(4)[:, :3], faces=[[0, 1, 2, 3]]),
        Raises(ValueError, r"faces: expected shape \(M, 3\), got \(1, 4\)"),
    ),
    Case(
        "mesh-positions-2d",
        K,
        "Mesh(positions of shape (3, 2))",
        lambda tmp: _mesh(positions=np.eye(3)[:, :2]),
        Raises(ValueError, r"positions: expected shape \(N, 3\), got \(3, 2\)"),
    ),
    Case(
        "mesh-zero-area-renders-nothing",
        K,
        "a Python Mesh whose only triangle is degenerate, rasterized",
        lambda tmp: _raster([(0, 0, -1.0), (1, 0, -1.0), (2, 0, -1.0)], [[0, 1, 2]]),
        Correct(_covers_nothing),
    ),
    # -- valid files that must load ------------------------------------------------------------
    Case(
        "stl-ascii-uppercase",
        K,
        "an ASCII STL written in upper case (SOLID / FACET / VERTEX)",
        lambda tmp: _load(_write(tmp, "up.stl", _stl_ascii(tmp, upper=True))),
        Correct(_loads(42, 80)),
        "before: 'the ASCII STL holds no facets' (keywords matched in lower case only)",
    ),
    Case(
        "stl-ascii-two-solids",
        K,
        "an ASCII STL holding two solids",
        lambda tmp: _load(_write(tmp, "two.stl", _stl_ascii(tmp, solids=2))),
        Correct(_loads(84, 160)),
    ),
    Case(
        "ply-binary-int64-indices",
        K,
        "a binary PLY with 'property list uint8 int64 vertex_indices'",
        lambda tmp: _load(_write(tmp, "i8.ply", _ply("binary_little_endian", "int64"))),
        Correct(_loads(42, 80)),
        "before: 'malformed property line' (int64 missing from the type table)",
    ),
    Case(
        "ply-ascii-uint32-indices",
        K,
        "an ASCII PLY with 'property list uint8 uint32 vertex_indices'",
        lambda tmp: _load(_write(tmp, "u4.ply", _ply("ascii", "uint32"))),
        Correct(_loads(42, 80)),
    ),
    Case(
        "ply-big-endian",
        K,
        "a big-endian binary PLY",
        lambda tmp: _load(_write(tmp, "be.ply", _ply("binary_big_endian", "int32", ">"))),
        Correct(_loads(42, 80)),
    ),
    Case(
        "obj-backslash-continuation",
        K,
        "an OBJ whose face lines are continued with a trailing backslash",
        lambda tmp: _load(
            _write(tmp, "cont.obj", _sphere_obj(lambda i, a, b, c: f"f {a} {b} \\\n {c}\n"))
        ),
        Correct(_loads(42, 80)),
    ),
    Case(
        "obj-negative-and-slash-indices",
        K,
        "an OBJ with negative (relative) indices and 'f v/vt/vn' and 'f v//vn' forms",
        lambda tmp: _load(_write(tmp, "slash.obj", _SLASH_OBJ)),
        Correct(_loads(4, 2)),
    ),
    Case(
        "obj-quads",
        K,
        "an OBJ of two quads",
        lambda tmp: _load(_write(tmp, "quads.obj", _QUADS_OBJ)),
        Correct(_loads(6, 4)),
    ),
    Case(
        "off-wrapped-records",
        K,
        "an OFF file whose vertex and face records are wrapped across lines",
        lambda tmp: _load(_write(tmp, "wrapped.off", _off_wrapped())),
        Correct(_loads(42, 80)),
    ),
    Case(
        "coff-colours",
        K,
        "a COFF file with vertex colours and face colours",
        lambda tmp: _load(_write(tmp, "colours.off", _coff())),
        Correct(_loads(42, 80)),
    ),
    Case(
        "gltf-external-bin",
        K,
        "a .gltf whose buffer is an external .bin file",
        lambda tmp: _load(_gltf(tmp)),
        Correct(_loads(42, 80)),
    ),
]


def _glb_points(tmp: Path) -> Path:
    import trimesh

    scene = trimesh.Scene()
    scene.add_geometry(trimesh.points.PointCloud(np.random.default_rng(0).random((5, 3))))
    p = tmp / "points.glb"
    scene.export(p)
    return p


test_case = parametrize(CASES)
