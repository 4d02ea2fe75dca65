"""Scene files: built-in scenes, mesh specs, a full round trip, and error messages."""

import os
import tomllib

import numpy as np
import pytest
import trimesh

from refnpr.scenes import (
    Light,
    SceneFileError,
    list_scenes,
    load_scene,
    mesh_from_spec,
    parse_scene,
    teapot,
)

BUILT_IN = {"default", "icosphere", "room", "sphere", "teapot", "terrain", "torus_knot", "vase"}
BACKDROPS = {"floor", "room", "terrain"}  # objects that may extend beyond the frame


def test_list_scenes():
    scenes = list_scenes()
    assert BUILT_IN <= set(scenes)  # styles may add their own figure scenes
    for name, text in scenes.items():
        assert text and "\n" not in text, name


def _ndc(scene, mesh, width, height):
    p = (
        np.c_[mesh.positions, np.ones(mesh.n_vertices)]
        @ scene.camera.view_projection(width, height).T
    )
    return p[:, :3] / p[:, 3:], p[:, 3]


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_builtin_scene_loads_and_frames(name):
    scene = load_scene(name)
    assert scene.name == name
    assert scene.objects and scene.lights
    for light in scene.lights:
        assert np.linalg.norm(light.direction) == pytest.approx(1.0)
    for obj, mesh in zip(scene.objects, scene.world_meshes(), strict=True):
        assert mesh.uv is not None and mesh.normals is not None
        if obj.name in BACKDROPS:
            continue
        # the default scene is framed for the command's 16:9 default size (and still fits 4:3)
        sizes = ((768, 432), (640, 480)) if name == "default" else ((512, 512), (640, 480))
        for width, height in sizes:
            ndc, w = _ndc(scene, mesh, width, height)
            assert np.all(w > scene.camera.near), (name, obj.name)  # in front of the camera
            assert np.abs(ndc[:, :2]).max() < 0.98, (name, obj.name, width, height)  # in frame
            assert np.abs(ndc[:, :2]).max() > 0.3, (name, obj.name)  # and not tiny


def test_default_is_the_teapot_in_a_paper_style_lit_from_upper_right():
    a, b = load_scene("default"), load_scene("teapot")
    assert a.lights == b.lights and [o.name for o in b.objects] == ["teapot", "floor"]
    assert [o.name for o in a.objects] == ["teapot"]
    assert np.array_equal(a.objects[0].mesh.positions, teapot(10).positions)
    # a paper's style with contours, so that `refnpr render` shows what refnpr is for
    assert a.style["name"] in {"threshold", "halftone", "xtoon", "tamiss", "tam"}
    assert a.style["contours"]["width"] > 0
    assert b.style is None or not b.style  # the teapot scene leaves the style to the caller
    view = a.camera.view_matrix()[:3, :3]
    light_eye = view @ np.array(a.lights[0].direction)
    assert light_eye[0] > 0.3 and light_eye[1] > 0.3  # right and up in the image


def test_mesh_from_spec(tmp_path):
    m = mesh_from_spec({"mesh": "torus", "R": 2.0, "r": 0.5, "n_u": 8, "n_v": 6})
    assert m.name == "torus" and m.n_faces == 2 * 8 * 6
    box = trimesh.creation.box()
    box.export(tmp_path / "box.stl")
    loaded = mesh_from_spec({"path": "box.stl", "uv_projection": "box"}, base_dir=tmp_path)
    assert loaded.n_faces == 12 and loaded.uv is not None
    projected = mesh_from_spec({"mesh": "icosphere", "subdivisions": 1, "uv_projection": "planar"})
    assert projected.uv.max() == 1.0
    with pytest.raises(ValueError, match="mesh: unknown built-in mesh 'cube'; valid names: teapot"):
        mesh_from_spec({"mesh": "cube"})
    with pytest.raises(
        ValueError, match="levels: unknown parameter of mesh 'teapot'; valid parameters: level"
    ):
        mesh_from_spec({"mesh": "teapot", "levels": 3})
    with pytest.raises(ValueError, match="mesh/path: give exactly one .* got both"):
        mesh_from_spec({"mesh": "teapot", "path": "x.obj"})
    with pytest.raises(ValueError, match="mesh/path: give exactly one .* got neither"):
        mesh_from_spec({"level": 3})
    with pytest.raises(ValueError, match="level: unknown key for a mesh file"):
        mesh_from_spec({"path": "box.stl", "level": 3}, base_dir=tmp_path)


FULL = """
name = "trip"
description = "every feature once"
ambient = 0.5
background = [0.1, 0.2, 0.3]

[camera]
eye = [1.0, 2.0, 9.0]
target = [0.0, 0.5, 0.0]
up = [0, 1, 0]
fov_y = 33
near = 0.25
far = 60.0

[style]
name = "toon"
n = 3

[[light]]
direction = [0, 2, 0]
color = 0.9

[[light]]
kind = "point"
position = [3, 4, 5]
color = [1.0, 0.5, 0.25]

[[object]]
name = "pot"
mesh = "teapot"
level = 3
transform = { translate = [1, 0, -1], rotate_deg = [0, 90, 0], scale = 0.5 }

[object.material]
diffuse = [0.2, 0.4, 0.6]
shininess = 12
texture = "tex/paper.png"
uv_scale = 2

[[object]]
path = "ball.obj"
uv_projection = "spherical"
transform = { matrix = [[1, 0, 0, 0], [0, 1, 0, 2], [0, 0, 1, 0], [0, 0, 0, 1]] }

[object.material]
texture = "brick"
"""


@pytest.fixture
def scene_dir(tmp_path):
    (tmp_path / "tex").mkdir()
    (tmp_path / "tex" / "paper.png").write_bytes(b"not read by the loader")
    trimesh.creation.icosphere(1).export(tmp_path / "ball.obj")
    (tmp_path / "trip.toml").write_text(FULL)
    return tmp_path


def test_round_trip(scene_dir):
    scene = load_scene(scene_dir / "trip.toml")
    assert scene.name == "trip" and scene.ambient == (0.5, 0.5, 0.5)
    assert scene.background == (0.1, 0.2, 0.3, 1.0)
    cam = scene.camera
    assert cam.eye.tolist() == [1.0, 2.0, 9.0] and cam.target.tolist() == [0.0, 0.5, 0.0]
    assert (cam.fov_y, cam.near, cam.far) == (33.0, 0.25, 60.0)
    assert scene.style == {"name": "toon", "n": 3}
    assert scene.lights == (
        Light(direction=(0, 1, 0), color=(0.9, 0.9, 0.9)),
        Light(kind="point", position=(3, 4, 5), color=(1.0, 0.5, 0.25)),
    )
    pot, ball = scene.objects
    assert pot.name == "pot" and ball.name == "ball"
    assert pot.material.diffuse == (0.2, 0.4, 0.6) and pot.material.shininess == 12.0
    assert pot.material.texture == str(scene_dir / "tex" / "paper.png")
    assert pot.material.uv_scale == (2.0, 2.0)
    assert ball.material.texture == "brick"  # a built-in name stays a name
    # transform: scale 0.5, rotate +90 about y (x -> -z), translate
    assert np.allclose(pot.transform @ [2, 0, 0, 1], [1, 0, -2, 1])
    world = scene.world_meshes()
    assert np.allclose(
        world[0].positions, pot.mesh.positions @ pot.transform[:3, :3].T + [1, 0, -1]
    )
    assert np.allclose(world[1].positions[:, 1].mean(), 2.0, atol=1e-9)
    assert ball.mesh.uv is not None
    # the same dict through parse_scene gives the same scene
    again = parse_scene(tomllib.loads(FULL), scene_dir, source="trip.toml")
    assert again.lights == scene.lights and again.style == scene.style
    assert np.array_equal(again.objects[0].transform, pot.transform)
    assert np.array_equal(again.objects[1].mesh.positions, ball.mesh.positions)


def test_minimal_scene_defaults(tmp_path):
    path = tmp_path / "mini.toml"
    path.write_text(
        '[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n[[object]]\nmesh = "icosphere"\n'
    )
    scene = load_scene(str(path))
    assert scene.name == "mini" and scene.lights == (Light(),) and scene.style == {}
    assert scene.objects[0].name == "icosphere" and scene.objects[0].material.diffuse == (0.8,) * 3


@pytest.mark.parametrize(
    "old, new, match",
    [
        (
            'name = "trip"',
            'nme = "trip"',
            r"trip.toml: top level: unknown key 'nme'; valid keys: name",
        ),
        ("fov_y = 33", "fovy = 33", r"trip.toml: \[camera\]: unknown key 'fovy'"),
        (
            "fov_y = 33",
            "fov_y = 200",
            r"trip.toml: \[camera\]: fov_y: expected degrees in \(0, 180\)",
        ),
        ("eye = [1.0, 2.0, 9.0]", "", r"trip.toml: \[camera\]: missing key 'eye'"),
        ("[camera]", "[kamera]", r"trip.toml: top level: unknown key 'kamera'"),
        (
            "level = 3",
            'level = "ten"',
            r"\[\[object\]\] #1 'pot': level: expected an integer, got str",
        ),
        (
            "level = 3",
            "lvl = 3",
            r"\[\[object\]\] #1 'pot': lvl: unknown parameter of mesh 'teapot'",
        ),
        ('mesh = "teapot"', 'mesh = "kettle"', r"#1 'pot': mesh: unknown built-in mesh 'kettle'"),
        ("shininess = 12", "shine = 12", r"#1 'pot': material: unknown key 'shine'; valid keys"),
        ("shininess = 12", "shininess = -1", r"#1 'pot': material: shininess: expected a positive"),
        ("scale = 0.5", "zoom = 0.5", r"#1 'pot': transform: unknown key 'zoom'"),
        ("scale = 0.5", "scale = 0", r"#1 'pot': transform: scale: must be non-zero"),
        ('kind = "point"', 'kind = "spot"', r"\[\[light\]\] #2: kind: unknown light kind 'spot'"),
        (
            "color = 0.9",
            'color = "white"',
            r"\[\[light\]\] #1: color: expected a list of 3 numbers",
        ),
        (
            '"tex/paper.png"',
            '"tex/missing.png"',
            r"#1 'pot': material: texture: file .*missing.png",
        ),
        (
            'texture = "brick"',
            'texture = "hatch"',
            r"trip\.toml: \[\[object\]\] #2 'ball\.obj': material: texture: 'hatch' is not a "
            r"built-in texture \(they are brick, grass, .*\) nor a file path",
        ),
        (
            'texture = "brick"',
            'color_texture = "paper"',
            r"#2 'ball\.obj': material: color_texture: 'paper' is not a built-in texture",
        ),
        (
            'path = "ball.obj"',
            'path = "nope.obj"',
            r"#2 'nope.obj': path: mesh file .*nope.obj' does not exist",
        ),
        (
            'uv_projection = "spherical"',
            'uv_projection = "polar"',
            "uv_projection: unknown projection",
        ),
        ("[style]", "style = 3\n[unused]", r"trip.toml: top level: unknown key 'unused'"),
        (
            "ambient = 0.5",
            "ambient = -1",
            r"trip.toml: top level: ambient\[0\]: expected a number >= 0",
        ),
        ('name = "trip"', "name = [", r"trip.toml: invalid TOML"),
        (  # tomllib parses nesting recursively: a RecursionError without the check
            'name = "trip"',
            "name = " + "[" * 100_000 + "]" * 100_000,
            r"trip.toml: invalid TOML: arrays or inline tables nested too deeply",
        ),
        ('description = "every feature once"', "objects = 1", "top level: unknown key 'objects'"),
        (  # integers beyond the float range: float() raises OverflowError
            "fov_y = 33",
            "fov_y = 1" + "0" * 400,
            r"trip.toml: \[camera\]: fov_y: expected a finite number, got an integer beyond the "
            r"float range",
        ),
        (
            "eye = [1.0, 2.0, 9.0]",
            "eye = [1" + "0" * 400 + ", 2.0, 9.0]",
            r"trip.toml: \[camera\]: eye: must be finite, got an integer beyond the float range",
        ),
        (
            "translate = [1, 0, -1]",
            "translate = [1" + "0" * 400 + ", 0, -1]",
            r"#1 'pot': transform: translate\[0\]: expected a finite number, got an integer "
            r"beyond the float range",
        ),
        (
            "[0, 1, 0, 2]",
            "[0, 1, 0, 2" + "0" * 400 + "]",
            r"#2 'ball.obj': transform: expected a finite \(4, 4\) matrix, got an integer beyond",
        ),
    ],
)
def test_file_errors_name_file_and_key(scene_dir, old, new, match):
    assert old in FULL
    path = scene_dir / "trip.toml"
    path.write_text(FULL.replace(old, new, 1))
    with pytest.raises(ValueError, match=match) as info:
        load_scene(path)
    assert isinstance(info.value, SceneFileError)


def test_missing_tables(scene_dir):
    path = scene_dir / "trip.toml"
    head, rest = FULL.split("[camera]")
    path.write_text(head + rest[rest.index("[style]") :])
    with pytest.raises(SceneFileError, match=r"trip.toml: missing the \[camera\] table; add one"):
        load_scene(path)
    path.write_text(FULL.split("[[object]]")[0])
    with pytest.raises(SceneFileError, match=r"trip.toml: no \[\[object\]\] tables"):
        load_scene(path)
    with pytest.raises(FileNotFoundError, match="scene: file .*absent.toml' does not exist"):
        load_scene(scene_dir / "absent.toml")


def test_scene_file_suffixes_in_any_case(scene_dir, monkeypatch):
    monkeypatch.chdir(scene_dir)
    (scene_dir / "TRIP.TOML").write_text(FULL)
    assert load_scene("TRIP.TOML").name == "trip"  # its name = "trip"
    (scene_dir / "notes.txt").write_text(FULL)
    with pytest.raises(
        SceneFileError,
        match=r"^scene: 'notes\.txt' is a file but not a built-in scene, and scene file names end "
        r"in \.toml \(a TOML scene\), \.gltf or \.glb \(glTF 2\.0\), in any case: rename it",
    ):
        load_scene("notes.txt")


def test_material_texture_names_of_a_gltf_scene_are_checked_in_their_table(tmp_path):
    from .test_gltf_degenerate import Tri, quiet

    Tri().write(tmp_path / "model.gltf")
    path = tmp_path / "s.toml"
    path.write_text('gltf = "model.gltf"\n[materials."tri"]\ntexture = "hatch"\n')
    with pytest.raises(
        SceneFileError,
        match=r"s\.toml: \[materials\.\"tri\"\]: texture: 'hatch' is not a built-in texture",
    ):
        quiet(load_scene, path)
    path.write_text('gltf = "model.gltf"\n[materials."*"]\ncolor_texture = "hatch"\n')
    with pytest.raises(SceneFileError, match=r"\[materials\.\"\*\"\]: color_texture: 'hatch'"):
        quiet(load_scene, path)
    path.write_text(
        'gltf = "model.gltf"\n[materials."*"]\ntexture = "grass"\n[materials.tri]\ndiffuse = 0.5\n'
    )
    material = quiet(load_scene, path).objects[0].material
    assert (material.texture, material.diffuse) == ("grass", (0.5, 0.5, 0.5))


def test_unknown_builtin_name_lists_valid_names():
    with pytest.raises(
        ValueError, match=r"unknown built-in scene 'kettle'; valid names: default, .*icosphere"
    ):
        load_scene("kettle")
    with pytest.raises(TypeError, match="name_or_path: expected a scene name or a path, got int"):
        load_scene(3)


def test_parse_scene_dict_source_label():
    data = {
        "camera": {"eye": [0, 0, 5], "target": [0, 0, 0]},
        "object": [{"mesh": "torus", "r": 2.0}],
    }
    with pytest.raises(
        ValueError, match=r"<scene dict>: \[\[object\]\] #1 'torus': r: the tube radius"
    ):
        parse_scene(data)


def test_style_file_parameters_are_relative_to_the_scene_file(tmp_path):
    import numpy as np

    from refnpr.image import write_png_atomic

    write_png_atomic(tmp_path / "paper.png", np.full((8, 8), 128, np.uint8))
    (tmp_path / "s.toml").write_text(
        "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n"
        "[style]\nname = 'threshold'\ntexture = 'paper.png'\nlist = ['paper.png', 'brick']\n"
        "[[object]]\nmesh = 'uv_sphere'\n"
    )
    scene = load_scene(tmp_path / "s.toml")
    assert scene.style["texture"] == str(tmp_path / "paper.png")
    assert scene.style["list"] == [str(tmp_path / "paper.png"), "brick"]  # names stay names


# -- files that are not regular files ----------------------------------------------------------
# A FIFO would block a read forever and a device such as /dev/zero never ends: a scene file, a
# mesh file and a glTF file are read only if they are regular files (their size capped).
SCENE_HEAD = "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n[[object]]\n"


def _not_regular(path, kind):
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/null")  # a device; reading /dev/zero would never end


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_mesh_path_that_is_no_regular_file_is_refused(tmp_path, kind):
    _not_regular(tmp_path / "m.obj", kind)
    (tmp_path / "s.toml").write_text(SCENE_HEAD + 'path = "m.obj"\n')
    with pytest.raises(
        SceneFileError,
        match=r"s\.toml: \[\[object\]\] #1 'm\.obj': path: mesh file .*m\.obj' is not a regular "
        r"file; expected a regular file",
    ):
        load_scene(tmp_path / "s.toml")


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_scene_or_gltf_file_that_is_no_regular_file_is_refused(tmp_path, kind):
    _not_regular(tmp_path / "s.toml", kind)
    with pytest.raises(SceneFileError, match=r"s\.toml: the scene file is not a regular file"):
        load_scene(tmp_path / "s.toml")
    _not_regular(tmp_path / "m.glb", kind)
    (tmp_path / "g.toml").write_text('gltf = "m.glb"\n')
    with pytest.raises(SceneFileError, match=r"m\.glb: the file is not a regular file"):
        load_scene(tmp_path / "g.toml")
    with pytest.raises(SceneFileError, match=r"m\.glb: the file is not a regular file"):
        load_scene(tmp_path / "m.glb")


def test_a_file_that_a_mesh_file_refers_to_is_read_only_if_regular(tmp_path):
    """trimesh reads an OBJ's material library through refnpr's resolver: a FIFO is refused
    (trimesh then loads the geometry without materials) instead of blocking the read."""
    os.mkfifo(tmp_path / "m.mtl")
    (tmp_path / "t.obj").write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")
    (tmp_path / "s.toml").write_text(SCENE_HEAD + 'path = "t.obj"\n')
    assert load_scene(tmp_path / "s.toml").objects[0].mesh.n_faces == 1


def test_mesh_and_scene_files_above_their_caps_are_refused(tmp_path, monkeypatch):
    import refnpr.scenes.loading as loading
    import refnpr.scenes.toml_format as toml_format

    trimesh.creation.box().export(tmp_path / "box.stl")
    (tmp_path / "s.toml").write_text(SCENE_HEAD + 'path = "box.stl"\n')
    assert load_scene(tmp_path / "s.toml").objects[0].mesh.n_faces == 12
    monkeypatch.setattr(loading, "MAX_MESH_FILE_BYTES", 100)
    with pytest.raises(
        SceneFileError,
        match=r"path: mesh file .*box\.stl' has \d+ bytes, more than the 100 bytes allowed",
    ):
        load_scene(tmp_path / "s.toml")
    monkeypatch.setattr(toml_format, "MAX_SCENE_FILE_BYTES", 20)
    with pytest.raises(
        SceneFileError, match=r"s\.toml: the scene file has \d+ bytes, more than the 20 bytes"
    ):
        load_scene(tmp_path / "s.toml")
