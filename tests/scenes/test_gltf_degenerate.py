"""glTF files that place nothing drawable or give a camera or light no direction: triangles of
zero area, zero and huge node scales (static and animated), lights that no node places, and a
TOML scene over such a file. Each is refused (or noted) with the file, the glTF path or TOML
table of the cause and a fix, and without numpy warnings on the way.

The files are written here by hand: one triangle, a camera, optional lights and animations.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from refnpr.scenes import load_mesh, load_scene
from refnpr.scenes.gltf import GltfError, GltfWarning, load_gltf

from ._gltf_write import write_gltf

TRIANGLE = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]


class Tri:
    """A glTF document of one triangle node ('tri', nodes[0]) and a camera node ('cam',
    nodes[1], at z = 3); more nodes, lights and animations by the methods."""

    def __init__(self, positions=TRIANGLE, tri=None, cam=None):
        self.blob = bytearray()
        self.doc = {
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [
                {"name": "tri", "mesh": 0, **(tri or {})},
                {"name": "cam", "camera": 0, "translation": [0.0, 0.0, 3.0], **(cam or {})},
            ],
            "cameras": [
                {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100}}
            ],
            "accessors": [],
            "bufferViews": [],
        }
        position = self.accessor(positions)
        self.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": position}}]}]

    def accessor(self, values) -> int:
        a = np.asarray(values, dtype="<f4")
        views, accessors = self.doc["bufferViews"], self.doc["accessors"]
        views.append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": a.nbytes})
        self.blob += a.tobytes()
        kind = "SCALAR" if a.ndim == 1 else f"VEC{a.shape[1]}"
        accessors.append(
            {"bufferView": len(views) - 1, "componentType": 5126, "count": len(a), "type": kind}
        )
        return len(accessors) - 1

    def node(self, parent=None, **fields) -> int:
        self.doc["nodes"].append(fields)
        i = len(self.doc["nodes"]) - 1
        if parent is None:
            self.doc["scenes"][0]["nodes"].append(i)
        else:
            self.doc["nodes"][parent].setdefault("children", []).append(i)
        return i

    def lights(self, *lights) -> Tri:
        self.doc["extensions"] = {"KHR_lights_punctual": {"lights": list(lights)}}
        return self

    def animate(self, node, path, times, values, interpolation="LINEAR") -> Tri:
        sampler = {
            "input": self.accessor(times),
            "output": self.accessor(values),
            "interpolation": interpolation,
        }
        self.doc["animations"] = [
            {
                "samplers": [sampler],
                "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
            }
        ]
        return self

    def write(self, path):
        return write_gltf(self.doc, bytes(self.blob), path, "data")


def quiet(fn, *args, **kwargs):
    """``fn(...)`` with refnpr's notes silenced and any numpy RuntimeWarning an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GltfWarning)
        warnings.simplefilter("error", RuntimeWarning)
        return fn(*args, **kwargs)


# -- geometry ----------------------------------------------------------------------------------------


def test_a_primitive_of_zero_area_triangles_is_refused_as_a_mesh_file_is(tmp_path):
    flat = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]
    with pytest.raises(
        GltfError,
        match=r"/flat\.gltf: meshes\[0\]\.primitives\[0\] \(the mesh of nodes\[0\] 'tri'\): all 1 "
        r"triangles have zero area \(nothing to draw\); remove the primitive",
    ):
        quiet(load_gltf, Tri(flat).write(tmp_path / "flat.gltf"))
    # the same geometry as an OBJ file: the same words
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n")
    with pytest.raises(ValueError, match=r"all 1 triangles have zero area \(nothing to draw\)"):
        load_mesh(tmp_path / "flat.obj")
    # one triangle with an area among flat ones is drawn
    scene = quiet(load_gltf, Tri(flat + TRIANGLE).write(tmp_path / "half.gltf"))
    assert scene.objects[0].mesh.faces.shape == (2, 3)


@pytest.mark.parametrize(
    "tri, field, magnitude",
    [
        ({"scale": [1e300, 1e300, 1e300]}, "scale", "1e\\+300"),
        ({"translation": [1e200, 0.0, 0.0]}, "translation", "1e\\+200"),
    ],
)
def test_a_node_transform_beyond_the_coordinate_limit_names_the_node_field(
    tmp_path, tri, field, magnitude
):
    with pytest.raises(
        GltfError,
        match=rf"/big\.gltf: nodes\[0\]\.{field}: object 'tri' \(meshes\[0\]\.primitives\[0\]\), "
        rf"placed by the world transform of nodes\[0\] 'tri', has a vertex coordinate of "
        rf"magnitude {magnitude} .*rescale the model",
    ):
        quiet(load_gltf, Tri(tri=tri).write(tmp_path / "big.gltf"))


def test_a_parent_scale_beyond_the_limit_is_named_on_the_parent(tmp_path):
    d = Tri()
    d.doc["scenes"][0]["nodes"].remove(0)
    d.node(name="world", scale=[1e20, 1e20, 1e20], children=[0])
    with pytest.raises(GltfError, match=r"/big\.gltf: nodes\[2\]\.scale: object 'tri'"):
        quiet(load_gltf, d.write(tmp_path / "big.gltf"))


# -- cameras and lights ------------------------------------------------------------------------------


def test_a_camera_node_of_zero_scale_names_its_scale(tmp_path):
    d = Tri(cam={"scale": [0.0, 0.0, 0.0]})
    with pytest.raises(
        GltfError,
        match=r"/cam\.gltf: nodes\[1\]\.scale: the camera of nodes\[1\] 'cam' has a zero scale: "
        r".*no direction; make every component of nodes\[1\]\.scale non-zero",
    ):
        quiet(load_gltf, d.write(tmp_path / "cam.gltf"))


def test_a_directional_light_of_zero_scale_names_the_scale_that_is_zero(tmp_path):
    sun = {"type": "directional", "name": "sun"}
    d = Tri().lights(sun)
    d.node(name="lamp", scale=[0.0, 0.0, 0.0], extensions={"KHR_lights_punctual": {"light": 0}})
    with pytest.raises(
        GltfError,
        match=r"/sun\.gltf: nodes\[2\]\.scale: directional light 'sun' of nodes\[2\] 'lamp' has "
        r"a zero scale",
    ):
        quiet(load_gltf, d.write(tmp_path / "sun.gltf"))
    # under a parent of zero scale: the parent's scale is named
    d = Tri().lights(sun)
    rig = d.node(name="rig", scale=[1.0, 1.0, 0.0])
    d.node(parent=rig, name="lamp", extensions={"KHR_lights_punctual": {"light": 0}})
    with pytest.raises(GltfError, match=r"/rig\.gltf: nodes\[2\]\.scale: directional light"):
        quiet(load_gltf, d.write(tmp_path / "rig.gltf"))
    # a point light has a position whatever its scale
    d = Tri().lights({"type": "point", "name": "bulb"})
    d.node(
        translation=[0.0, 2.0, 0.0],
        scale=[0.0] * 3,
        extensions={"KHR_lights_punctual": {"light": 0}},
    )
    scene = quiet(load_gltf, d.write(tmp_path / "bulb.gltf"))
    assert scene.lights[0].position == (0.0, 2.0, 0.0)


def test_lights_that_no_node_places_are_named_in_the_headlight_note(tmp_path):
    path = Tri().lights({"type": "directional", "name": "sun"}).write(tmp_path / "unused.gltf")
    with pytest.warns(
        GltfWarning,
        match=r"unused\.gltf: KHR_lights_punctual defines 1 light\(s\) \('sun'\) but no node of "
        r"the scene places one .*; refnpr adds a headlight",
    ):
        scene = load_gltf(path)
    assert [lt.kind for lt in scene.lights] == ["directional"]
    with pytest.warns(GltfWarning, match=r"none\.gltf: no KHR_lights_punctual lights; refnpr"):
        load_gltf(Tri().write(tmp_path / "none.gltf"))


# -- animations --------------------------------------------------------------------------------------


def test_an_animated_zero_scale_says_how_to_hide_an_object(tmp_path):
    ones, zeros = [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]
    blink = Tri().animate(0, "scale", [0.0, 1.0, 2.0], [ones, zeros, ones], "STEP")
    with pytest.raises(
        GltfError,
        match=r"/blink\.gltf: animations\[0\]: nodes\[0\]\.scale of node 'tri' reaches zero at "
        r"time 1 s \(frame 24\); refnpr cannot hide an object on some frames only .*animate the "
        r"scale to a tiny non-zero value instead",
    ):
        quiet(load_gltf, blink.write(tmp_path / "blink.gltf"))
    # what the message advises: a scale far below a pixel
    tiny = [1e-6] * 3
    blink = Tri().animate(0, "scale", [0.0, 1.0, 2.0], [ones, tiny, ones], "STEP")
    scene = quiet(load_gltf, blink.write(tmp_path / "tiny.gltf"))
    np.testing.assert_allclose(np.diag(scene.at(24).objects[0].transform)[:3], tiny, rtol=1e-6)
    np.testing.assert_allclose(np.diag(scene.at(48).objects[0].transform)[:3], ones)


def test_an_object_of_zero_rest_scale_that_the_animation_shows_is_refused(tmp_path):
    """A node scaled 0 at rest and scaled up by the animation (an "appear" effect) would be
    left out of every frame; the file is refused with the fix instead."""

    def appear(values, name):
        d = Tri()
        d.node(mesh=0, name="late", scale=[0.0, 0.0, 0.0])  # nodes[2]
        return d.animate(2, "scale", [0.0, 1.0], values).write(tmp_path / name)

    with pytest.raises(
        GltfError,
        match=r"/appear\.gltf: nodes\[2\]\.scale: node 'late' has a zero scale at rest, and "
        r"animations\[0\] gives it a non-zero one at time 0\.0416667 s \(frame 1\).*give "
        r"nodes\[2\]\.scale a tiny non-zero value instead",
    ):
        quiet(load_gltf, appear([[0.0] * 3, [1.0] * 3], "appear.gltf"))
    only = Tri(tri={"scale": [0.0, 0.0, 0.0]}).animate(
        0, "scale", [0.0, 1.0], [[0.0] * 3, [1.0] * 3]
    )
    with pytest.raises(
        GltfError, match=r"every mesh node has a zero scale; .* needs a tiny non-zero rest scale"
    ):
        quiet(load_gltf, only.write(tmp_path / "only.gltf"))
    # scaled, but never away from zero: it stays out, as a static zero scale does
    scene = quiet(load_gltf, appear([[0.0] * 3, [0.0] * 3], "never.gltf"))
    assert [o.name for o in scene.objects] == ["tri"]


def test_an_animation_that_carries_an_object_beyond_the_coordinate_limit_names_the_frame(
    tmp_path,
):
    """Checked when the file is read (the object's box against 1e15), not when that frame is
    rendered after the frames before it were written."""
    grow = Tri().animate(0, "scale", [0.0, 1.0], [[1.0] * 3, [1e20] * 3])
    with pytest.raises(
        GltfError,
        match=r"/grow\.gltf: animations\[0\]: object 'tri' at time 0\.0416667 s \(frame 1\) has a "
        r"vertex coordinate of magnitude 4\.17e\+18 .*above the limit 1e\+15",
    ):
        quiet(load_gltf, grow.write(tmp_path / "grow.gltf"))
    within = Tri().animate(0, "translation", [0.0, 1.0], [[0.0] * 3, [9e14, 0.0, 0.0]])
    scene = quiet(load_gltf, within.write(tmp_path / "within.gltf"))  # 9e14 + 1: inside
    assert scene.at(24).objects[0].transform[0, 3] == pytest.approx(9e14, rel=1e-7)  # float32 keys


def test_a_camera_animated_to_zero_scale_names_the_time(tmp_path):
    d = Tri().animate(1, "scale", [0.0, 1.0], [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]])
    with pytest.raises(
        GltfError,
        match=r"/cs\.gltf: nodes\[1\]\.scale: the camera of nodes\[1\] 'cam' has a "
        r"zero scale at time 1 s",
    ):
        quiet(load_gltf, d.write(tmp_path / "cs.gltf"))


# -- a TOML scene over the file ----------------------------------------------------------------------


def moving_camera(tmp_path):
    """A file whose camera (at rest at z = 3) moves from z = 0 to z = -10 over 1 s."""
    d = Tri().animate(1, "translation", [0.0, 1.0], [[0.0, 0.0, 0.0], [0.0, 0.0, -10.0]])
    return d.write(tmp_path / "cam.gltf")


def test_a_camera_table_of_lens_keys_keeps_the_file_camera_animation(tmp_path):
    moving_camera(tmp_path)
    (tmp_path / "plain.toml").write_text('gltf = "cam.gltf"\n')
    (tmp_path / "lens.toml").write_text('gltf = "cam.gltf"\n[camera]\nfov_y = 30.0\nnear = 0.5\n')
    plain, lens = (
        quiet(load_scene, tmp_path / "plain.toml"),
        quiet(load_scene, tmp_path / "lens.toml"),
    )
    assert lens.frames == plain.frames == 25
    for f in (0, 12, 24):
        np.testing.assert_array_equal(lens.at(f).camera.eye, plain.at(f).camera.eye)
        np.testing.assert_array_equal(lens.at(f).camera.target, plain.at(f).camera.target)
        assert (lens.at(f).camera.fov_y, lens.at(f).camera.near) == (30.0, 0.5)
        assert lens.at(f).lights == plain.at(f).lights  # the headlight follows the camera
    assert lens.at(0).camera.eye.tolist() == [0.0, 0.0, 0.0]
    assert lens.at(24).camera.eye.tolist() == [0.0, 0.0, -10.0]
    # a table that sets the pose replaces the moving pose
    (tmp_path / "posed.toml").write_text('gltf = "cam.gltf"\n[camera]\neye = [0.0, 0.0, 5.0]\n')
    posed = quiet(load_scene, tmp_path / "posed.toml")
    assert posed.at(0).camera.eye.tolist() == posed.at(24).camera.eye.tolist() == [0, 0, 5]


def test_an_object_table_named_like_an_animated_file_object_names_the_table(tmp_path, monkeypatch):
    Tri().animate(0, "translation", [0.0, 1.0], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]).write(
        tmp_path / "a.gltf"
    )
    (tmp_path / "s.toml").write_text(
        'gltf = "a.gltf"\n[[object]]\nname = "tri"\nmesh = "icosphere"\n'
    )
    monkeypatch.chdir(tmp_path)
    with pytest.raises(
        ValueError,
        match=r"^s\.toml: \[\[object\]\] #1 'tri': name: 'tri' is also the name of an object of "
        r"'a\.gltf' that its animation moves \(track 'object \"tri\"\.translation'\); .*give "
        r"this \[\[object\]\] another name",
    ):
        quiet(load_scene, "s.toml")
    # another name: both objects, the file's one animated
    (tmp_path / "s.toml").write_text(
        'gltf = "a.gltf"\n[[object]]\nname = "ball"\nmesh = "icosphere"\n'
    )
    scene = quiet(load_scene, "s.toml")
    assert [o.name for o in scene.objects] == ["tri", "ball"]
    assert scene.at(24).objects[0].transform[0, 3] == 1.0
