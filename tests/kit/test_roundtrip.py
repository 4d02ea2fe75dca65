"""Round trip: a kit's meshes, camera and textures, read with trimesh / OpenEXR / imageio alone,
rebuilt into refnpr Meshes and a Camera, rasterize to the same G-buffer as the original scene.

The .glb stores vertex data as float32 (glTF has no float64 vertex type), refnpr's meshes are
float64: the rebuilt G-buffer is bit-identical to rasterizing the original scene with its vertex
data rounded to float32 (what the kit defines), and within float32 rounding of the float64
original (measured below).
"""

from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import OpenEXR
import pytest
import trimesh

from refnpr.golden import load_suite
from refnpr.raster import Camera, Mesh, rasterize
from refnpr.scenes import load_scene

from .conftest import SUITE

CASES = ["gbuffer-default", "room-smooth", "tamiss-teapot", "xtoon-shape-weight-detail"]
BASE_CHANNELS = ["depth", "ndc_z", "tri_id", "mesh_id", "bary", "position", "coverage"]
UV_CHANNELS = ["uv", "duv_dx", "duv_dy", "lod", "dyadic_scale"]


def read_glb(path: Path) -> dict:
    """The glTF mesh's raw arrays as trimesh's glTF reader returns them (no processing)."""
    with open(path, "rb") as f:
        kw = trimesh.exchange.gltf.load_glb(f)
    (geom,) = kw["geometry"].values()
    return geom


def rebuild_mesh(path: Path, entry: dict) -> Mesh:
    """A refnpr Mesh from the .glb alone (plus case.json's attribute name map)."""
    g = read_glb(path)
    attrs = dict(g.get("vertex_attributes", {}))
    uv = attrs.pop("_UV", None)
    extra = {}
    for gl_name, name in entry["attributes"].items():
        a = np.asarray(attrs[gl_name], dtype=np.float64)
        extra[name] = a[:, 0] if a.ndim == 2 and a.shape[1] == 1 else a
    normals = g.get("vertex_normals")
    return Mesh(
        np.asarray(g["vertices"], dtype=np.float64),
        np.asarray(g["faces"], dtype=np.int64),
        normals=None if normals is None else np.asarray(normals, dtype=np.float64),
        uv=None if uv is None else np.asarray(uv, dtype=np.float64),
        attributes=extra,
        name=entry["name"],
    )


def rebuild_camera(cam: dict) -> Camera:
    return Camera.look_at(
        cam["eye"], cam["target"], cam["up"], cam["fov_y"], cam["near"], cam["far"]
    )


def rounded(mesh: Mesh, extra: dict | None = None) -> Mesh:
    """``mesh`` (plus style vertex attributes) with every array rounded to float32."""

    def r(a):
        return None if a is None else np.asarray(a, dtype=np.float32).astype(np.float64)

    attrs = {k: r(v) for k, v in {**mesh.attributes, **(extra or {})}.items()}
    return Mesh(
        r(mesh.positions),
        mesh.faces,
        normals=r(mesh.normals),
        uv=r(mesh.uv),
        attributes=attrs,
        name=mesh.name,
    )


def channels_for(meshes: list[Mesh]) -> list[str]:
    ch = list(BASE_CHANNELS)
    if all(m.normals is not None for m in meshes):
        ch.append("normal")
    if all(m.uv is not None for m in meshes):
        ch += UV_CHANNELS
    names = set(meshes[0].attributes)
    for m in meshes[1:]:
        names &= set(m.attributes)
    return ch + sorted(names)


def raster_kwargs(options: dict) -> dict:
    kw = dict(options)
    kw["texture_size"] = tuple(kw.get("texture_size") or (256, 256))
    if "dtype" in kw:
        kw["dtype"] = np.dtype(kw["dtype"])
    return kw


def original_meshes(case, scene, tmp: Path) -> list[Mesh]:
    """The scene's world meshes with the style's exported vertex attributes (float32-rounded)."""
    extra: dict = {}
    if case.kind == "image":
        from refnpr.kit.export import _style_of
        from refnpr.kit.styles import export_style

        style = _style_of(case, scene)
        sx = export_style(style, scene, tmp, width=case.width, height=case.height, spp=case.spp)
        extra = sx.vertex_attributes
    return [rounded(m, extra.get(k)) for k, m in enumerate(scene.world_meshes())]


@pytest.mark.parametrize("name", CASES)
def test_rebuilt_scene_rasterizes_bit_identically(name, kit_dir, kit_cases, tmp_path):
    data = kit_cases[name]
    case = {c.name: c for c in load_suite(SUITE)}[name]
    scene = load_scene(case.scene)
    cam = rebuild_camera(data["camera"])
    # the camera rebuilt from eye/target/up/fov/near/far has exactly the exported matrices
    assert np.array_equal(cam.view_matrix(), np.array(data["camera"]["view_matrix"]))
    assert np.array_equal(
        cam.projection_matrix(data["width"], data["height"]),
        np.array(data["camera"]["projection_matrix"]),
    )
    rebuilt = [rebuild_mesh(kit_dir / name / o["mesh"], o) for o in data["objects"]]
    assert [o["first_tri_id"] for o in data["objects"]] == list(
        np.cumsum([0] + [len(m.faces) for m in rebuilt[:-1]])
    )
    orig = original_meshes(case, scene, tmp_path)
    channels = channels_for(rebuilt)
    assert channels == channels_for(orig)
    kw = raster_kwargs(data["raster_options"])
    size = (data["width"], data["height"], channels, data["spp"])
    got = rasterize(rebuilt, cam, *size, **kw)
    want = rasterize(orig, scene.camera, *size, **kw)
    for ch in channels:
        a, b = np.asarray(got[ch]), np.asarray(want[ch])
        assert a.dtype == b.dtype and a.shape == b.shape, ch
        assert a.tobytes() == b.tobytes(), f"{name}: channel {ch} differs"


def test_gbuffer_case_expected_channels_are_the_rebuilt_scenes(kit_dir, kit_cases):
    """A G-buffer case's expected channels are refnpr's rasterization of the kit's own meshes:
    rasterizing the rebuilt scene reproduces them bit for bit."""
    data = kit_cases["gbuffer-default"]
    assert data["expected"]["geometry"] == "kit"
    rebuilt = [rebuild_mesh(kit_dir / data["name"] / o["mesh"], o) for o in data["objects"]]
    cam = rebuild_camera(data["camera"])
    kw = raster_kwargs(data["raster_options"])
    gb = rasterize(rebuilt, cam, data["width"], data["height"], data["channels"], data["spp"], **kw)
    for ch, entry in data["expected"]["channels"].items():
        want = np.load(kit_dir / data["name"] / entry["file"])
        got = np.asarray(gb[ch])
        assert list(got.shape) == entry["shape"] and str(got.dtype) == entry["dtype"]
        assert got.tobytes() == want.tobytes(), ch


def test_textures_read_with_openexr_and_imageio_alone(kit_dir, kit_cases):
    """Every texture level decodes without refnpr (OpenEXR's and imageio's own readers) to the
    dtype its entry states, level 0 to its shape, every level with the same channel count."""
    seen = 0
    for name, data in kit_cases.items():
        for role, tex in data["textures"].items():
            shapes = []
            for rel in tex["levels"]:
                path = kit_dir / name / rel
                if tex["dtype"] == "float32":
                    with OpenEXR.File(str(path), separate_channels=True) as f:
                        ch = {k: np.array(v.pixels) for k, v in f.channels().items()}
                    names = [n for n in ("Y", "R", "G", "B", "A") if n in ch]
                    assert names and len(names) == len(ch), (name, role, rel, sorted(ch))
                    arr = np.stack([ch[n] for n in names], axis=-1)
                    arr = arr[..., 0] if names == ["Y"] else arr
                    assert np.all(np.isfinite(arr)), (name, role, rel)
                else:
                    arr = iio.imread(path)
                assert str(arr.dtype) == tex["dtype"], (name, role, rel)
                shapes.append(arr.shape)
                seen += 1
            assert list(shapes[0]) == tex["shape"], (name, role)
            assert all(s[2:] == shapes[0][2:] for s in shapes), (name, role)
    assert seen > 0  # the suite has textured cases


def test_index_lists_every_case_directory(kit_dir):
    index = json.loads((kit_dir / "index.json").read_text())
    dirs = sorted(p.name for p in kit_dir.iterdir() if (p / "case.json").is_file())
    assert sorted(c["name"] for c in index["cases"]) == dirs
