"""glTF 2.0 scenes: the reader's geometry, transforms, cameras, lights, materials and animations
against values computed here from the file's numbers, and malformed files with their messages.

The files are written here: geometry from trimesh, JSON (nodes, cameras, lights, animations) by
hand, packed as .gltf with a data: URI, an external .bin, or .glb. Embedded images:
test_gltf_images.py.
"""

from __future__ import annotations

import base64
import json
import math
import struct
import warnings

import numpy as np
import pytest
import trimesh

from refnpr.scenes import load_scene
from refnpr.scenes.gltf import GltfError, GltfWarning, load_gltf

from ._gltf_write import write_gltf


class Doc:
    """A glTF document under construction: arrays packed into one buffer."""

    def __init__(self):
        self.blob = bytearray()
        self.doc = {
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }

    def accessor(self, array, ctype=5126, kind=None, **extra) -> int:
        dtype = {5126: "<f4", 5125: "<u4", 5123: "<u2", 5121: "<u1"}[ctype]
        a = np.ascontiguousarray(array, dtype=dtype)
        width = 1 if a.ndim == 1 else a.shape[1]
        data = a.tobytes()
        self.doc["bufferViews"].append(
            {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        )
        self.blob += data + b"\0" * (-len(data) % 4)
        kind = kind or {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}[width]
        self.doc["accessors"].append(
            {
                "bufferView": len(self.doc["bufferViews"]) - 1,
                "componentType": ctype,
                "count": int(a.shape[0]),
                "type": kind,
                **extra,
            }
        )
        return len(self.doc["accessors"]) - 1

    def view(self, array, dtype, **extra) -> int:
        """A buffer view of ``array`` packed as ``dtype`` (no accessor): its index."""
        data = np.ascontiguousarray(array, dtype=dtype).tobytes()
        self.doc["bufferViews"].append(
            {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data), **extra}
        )
        self.blob += data + b"\0" * (-len(data) % 4)
        return len(self.doc["bufferViews"]) - 1

    def mesh(self, tm: trimesh.Trimesh, *, normals=True, indexed=True, name=None, **prim) -> int:
        pos = np.asarray(tm.vertices)
        faces = np.asarray(tm.faces)
        if not indexed:
            pos = pos[faces].reshape(-1, 3)
        attrs = {"POSITION": self.accessor(pos)}
        if normals:
            n = np.asarray(tm.vertex_normals)
            attrs["NORMAL"] = self.accessor(n if indexed else n[faces].reshape(-1, 3))
        p = {"attributes": attrs, **prim}
        if indexed:
            p["indices"] = self.accessor(faces.reshape(-1), 5125)
        self.doc["meshes"].append({"primitives": [p], **({"name": name} if name else {})})
        return len(self.doc["meshes"]) - 1

    def node(self, root=True, **fields) -> int:
        self.doc["nodes"].append(fields)
        i = len(self.doc["nodes"]) - 1
        if root:
            self.doc["scenes"][0]["nodes"].append(i)
        return i

    def write(self, path, form="glb"):
        return write_gltf(self.doc, bytes(self.blob), path, form)


def quat(axis, deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = math.radians(deg) / 2
    return [*(a * math.sin(h)), math.cos(h)]


def rot(q):
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def trs(t=(0, 0, 0), q=(0, 0, 0, 1), s=(1, 1, 1)):
    m = np.eye(4)
    m[:3, :3] = rot(q) @ np.diag(s)
    m[:3, 3] = t
    return m


def quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GltfWarning)
        return fn(*a, **k)


def two_boxes_with_camera():
    """A parent node (TRS) with a child box (matrix), a second box, a camera under a rotated
    node and a directional light."""
    d = Doc()
    box = d.mesh(trimesh.creation.box((1.0, 1.0, 1.0)), name="boxmesh")
    child = d.node(
        root=False,
        name="child",
        mesh=box,
        matrix=trs((1.0, 0.0, 0.0), quat((0, 0, 1), 30), (0.5, 0.5, 0.5)).T.reshape(-1).tolist(),
    )
    d.node(
        name="parent", translation=[0.0, 1.0, -2.0], rotation=quat((0, 1, 0), 90), children=[child]
    )
    d.node(name="second", mesh=box, translation=[-2.0, 0.0, 0.0], scale=[1.0, 2.0, 1.0])
    d.doc["cameras"] = [
        {
            "name": "cam",
            "type": "perspective",
            "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 50.0},
        }
    ]
    d.node(name="camnode", camera=0, translation=[0.5, 2.0, 8.0], rotation=quat((1, 0, 0), -10))
    d.doc["extensions"] = {
        "KHR_lights_punctual": {
            "lights": [{"type": "directional", "color": [1.0, 0.5, 0.25], "intensity": 2.0}]
        }
    }
    d.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    d.node(
        name="sun",
        rotation=quat((1, 0, 0), -90),
        extensions={"KHR_lights_punctual": {"light": 0}},
    )
    return d


@pytest.mark.parametrize("form", ["glb", "data", "bin"])
def test_hierarchy_camera_light(tmp_path, form):
    d = two_boxes_with_camera()
    path = d.write(tmp_path / ("model.glb" if form == "glb" else "model.gltf"), form)
    scene = quiet(load_scene, str(path))
    names = [o.name for o in scene.objects]
    assert names == ["child", "second"]
    parent = trs((0.0, 1.0, -2.0), quat((0, 1, 0), 90))
    child = trs((1.0, 0.0, 0.0), quat((0, 0, 1), 30), (0.5, 0.5, 0.5))
    np.testing.assert_allclose(scene.objects[0].transform, parent @ child, atol=1e-12)
    np.testing.assert_allclose(
        scene.objects[1].transform, trs((-2.0, 0.0, 0.0), s=(1, 2, 1)), atol=1e-12
    )
    cam = scene.camera
    np.testing.assert_allclose(cam.eye, [0.5, 2.0, 8.0])
    r = rot(quat((1, 0, 0), -10))
    np.testing.assert_allclose(cam.forward, -r[:, 2], atol=1e-12)
    assert cam.fov_y == pytest.approx(math.degrees(0.8))
    assert (cam.near, cam.far) == (0.1, 50.0)
    (light,) = scene.lights
    assert light.kind == "directional"
    np.testing.assert_allclose(light.color, [2.0, 1.0, 0.5])
    # the light shines along its node's -Z: rotated -90 deg about x, -Z becomes -Y (straight down)
    np.testing.assert_allclose(light.direction, [0.0, 1.0, 0.0], atol=1e-12)
    assert scene.objects[0].mesh.positions.shape == (8, 3) or scene.objects[0].mesh.n_faces == 12


def test_render_lands_where_projected(tmp_path):
    """A rendered glTF's pixels match a float64 pinhole projection of its known vertices."""
    from refnpr.raster import rasterize
    from refnpr.render import render

    d = Doc()
    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)
    mesh = d.mesh(tri, normals=False)
    d.node(
        name="tri",
        mesh=mesh,
        translation=[0.2, -0.3, -1.0],
        rotation=quat((0, 0, 1), 20),
        scale=[1.5, 1.2, 1.0],
    )
    yfov, w, h = 0.9, 48, 32
    d.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.05}}]
    cam_q = quat((0, 1, 0), 15)
    d.node(name="cam", camera=0, translation=[0.4, 0.1, 3.0], rotation=cam_q)
    d.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.4, 0.6, 0.8, 1.0]}}]
    d.doc["meshes"][0]["primitives"][0]["material"] = 0
    d.doc["extensions"] = {
        "KHR_lights_punctual": {"lights": [{"type": "directional", "color": [1.0, 0.5, 0.25]}]}
    }
    light_q = quat((1, 0, 0), -30)
    d.node(name="sun", rotation=light_q, extensions={"KHR_lights_punctual": {"light": 0}})
    scene = quiet(load_gltf, d.write(tmp_path / "t.glb"))
    gb = rasterize(scene, scene.camera, w, h, channels=("tri_id",))
    covered = gb["tri_id"] >= 0
    # independent projection: world vertices, camera frame from the node's TRS, pinhole
    model = trs((0.2, -0.3, -1.0), quat((0, 0, 1), 20), (1.5, 1.2, 1.0))
    verts = (model @ np.c_[tri.vertices, np.ones(3)].T).T[:, :3]
    cam_r = rot(cam_q)
    eye = np.array([0.4, 0.1, 3.0])
    local = (verts - eye) @ cam_r  # camera-space coordinates (columns: right, up, back)
    f = 1 / math.tan(yfov / 2)
    ndc = np.c_[f * (h / w) * local[:, 0] / -local[:, 2], f * local[:, 1] / -local[:, 2]]
    px = np.c_[(ndc[:, 0] + 1) / 2 * w, (1 - ndc[:, 1]) / 2 * h]
    # a pixel centre is covered iff it lies inside the projected triangle (edge functions)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    pts = np.stack([xs, ys], -1)

    def edge(a, b):
        return (b[0] - a[0]) * (pts[..., 1] - a[1]) - (b[1] - a[1]) * (pts[..., 0] - a[0])

    e = [edge(px[0], px[1]), edge(px[1], px[2]), edge(px[2], px[0])]
    inside = (e[0] > 0.05) & (e[1] > 0.05) & (e[2] > 0.05) | (e[0] < -0.05) & (e[1] < -0.05) & (
        e[2] < -0.05
    )
    outside = ~((e[0] >= -0.05) & (e[1] >= -0.05) & (e[2] >= -0.05)) & ~(
        (e[0] <= 0.05) & (e[1] <= 0.05) & (e[2] <= 0.05)
    )
    assert inside.sum() > 50
    assert covered[inside].all()
    assert not covered[outside].any()
    # the light: Veryovka eq. 1 without specular, I = m_a l_a + m_d max(N.L, 0) l_i, with the
    # light shining along its node's -Z and the triangle's normal +Z (a z rotation keeps it)
    image = render(scene, {"name": "smooth", "specular": False}, w, h)
    to_light = rot(light_q)[:, 2]
    base = np.array([0.4, 0.6, 0.8])
    expect = 0.15 / 0.8 * base + base * max(to_light[2], 0.0) * np.array([1.0, 0.5, 0.25])
    np.testing.assert_allclose(
        image.rgba[inside][:, :3], np.tile(expect, (inside.sum(), 1)), atol=1e-5
    )


def test_no_lights_gets_headlight_and_no_camera_frames(tmp_path):
    d = Doc()
    d.node(name="ball", mesh=d.mesh(trimesh.creation.icosphere(1)))
    path = d.write(tmp_path / "ball.glb")
    with pytest.warns(GltfWarning, match="headlight"):
        scene = load_gltf(path)
    (light,) = scene.lights
    expect = (scene.camera.eye - scene.camera.target) / np.linalg.norm(
        scene.camera.eye - scene.camera.target
    )
    np.testing.assert_allclose(light.direction, expect, atol=1e-12)
    lo, hi = scene.bounds()
    for corner in np.array(np.meshgrid(*zip(lo, hi, strict=True))).reshape(3, -1).T:
        p = scene.camera.view_projection(64, 64) @ [*corner, 1.0]
        assert np.all(np.abs(p[:3] / p[3]) < 1.0)  # the framing camera sees every corner


def test_strips_fans_nonindexed_and_flat_normals(tmp_path):
    d = Doc()
    quad = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    strip = {"attributes": {"POSITION": d.accessor(quad)}, "mode": 5}
    fan = {"attributes": {"POSITION": d.accessor(quad[[0, 1, 3, 2]])}, "mode": 6}
    d.doc["meshes"].append({"name": "m", "primitives": [strip, fan]})
    d.node(name="q", mesh=0)
    scene = quiet(load_gltf, d.write(tmp_path / "q.glb"))
    a, b = scene.objects
    assert (a.name, b.name) == ("q[0]", "q[1]")
    for obj in (a, b):
        p = obj.mesh.positions[obj.mesh.faces]
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        assert obj.mesh.n_faces == 2
        assert np.all(n[:, 2] > 0)  # both converted triangles counter-clockwise, facing +z
        np.testing.assert_allclose(obj.mesh.normals, np.tile([0, 0, 1.0], (6, 1)))


def test_material_base_color_and_ignored_inputs(tmp_path):
    d = Doc()
    d.node(name="b", mesh=d.mesh(trimesh.creation.box(), material=0))
    d.doc["materials"] = [
        {
            "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1.0], "metallicFactor": 0},
            "normalTexture": {"index": 0},
        }
    ]
    with pytest.warns(GltfWarning) as record:
        scene = load_gltf(d.write(tmp_path / "m.glb"))
    m = scene.objects[0].material
    np.testing.assert_allclose(m.diffuse, [0.2, 0.4, 0.6])
    np.testing.assert_allclose(m.ambient, np.array([0.2, 0.4, 0.6]) * 0.15 / 0.8)
    ignored = [str(w.message) for w in record if "ignored" in str(w.message)]
    assert len(ignored) == 1
    assert "normalTexture" in ignored[0] and "metallicFactor" in ignored[0]


def test_ignored_keys_are_named_with_their_control_characters_escaped(tmp_path):
    """The note of inputs not read quotes the file's own keys: a terminal escape or a bidi
    override in one is written as a Python escape, never sent to the terminal."""
    d = _base()
    d.doc["meshes"][0]["primitives"][0]["attributes"]["\x1b[2J\x1b[31mX\u202e"] = 0
    d.doc["extensions"] = {"\x1b]0;title\x07": {}}
    with pytest.warns(GltfWarning) as record:
        load_gltf(d.write(tmp_path / "esc.glb"))
    (ignored,) = [str(w.message) for w in record if "not read (ignored)" in str(w.message)]
    assert ignored.isprintable()
    assert "vertex attribute \\x1b[2J\\x1b[31mX\\u202e" in ignored
    assert "extension \\x1b]0;title\\x07" in ignored


def _light(color, intensity):
    def edit(d):
        d.doc["extensions"] = {
            "KHR_lights_punctual": {
                "lights": [{"type": "point", "color": color, "intensity": intensity}]
            }
        }
        d.node(extensions={"KHR_lights_punctual": {"light": 0}}, translation=[0.0, 0.0, 2.0])

    return edit


def test_a_light_whose_colour_times_intensity_overflows_is_refused(tmp_path):
    d = _base()
    _light([1e300, 1.0, 1.0], 1e300)(d)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no numpy overflow warning either
        with pytest.raises(
            GltfError,
            match=r"l\.glb: extensions\.KHR_lights_punctual\.lights\[0\]: color \[1e\+300, 1\.0, "
            r"1\.0\] x intensity 1e\+300 \(the light's colour\) is beyond float64",
        ):
            quiet(load_gltf, d.write(tmp_path / "l.glb"))
    d = _base()
    _light([1e200, 1.0, 1.0], 1e100)(d)  # large, but a float64
    (light,) = quiet(load_gltf, d.write(tmp_path / "big.glb")).lights
    assert light.color == (1e300, 1e100, 1e100)


def test_a_refused_light_names_the_file_and_light(tmp_path, monkeypatch):
    import refnpr.scenes.gltf as gltf

    def refuse(**fields):
        raise ValueError(f"color: {len(fields)} fields refused")

    monkeypatch.setattr(gltf, "Light", refuse)
    d = _base()
    _light([1.0, 0.5, 0.25], 2.0)(d)
    with pytest.raises(
        GltfError,
        match=r"r\.glb: extensions\.KHR_lights_punctual\.lights\[0\]: color: 3 fields refused",
    ):
        quiet(load_gltf, d.write(tmp_path / "r.glb"))


def test_camera_choice_and_orthographic(tmp_path):
    d = two_boxes_with_camera()
    d.doc["cameras"].append(
        {
            "name": "ortho",
            "type": "orthographic",
            "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 9},
        }
    )
    d.doc["cameras"].append(
        {"name": "wide", "type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.2}}
    )
    d.node(name="ortho_node", camera=1, translation=[0, 0, 5])
    d.node(name="wide_node", camera=2, translation=[0, 1, 6])
    path = d.write(tmp_path / "c.glb")
    assert quiet(load_scene, str(path)).camera.fov_y == pytest.approx(math.degrees(0.8))
    wide = quiet(load_scene, str(path), camera="wide")
    np.testing.assert_allclose(wide.camera.eye, [0, 1, 6])
    assert quiet(load_gltf, path, camera="wide_node").camera.fov_y == pytest.approx(
        math.degrees(1.2)
    )
    with pytest.raises(ValueError, match=r"c\.glb: cameras\[1\]\.type: .*'ortho'.*orthographic"):
        quiet(load_gltf, path, camera="ortho")
    with pytest.raises(ValueError, match="no camera node named 'nope'.*'camnode'"):
        quiet(load_gltf, path, camera="nope")


def test_toml_with_gltf_overrides(tmp_path):
    two_boxes_with_camera().write(tmp_path / "model.glb")
    (tmp_path / "s.toml").write_text(
        'gltf = "model.glb"\n'
        "[camera]\nfov_y = 30.0\n"
        '[style]\nname = "toon"\n'
        '[materials."*"]\nspecular = 0.0\n'
        "[materials.second]\ndiffuse = [1.0, 0.0, 0.0]\n"
        '[[light]]\nkind = "point"\nposition = [1.0, 2.0, 3.0]\n'
        '[[object]]\nname = "extra"\nmesh = "teapot"\nlevel = 2\n'
    )
    scene = quiet(load_scene, tmp_path / "s.toml")
    assert scene.camera.fov_y == 30.0
    np.testing.assert_allclose(scene.camera.eye, [0.5, 2.0, 8.0])
    assert scene.style == {"name": "toon"}
    assert [o.name for o in scene.objects] == ["child", "second", "extra"]
    assert scene.objects[1].material.diffuse == (1.0, 0.0, 0.0)
    assert scene.objects[0].material.specular == (0.0, 0.0, 0.0)
    assert scene.objects[0].material.diffuse == (0.8, 0.8, 0.8)  # no glTF material: refnpr's
    assert [lt.kind for lt in scene.lights] == ["point"]
    (tmp_path / "bad.toml").write_text('gltf = "model.glb"\n[materials.nobody]\ndiffuse = 1.0\n')
    with pytest.raises(
        ValueError, match=r"bad\.toml: \[materials\]: no glTF object named 'nobody'"
    ):
        quiet(load_scene, tmp_path / "bad.toml")


def _box_and_moving_camera():
    """A box, a camera node that slides along +x over 1 s, and no lights."""
    d = Doc()
    d.node(name="box", mesh=d.mesh(trimesh.creation.box()))
    d.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]
    d.node(name="cam", camera=0, translation=[0.0, 1.0, 6.0])
    tin = d.accessor(np.array([0.0, 1.0]))
    tout = d.accessor(np.array([[0.0, 1.0, 6.0], [3.0, 1.0, 6.0]]))
    d.doc["animations"] = [
        {
            "samplers": [{"input": tin, "output": tout, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
        }
    ]
    return d


def test_a_toml_scene_lights_a_lightless_file_from_its_own_camera(tmp_path):
    """The headlight of a file without lights is the camera the scene renders from: the file's
    (following its animation, as load_gltf gives it), or the one a [camera] table sets."""
    from refnpr.scenes.gltf import camera_headlight

    _box_and_moving_camera().write(tmp_path / "model.glb")
    direct = quiet(load_gltf, tmp_path / "model.glb")
    (tmp_path / "plain.toml").write_text('gltf = "model.glb"\n')
    with pytest.warns(GltfWarning, match="headlight .*from the scene's camera"):
        plain = load_scene(tmp_path / "plain.toml")
    assert plain.lights == direct.lights == (camera_headlight(direct.camera),)
    assert at_frames(plain, "light[0].direction").tolist() == (
        at_frames(direct, "light[0].direction").tolist()
    )
    eye, target = at_frames(direct, "camera.eye"), at_frames(direct, "camera.target")
    assert eye[-1].tolist() == [3.0, 1.0, 6.0]  # the camera moved
    assert at_frames(plain, "light[0].direction").tolist() == (eye - target).tolist()

    (tmp_path / "moved.toml").write_text(
        'gltf = "model.glb"\n[camera]\neye = [-5.0, 2.0, 1.0]\ntarget = [0.0, 0.0, 0.0]\n'
    )
    moved = quiet(load_scene, tmp_path / "moved.toml")
    assert moved.lights == (camera_headlight(moved.camera),)
    np.testing.assert_allclose(moved.lights[0].direction, np.array([-5, 2, 1]) / np.sqrt(30))
    assert not any(t.target.startswith(("camera.", "light[")) for t in moved.animation.tracks)

    (tmp_path / "lit.toml").write_text('gltf = "model.glb"\n[[light]]\ndirection = [0, 1, 0]\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error", GltfWarning)  # no headlight, no warning about one
        lit = load_scene(tmp_path / "lit.toml")
    assert [lt.direction for lt in lit.lights] == [(0.0, 1.0, 0.0)]


# -- animation ---------------------------------------------------------------------------------------


def animated(interp, times, values, path="translation"):
    d = Doc()
    box = d.mesh(trimesh.creation.box())
    d.node(name="box", mesh=box, translation=[0.0, 0.0, 0.0])
    tin = d.accessor(np.asarray(times, float))
    tout = d.accessor(np.asarray(values, float))
    d.doc["animations"] = [
        {
            "name": "move",
            "samplers": [{"input": tin, "output": tout, "interpolation": interp}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": path}}],
        }
    ]
    return d


def at_frames(scene, target):
    track = {t.target: t for t in scene.animation.tracks}[target]
    return np.array([k.value for k in track.keys])


def test_animation_linear_step_cubic(tmp_path):
    times = [0.0, 0.5, 1.0]
    vals = [[0, 0, 0], [2, 0, 0], [2, 4, 0]]
    lin = quiet(load_gltf, animated("LINEAR", times, vals).write(tmp_path / "a.glb"), fps=4)
    assert lin.frames == 5
    got = at_frames(lin, 'object "box".translation')
    np.testing.assert_allclose(got, [[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 2, 0], [2, 4, 0]])
    step = quiet(load_gltf, animated("STEP", times, vals).write(tmp_path / "s.glb"), fps=4)
    got = at_frames(step, 'object "box".translation')
    np.testing.assert_allclose(got, [[0, 0, 0], [0, 0, 0], [2, 0, 0], [2, 0, 0], [2, 4, 0]])
    # CUBICSPLINE: (in-tangent, value, out-tangent) per key; hand-evaluated Hermite at t = 0.25
    cub_vals = [[0, 0, 0], [0, 0, 0], [4, 0, 0], [0, 0, 0], [1, 0, 0], [0, 0, 0]]
    cub = quiet(
        load_gltf, animated("CUBICSPLINE", [0.0, 0.5], cub_vals).write(tmp_path / "c.glb"), fps=8
    )
    got = at_frames(cub, 'object "box".translation')
    u, td = 0.5, 0.5  # frame 2 = 0.25 s, halfway
    expect = (u**3 - 2 * u**2 + u) * 4 * td + (-2 * u**3 + 3 * u**2) * 1
    assert got[2, 0] == pytest.approx(expect, abs=1e-12)
    assert got[4, 0] == 1.0 and got[0, 0] == 0.0
    # the scene's still at a frame carries the sampled transform
    np.testing.assert_allclose(cub.at(2).objects[0].transform[:3, 3], [expect, 0, 0], atol=1e-12)


def test_an_animated_root_listed_twice_is_refused(tmp_path):
    d = animated("LINEAR", [0.0, 1.0], [[0, 0, 0], [1, 0, 0]])
    d.doc["scenes"][0]["nodes"] = [0, 0]
    with pytest.raises(GltfError, match=r"twice\.glb: scenes\[0\]\.nodes\[1\]: node 0 is listed"):
        quiet(load_gltf, d.write(tmp_path / "twice.glb"))


def test_animated_objects_get_unique_names_when_a_node_takes_a_made_up_name(tmp_path):
    """A repeated name gets " (nodes[i])"; a node may already be named so: that name is taken
    too, else two moving objects would share their tracks."""
    d = animated("LINEAR", [0.0, 1.0], [[0, 0, 0], [1, 0, 0]])
    box = d.doc["nodes"][0]["mesh"]
    kids = [
        d.node(root=False, name=n, mesh=box, translation=[2.0 * k, 0.0, 0.0])
        for k, n in enumerate(["box", "box (nodes[3])", "box"], start=1)
    ]
    d.doc["nodes"][0]["children"] = kids
    scene = quiet(load_gltf, d.write(tmp_path / "names.glb"), fps=2)
    names = [o.name for o in scene.objects]
    assert names == ["box", "box (nodes[1])", "box (nodes[3])", "box (nodes[3]) (nodes[3])"]
    targets = [t.target for t in scene.animation.tracks]
    assert len(targets) == len(set(targets)) == 3 * 4


def test_a_refused_animation_key_names_the_file_and_animation(tmp_path, monkeypatch):
    import refnpr.scenes.gltf as gltf

    def refuse(frame, value):
        raise ValueError(f"frame: {frame} refused")

    monkeypatch.setattr(gltf, "Keyframe", refuse)
    d = animated("LINEAR", [0.0, 1.0], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(GltfError, match=r"k\.glb: animations\[0\]: frame: 0 refused"):
        quiet(load_gltf, d.write(tmp_path / "k.glb"))


def test_animation_target_path_must_be_a_string(tmp_path):
    d = animated("LINEAR", [0.0, 1.0], [[0, 0, 0], [1, 0, 0]])
    d.doc["animations"][0]["channels"][0]["target"]["path"] = ["translation"]
    with pytest.raises(
        GltfError,
        match=r"p\.glb: animations\[0\]\.channels\[0\]\.target\.path: \['translation'\]; "
        r"expected translation, rotation, scale or weights",
    ):
        quiet(load_gltf, d.write(tmp_path / "p.glb"))


def test_animation_rotation_slerp_of_parent(tmp_path):
    d = Doc()
    box = d.mesh(trimesh.creation.box())
    child = d.node(root=False, name="kid", mesh=box, translation=[1.0, 0.0, 0.0])
    d.node(name="spin", children=[child])
    tin = d.accessor(np.array([0.0, 1.0]))
    tout = d.accessor(np.array([quat((0, 1, 0), 0), quat((0, 1, 0), 90)]))
    d.doc["animations"] = [
        {
            "samplers": [{"input": tin, "output": tout}],
            "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}],
        }
    ]
    scene = quiet(load_gltf, d.write(tmp_path / "r.glb"), fps=3)
    tr = at_frames(scene, 'object "kid".translation')
    for f in range(4):  # the child orbits: world position = R_y(30 f) (1, 0, 0)
        a = math.radians(30 * f)
        np.testing.assert_allclose(tr[f], [math.cos(a), 0, -math.sin(a)], atol=1e-7)


# -- malformed files ---------------------------------------------------------------------------------


def _base():
    d = Doc()
    d.node(
        name="tri",
        mesh=d.mesh(trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)),
    )
    return d


def _set(path, value):
    def edit(doc):
        obj = doc
        for key in path[:-1]:
            obj = obj[key]
        obj[path[-1]] = value

    return edit


MALFORMED = [
    (
        "accessor count beyond view",
        _set(["accessors", 0, "count"], 1000),
        r"accessors\[0\]\.count: 1000 elements",
    ),
    ("huge count", _set(["accessors", 0, "count"], 2**62), r"accessors\[0\]\.count"),
    (  # all zeros by the spec: nothing in the file bounds it but the cap
        "zero accessor of 300 million elements",
        lambda doc: (
            doc["accessors"].append({"componentType": 5121, "type": "SCALAR", "count": 300_000_000})
            or doc["meshes"][0]["primitives"][0].__setitem__("indices", len(doc["accessors"]) - 1)
        ),
        r"accessors\[\d+\]\.count: 300000000 elements without a bufferView .* would take",
    ),
    (
        "NUL in a buffer URI",
        _set(["buffers", 0, "uri"], "a%00b.bin"),
        r"buffers\[0\]\.uri: 'a%00b\.bin' holds a NUL character",
    ),
    (
        "view beyond buffer",
        _set(["bufferViews", 0, "byteLength"], 10**6),
        r"bufferViews\[0\]: byteOffset",
    ),
    (
        "missing accessor",
        _set(["meshes", 0, "primitives", 0, "attributes", "POSITION"], 9),
        r"meshes\[0\]\.primitives\[0\]\.attributes\.POSITION: 9 is not an index of accessors",
    ),
    (
        "bad component",
        _set(["accessors", 0, "componentType"], 5125),
        r"accessors\[0\]\.componentType: UNSIGNED_INT cannot",
    ),
    (
        "bad stride",
        _set(["bufferViews", 0, "byteStride"], 4),
        r"bufferViews\[0\]\.byteStride: 4 is smaller",
    ),
    (
        "index out of range",
        lambda doc: doc["accessors"][2].update(bufferView=0, byteOffset=12),
        r"accessors\[2\]: index \d+ at position \d+ .* out of range",
    ),
    (
        "cycle",
        _set(["nodes", 0, "children"], [0]),
        r"nodes\[0\]\.children\[0\]: node 0 lists itself",
    ),
    (
        "lines",
        _set(["meshes", 0, "primitives", 0, "mode"], 1),
        r"meshes\[0\]\.primitives\[0\]\.mode: 1 \(LINES\) in nodes\[0\] 'tri'",
    ),
    (
        "bad matrix",
        _set(["nodes", 0, "matrix"], [1, 0, 0, 1] + [0] * 12),
        r"nodes\[0\]\.matrix: the last row",
    ),
    (
        "non-unit rotation",
        _set(["nodes", 0, "rotation"], [0, 0, 0, 2]),
        r"nodes\[0\]\.rotation: .*unit quaternion",
    ),
    (
        "missing buffer",
        _set(["buffers"], []),
        r"bufferViews\[0\]\.buffer: refers to buffers\[0\], but the file has no buffers",
    ),
    ("no version", _set(["asset"], {}), r"asset\.version: missing"),
    (
        "required ext",
        _set(["extensionsRequired"], ["KHR_draco_mesh_compression"]),
        r"extensionsRequired: 'KHR_draco",
    ),
    (
        "sparse without count",
        _set(["accessors", 0, "sparse"], {}),
        r"accessors\[0\]\.sparse\.count: missing",
    ),
    (
        "ortho",
        lambda doc: (
            doc.__setitem__("cameras", [{"type": "orthographic"}]),
            doc["nodes"].append({"camera": 0}),
            doc["scenes"][0]["nodes"].append(1),
        ),
    ),
    (
        "bad light",
        _set(["nodes", 0, "extensions"], {"KHR_lights_punctual": {"light": 3}}),
        r"nodes\[0\]\.extensions\.KHR_lights_punctual\.light: 3 is not a light index",
    ),
    (  # each root loaded once more: objects of the same name (and same tracks if animated)
        "a root listed twice",
        _set(["scenes", 0, "nodes"], [0, 0, 0]),
        r"scenes\[0\]\.nodes\[1\]: node 0 is listed twice \(also at scenes\[0\]\.nodes\[0\]\)",
    ),
    (  # read as floats in [0, 1], the indices were no vertex indices
        "normalized indices",
        lambda doc: doc["accessors"][2].update(normalized=True),
        r"accessors\[2\]\.normalized: true for the indices of meshes\[0\]\.primitives\[0\]"
        r"\.indices; glTF indices are plain unsigned integers",
    ),
    (  # and without NORMAL (flat normals), they indexed an array: an IndexError
        "normalized indices without normals",
        lambda doc: (
            doc["accessors"][2].update(normalized=True),
            doc["meshes"][0]["primitives"][0]["attributes"].pop("NORMAL"),
        ),
        r"accessors\[2\]\.normalized: true for the indices",
    ),
    # a list where a number or a string belongs (unhashable: a dict lookup raised TypeError),
    # and a float where glTF has an integer (4.0 == 4 passed a lookup)
    (
        "material as a list",
        _set(["meshes", 0, "primitives", 0, "material"], [0]),
        r"meshes\[0\]\.primitives\[0\]\.material: refers to materials\[\[0\]\], but the "
        r"file has no materials",
    ),
    (
        "mode as a list",
        _set(["meshes", 0, "primitives", 0, "mode"], [4]),
        r"meshes\[0\]\.primitives\[0\]\.mode: expected an integer in \[0, 6\], got \[4\]",
    ),
    (
        "mode as a float",
        _set(["meshes", 0, "primitives", 0, "mode"], 4.0),
        r"meshes\[0\]\.primitives\[0\]\.mode: expected an integer in \[0, 6\], got 4\.0",
    ),
    (
        "componentType as a list",
        _set(["accessors", 0, "componentType"], [5126]),
        r"accessors\[0\]\.componentType: \[5126\] is not a glTF component type \(an integer",
    ),
    (
        "componentType as a float",
        _set(["accessors", 0, "componentType"], 5126.0),
        r"accessors\[0\]\.componentType: 5126\.0 is not a glTF component type",
    ),
    (
        "type as a list",
        _set(["accessors", 0, "type"], ["VEC3"]),
        r"accessors\[0\]\.type: \['VEC3'\] at meshes\[0\]\.primitives\[0\]\.attributes\.POSITION",
    ),
]


@pytest.mark.parametrize(
    "label, edit, message",
    [m if len(m) == 3 else (*m, r"cameras\[0\]\.type: .*orthographic") for m in MALFORMED],
    ids=[m[0] for m in MALFORMED],
)
def test_malformed(tmp_path, label, edit, message):
    d = _base()
    path = d.write(tmp_path / "bad.gltf", "data")
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(GltfError, match=r"bad\.gltf: " + message):
        quiet(load_gltf, path)


def test_malformed_nan_and_two_parent_cycle(tmp_path):
    d = _base()
    d.doc["accessors"][0]["count"] = 3
    d.blob[0:4] = struct.pack("<f", float("nan"))
    with pytest.raises(ValueError, match=r"nan\.glb: accessors\[0\]: element 0 .* not finite"):
        quiet(load_gltf, d.write(tmp_path / "nan.glb"))
    d = _base()
    d.doc["nodes"] += [{"children": [2]}, {"children": [1]}]
    with pytest.raises(
        ValueError, match=r"cyc\.glb: nodes\[\d\]\.children: the node graph has a cycle"
    ):
        quiet(load_gltf, d.write(tmp_path / "cyc.glb"))


def _camera_yfov(value):
    def edit(doc):
        doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": value, "znear": 0.1}}]
        doc["nodes"].append({"camera": 0, "translation": [0, 0, 3]})
        doc["scenes"][0]["nodes"].append(1)

    return edit


HUGE = [  # (label, edit putting the marker 12345 in, its replacement digits, message)
    (
        "translation",
        _set(["nodes", 0, "translation"], [12345, 0, 0]),
        "1" + "0" * 400,
        r"nodes\[0\]\.translation: expected 3 finite numbers, got \[10+\.\.\. \(an integer "
        r"beyond the float range",
    ),
    (
        "yfov",
        _camera_yfov(12345),
        "1" + "0" * 400,
        r"cameras\[0\]\.perspective\.yfov: expected a positive finite number, got 10+\.\.\. "
        r"\(an integer beyond the float range",
    ),
    (
        "count",
        _set(["accessors", 0, "count"], 12345),
        "1" + "0" * 400,
        r"accessors\[0\]\.count: expected an integer >= 1 and at most 2\^53 - 1",
    ),
    (
        "5000 digits",
        _set(["nodes", 0, "translation"], [12345, 0, 0]),
        "1" + "0" * 5000,
        r"invalid glTF JSON: Exceeds the limit \(\d+ digits\) .* repair or re-export",
    ),
]


@pytest.mark.parametrize("label, edit, digits, message", HUGE, ids=[h[0] for h in HUGE])
def test_integers_beyond_the_float_range_name_the_file_and_field(
    tmp_path, label, edit, digits, message
):
    """JSON integers have no size limit: float() of one with 309 digits or more raises
    OverflowError, and Python refuses to parse one of more than 4300 digits."""
    path = _base().write(tmp_path / "big.gltf", "file")  # no base64: the marker is unique
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc).replace("12345", digits))
    with pytest.raises(GltfError, match=r"big\.gltf: " + message):
        quiet(load_gltf, path)


def test_uris_outside_directory_refused(tmp_path):
    sub = tmp_path / "sub"
    sub.mkdir()
    d = _base()
    d.write(sub / "model.gltf", "bin")
    (sub / "loop.bin").symlink_to("loop.bin")
    for uri, what in [
        ("../secret.bin", "outside the directory"),
        ("/etc/passwd", "absolute"),
        ("http://example.com/x.bin", "not a relative file"),
        ("nothere.bin", "not found"),
        ("loop.bin", "'loop.bin' cannot be resolved"),  # a symbolic link loop
    ]:
        doc = json.loads((sub / "model.gltf").read_text())
        doc["buffers"][0]["uri"] = uri
        (sub / "model.gltf").write_text(json.dumps(doc))
        with pytest.raises(ValueError, match=r"model\.gltf: buffers\[0\]\.uri: .*" + what):
            load_gltf(sub / "model.gltf")


def test_truncated_glb_and_huge_byte_length(tmp_path):
    path = _base().write(tmp_path / "t.glb")
    raw = path.read_bytes()
    path.write_bytes(raw[:-8])
    with pytest.raises(ValueError, match=r"t\.glb: GLB header: declares"):
        load_gltf(path)
    d = _base()
    path = d.write(tmp_path / "h.gltf", "bin")
    doc = json.loads(path.read_text())
    doc["buffers"][0]["byteLength"] = 10**6
    path.write_text(json.dumps(doc))
    with pytest.raises(
        ValueError,
        match=r"h\.gltf: buffers\[0\]\.uri: buffer file 'model\.bin' has \d+ bytes, but "
        r"byteLength declares 1000000",
    ):
        load_gltf(path)
    doc["buffers"][0]["byteLength"] = 2**40  # beyond the cap: refused before the file is read
    path.write_text(json.dumps(doc))
    with pytest.raises(
        ValueError, match=r"h\.gltf: buffers\[0\]\.byteLength: 1099511627776 bytes, more than"
    ):
        load_gltf(path)


def test_buffers_are_capped_one_by_one_and_together(tmp_path, monkeypatch):
    """A buffer file is read up to its byteLength: MAX_FILE_BYTES caps each byteLength, and
    the buffers of a file together, before anything is read (not only the .gltf's size)."""
    import refnpr.scenes.gltf as gltf

    d = _base()
    d.blob += bytes(1200 - len(d.blob))  # 1200 bytes of buffer, a .gltf of a few hundred
    path = d.write(tmp_path / "cap.gltf", "bin")
    assert quiet(load_gltf, path).objects[0].mesh.n_faces == 1
    monkeypatch.setattr(gltf, "MAX_FILE_BYTES", 1000)
    with pytest.raises(
        GltfError,
        match=r"cap\.gltf: buffers\[0\]\.byteLength: 1200 bytes, more than the 1000 bytes "
        r"refnpr reads of a file's buffers",
    ):
        quiet(load_gltf, path)
    # two buffers of 600 bytes each (the normals in the second): each fits, not both
    monkeypatch.setattr(gltf, "MAX_FILE_BYTES", 1100)
    doc = json.loads(path.read_text())
    blob = (tmp_path / "model.bin").read_bytes()[:600]
    (tmp_path / "model.bin").write_bytes(blob)
    (tmp_path / "second.bin").write_bytes(blob)
    doc["buffers"] = [
        {"byteLength": 600, "uri": "model.bin"},
        {"byteLength": 600, "uri": "second.bin"},
    ]
    doc["bufferViews"][1]["buffer"] = 1
    path.write_text(json.dumps(doc))
    with pytest.raises(
        GltfError,
        match=r"cap\.gltf: buffers\[1\]\.byteLength: 600 bytes \(with the 600 bytes of the "
        r"buffers read before it, 1200\), more than the 1100 bytes",
    ):
        quiet(load_gltf, path)


def test_a_data_uri_longer_than_its_byte_length_gives_its_first_bytes(tmp_path):
    """glTF: a buffer's resource must hold at least byteLength bytes, and may hold more."""
    path = _base().write(tmp_path / "d.gltf", "data")
    whole = quiet(load_gltf, path)
    doc = json.loads(path.read_text())
    head, payload = doc["buffers"][0]["uri"].split(",")
    extra = base64.b64encode(base64.b64decode(payload) + bytes(48)).decode()
    doc["buffers"][0]["uri"] = f"{head},{extra}"  # 48 bytes past byteLength
    path.write_text(json.dumps(doc))
    longer = quiet(load_gltf, path)
    np.testing.assert_array_equal(longer.objects[0].mesh.positions, whole.objects[0].mesh.positions)
    np.testing.assert_array_equal(longer.objects[0].mesh.faces, whole.objects[0].mesh.faces)


def test_nodes_and_the_geometry_they_place_are_capped(tmp_path, monkeypatch):
    """Each node that places a mesh makes an object with its own world mesh: a small file could
    place one large mesh thousands of times. The node count and the triangles and vertices of
    all objects together are capped before any object is built."""
    import refnpr.scenes.gltf as gltf

    d = _base()
    for k in range(3):
        d.node(name=f"copy{k}", mesh=d.doc["nodes"][0]["mesh"], translation=[k + 1.0, 0.0, 0.0])
    path = d.write(tmp_path / "inst.glb")
    assert len(quiet(load_gltf, path).objects) == 4  # 4 triangles, 12 vertices
    monkeypatch.setattr(gltf, "MAX_NODES", 3)
    with pytest.raises(
        GltfError, match=r"inst\.glb: nodes: the file has 4 nodes, more than the 3 refnpr reads"
    ):
        quiet(load_gltf, path)
    monkeypatch.setattr(gltf, "MAX_NODES", 4)
    monkeypatch.setattr(gltf, "MAX_PLACED_TRIANGLES", 3)
    with pytest.raises(
        GltfError,
        match=r"inst\.glb: the scene's 4 objects have 4 triangles, more than the 3 refnpr "
        r"renders in one scene \(3 of the objects place a mesh that another one places too\)",
    ):
        quiet(load_gltf, path)
    monkeypatch.setattr(gltf, "MAX_PLACED_TRIANGLES", 4)
    monkeypatch.setattr(gltf, "MAX_PLACED_VERTICES", 11)
    with pytest.raises(GltfError, match=r"4 objects have 12 vertices, more than the 11 refnpr"):
        quiet(load_gltf, path)


def test_animation_work_is_bounded_by_frames_times_nodes(tmp_path, monkeypatch):
    """Each frame evaluates every node's world matrix: frames x (nodes + animated nodes) is
    capped before any frame is evaluated (a small file could otherwise ask for hours)."""
    import refnpr.scenes.gltf as gltf

    path = animated("LINEAR", [0.0, 10.0], [[0, 0, 0], [1, 0, 0]]).write(tmp_path / "a.glb")
    assert quiet(load_gltf, path, fps=4).frames == 41  # 41 frames x (1 node + 1 animated)
    monkeypatch.setattr(gltf, "MAX_ANIMATION_WORK", 81)
    with pytest.raises(
        GltfError, match=r"animations\[0\]: 41 frames x 1 nodes .* node evaluations"
    ):
        quiet(load_gltf, path, fps=4)


# -- sparse accessors --------------------------------------------------------------------------------


def sparse_triangle(base=True, index_type="<u2", indices=(1,), values=((2.0, 0.5, 0.0),)):
    """A triangle whose POSITION accessor has a sparse override of ``indices`` by ``values``
    (over the dense base [[0,0,0],[1,0,0],[0,1,0]], or over zeros without ``base``)."""
    d = Doc()
    dense = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    if base:
        pos = d.accessor(dense)
    else:
        d.doc["accessors"].append({"componentType": 5126, "count": 3, "type": "VEC3"})
        pos = len(d.doc["accessors"]) - 1
    ctype = {"<u1": 5121, "<u2": 5123, "<u4": 5125}[index_type]
    d.doc["accessors"][pos]["sparse"] = {
        "count": len(indices),
        "indices": {"bufferView": d.view(indices, index_type), "componentType": ctype},
        "values": {"bufferView": d.view(values, "<f4")},
    }
    d.doc["meshes"].append({"primitives": [{"attributes": {"POSITION": pos}}]})
    d.node(name="tri", mesh=0, translation=[0.0, 0.0, -3.0])
    return d, dense if base else np.zeros((3, 3))


@pytest.mark.parametrize("index_type", ["<u1", "<u2", "<u4"])
def test_sparse_accessor_moves_the_given_vertices(tmp_path, index_type):
    """glTF 2.0 sec. 3.6.2.3: the base, with element indices[j] replaced by values[j]."""
    for base, indices, values in [
        (True, (1,), ((2.0, 0.5, 0.0),)),
        (True, (0, 2), ((-1.0, 0.0, 0.0), (0.0, 3.0, 0.0))),
        (False, (1, 2), ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))),  # over zeros (no bufferView)
    ]:
        d, want = sparse_triangle(base, index_type, indices, values)
        want = want.copy()
        want[list(indices)] = values
        scene = quiet(load_gltf, d.write(tmp_path / "s.glb"))
        world = scene.objects[0].world_mesh().positions
        # flat normals unshare the vertices in face order (0, 1, 2): one triangle
        np.testing.assert_array_equal(world, want + [0.0, 0.0, -3.0])


def _sparse_edit(*path, value=None, drop=False):
    def edit(doc):
        obj = doc["accessors"][0]["sparse"]
        for key in path[:-1]:
            obj = obj[key]
        if drop:
            del obj[path[-1]]
        else:
            obj[path[-1]] = value

    return edit


SPARSE_BAD = [
    ("zero count", _sparse_edit("count", value=0), r"sparse\.count: expected an integer >= 1"),
    (
        "count over accessor",
        _sparse_edit("count", value=4),
        r"sparse\.count: 4 substitutions for an accessor of 3 elements",
    ),
    ("not an object", lambda doc: doc["accessors"][0].update(sparse=[1]), r"sparse: expected"),
    ("no values", _sparse_edit("values", drop=True), r"sparse\.values: missing"),
    (
        "index type",
        _sparse_edit("indices", "componentType", value=5126),
        r"sparse\.indices\.componentType: 5126; expected 5121",
    ),
    (
        "index type as a float",
        _sparse_edit("indices", "componentType", value=5123.0),
        r"sparse\.indices\.componentType: 5123\.0; expected 5121",
    ),
    (
        "indices beyond view",
        _sparse_edit("indices", "byteOffset", value=4),
        r"sparse\.indices\.byteOffset: 2 elements of 2 bytes at byteOffset 4 need 8 bytes, "
        r"beyond the end of bufferViews\[1\] \(4 bytes\)",
    ),
    (
        "count beyond indices view",
        _sparse_edit("count", value=3),
        r"sparse\.indices\.byteOffset: 3 elements of 2 bytes at byteOffset 0 need 6 bytes",
    ),
    (
        "values beyond view",
        _sparse_edit("values", "byteOffset", value=12),
        r"sparse\.values\.byteOffset: 2 elements of 12 bytes at byteOffset 12 need 36 bytes, "
        r"beyond the end of bufferViews\[2\] \(24 bytes\)",
    ),
    (
        "misaligned",
        _sparse_edit("indices", "byteOffset", value=1),
        r"sparse\.indices\.byteOffset: 1 is not a multiple of the component size 2",
    ),
    (
        "stride",
        lambda doc: doc["bufferViews"][2].update(byteStride=12),
        r"sparse\.values\.bufferView: bufferViews\[2\] has a byteStride \(12\)",
    ),
    (
        "view index",
        _sparse_edit("values", "bufferView", value=7),
        r"sparse\.values\.bufferView: 7 is not an index of bufferViews",
    ),
]


@pytest.mark.parametrize("label, edit, message", SPARSE_BAD, ids=[m[0] for m in SPARSE_BAD])
def test_sparse_malformed(tmp_path, label, edit, message):
    d, _ = sparse_triangle(True, "<u2", (0, 2), ((-1.0, 0.0, 0.0), (0.0, 3.0, 0.0)))
    edit(d.doc)
    with pytest.raises(GltfError, match=r"bad\.glb: accessors\[0\]\." + message):
        quiet(load_gltf, d.write(tmp_path / "bad.glb"))


@pytest.mark.parametrize(
    "indices, message",
    [
        ((2, 1), r"index 1 at position 1 is not greater than the one before it \(2\)"),
        ((1, 1), r"index 1 at position 1 is not greater"),
        ((0, 3), r"index 3 at position 1 is out of range for the accessor's 3 elements"),
    ],
)
def test_sparse_indices_increasing_and_in_range(tmp_path, indices, message):
    d, _ = sparse_triangle(True, "<u1", indices, ((1.0, 1.0, 0.0), (2.0, 2.0, 0.0)))
    with pytest.raises(GltfError, match=r"accessors\[0\]\.sparse\.indices: " + message):
        quiet(load_gltf, d.write(tmp_path / "bad.glb"))


def test_sparse_values_must_be_finite(tmp_path):
    d, _ = sparse_triangle(True, "<u2", (1,), ((float("nan"), 0.0, 0.0),))
    with pytest.raises(GltfError, match=r"accessors\[0\]: element 1 .* not finite"):
        quiet(load_gltf, d.write(tmp_path / "nan.glb"))
