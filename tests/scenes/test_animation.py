"""Animated scenes: interpolation (against closed forms), scene.at for every track type, the
[animation] table of scene files and its errors."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr.raster import Camera, Mesh
from refnpr.scenes import (
    Animation,
    Keyframe,
    Light,
    Scene,
    SceneFileError,
    SceneObject,
    Track,
    list_scenes,
    load_scene,
    parse_scene,
    quaternion_from_axis_angle,
    transform_matrix,
)
from refnpr.scenes.toml_format import scene_frames
from refnpr.scenes.tracks import interpolate, quaternion_from_matrix, quaternion_matrix, slerp

finite = st.floats(-100, 100, allow_nan=False, allow_infinity=False)


def keys_strategy(size=3, kind="vector"):
    gaps = st.lists(st.floats(0.25, 10.0), min_size=1, max_size=6)
    return gaps.flatmap(
        lambda g: st.tuples(
            st.just(np.concatenate([[0.0], np.cumsum(g)])),
            st.lists(
                st.lists(finite, min_size=size, max_size=size),
                min_size=len(g) + 1,
                max_size=len(g) + 1,
            ),
        )
    )


def unit_quaternions(n):
    return st.lists(
        st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
            lambda q: np.linalg.norm(q) > 0.1
        ),
        min_size=n,
        max_size=n,
    ).map(lambda qs: [tuple(np.asarray(q) / np.linalg.norm(q)) for q in qs])


# ------------------------------------------------------------------------------ interpolation
@pytest.mark.parametrize("interp", ["linear", "catmull_rom"])
@given(data=keys_strategy())
def test_vector_interpolation_is_exact_at_keys(interp, data):
    frames, values = data
    keys = [Keyframe(f, v) for f, v in zip(frames, values, strict=True)]
    for k in keys:
        assert interpolate(keys, k.frame, interp) == k.value  # bit-exact, not approximately
    # held outside the keys
    assert interpolate(keys, frames[-1] + 5.0, interp) == keys[-1].value


@given(qs=unit_quaternions(4), gaps=st.lists(st.floats(0.5, 5), min_size=3, max_size=3))
def test_slerp_is_exact_at_keys_and_unit_length_between(qs, gaps):
    frames = np.concatenate([[0.0], np.cumsum(gaps)])
    keys = [Keyframe(f, q) for f, q in zip(frames, qs, strict=True)]
    for k in keys:
        assert interpolate(keys, k.frame, "slerp") == k.value
    for f in np.linspace(0.0, frames[-1], 37):
        q = interpolate(keys, f, "slerp")
        assert abs(np.linalg.norm(q) - 1.0) < 1e-12


@given(
    axis=st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
        lambda a: np.linalg.norm(a) > 0.1
    ),
    a0=st.floats(-170, 170),
    delta=st.floats(-170, 170),
    u=st.floats(0, 1),
)
def test_slerp_about_one_axis_is_the_linearly_interpolated_angle(axis, a0, delta, u):
    # oracle: rotations about one axis compose by adding angles, so slerp (constant angular
    # speed on the shorter arc) gives the angle a0 + u * delta for |delta| < 180
    q0 = quaternion_from_axis_angle(axis, a0)
    q1 = quaternion_from_axis_angle(axis, a0 + delta)
    got = quaternion_matrix(slerp(q0, q1, u))
    want = quaternion_matrix(quaternion_from_axis_angle(axis, a0 + u * delta))
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_slerp_takes_the_shorter_arc():
    q0 = quaternion_from_axis_angle((0, 1, 0), 10.0)
    q1 = tuple(-c for c in quaternion_from_axis_angle((0, 1, 0), 50.0))  # same rotation, -q
    mid = quaternion_matrix(slerp(q0, q1, 0.5))
    np.testing.assert_allclose(mid, transform_matrix(rotate_deg=(0, 30, 0))[:3, :3], atol=1e-12)


def catmull_rom_uniform(p0, p1, p2, p3, u):
    """The classic uniform Catmull-Rom segment between p1 and p2 (matrix form, tension 1/2)."""
    p0, p1, p2, p3 = (np.asarray(p, float) for p in (p0, p1, p2, p3))
    return 0.5 * (
        2 * p1
        + (-p0 + p2) * u
        + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u**2
        + (-p0 + 3 * p1 - 3 * p2 + p3) * u**3
    )


@given(
    pts=st.lists(st.lists(finite, min_size=2, max_size=2), min_size=4, max_size=4),
    u=st.floats(0, 1),
    step=st.floats(0.5, 8),
)
def test_catmull_rom_on_even_keys_is_the_uniform_spline(pts, u, step):
    keys = [Keyframe(i * step, p) for i, p in enumerate(pts)]
    got = interpolate(keys, (1 + u) * step, "catmull_rom")  # the middle segment
    np.testing.assert_allclose(got, catmull_rom_uniform(*pts, u), rtol=1e-9, atol=1e-9)


@given(
    gaps=st.lists(st.floats(0.25, 10), min_size=2, max_size=5),
    a=st.lists(finite, min_size=3, max_size=3),
    b=st.lists(finite, min_size=3, max_size=3),
    t=st.floats(0, 1),
)
def test_catmull_rom_and_linear_reproduce_linear_motion(gaps, a, b, t):
    frames = np.concatenate([[0.0], np.cumsum(gaps)])
    line = lambda f: np.asarray(a) + f * np.asarray(b)  # noqa: E731
    keys = [Keyframe(f, line(f)) for f in frames]
    f = t * frames[-1]
    for interp in ("linear", "catmull_rom"):
        np.testing.assert_allclose(interpolate(keys, f, interp), line(f), rtol=1e-9, atol=1e-7)


def test_quaternions_match_transform_matrix_rotations():
    for axis, index in (((1, 0, 0), 0), ((0, 1, 0), 1), ((0, 0, 1), 2)):
        angles = [0.0, 0.0, 0.0]
        angles[index] = 37.0
        want = transform_matrix(rotate_deg=angles)[:3, :3]
        np.testing.assert_allclose(
            quaternion_matrix(quaternion_from_axis_angle(axis, 37.0)), want, atol=1e-12
        )


@given(qs=unit_quaternions(1))
def test_quaternion_from_matrix_inverts_quaternion_matrix(qs):
    (q,) = qs
    back = quaternion_from_matrix(quaternion_matrix(q))
    assert min(np.abs(np.subtract(back, q)).max(), np.abs(np.add(back, q)).max()) < 1e-9


# ------------------------------------------------------------------------------ scene.at
def tri_mesh(name="tri"):
    return Mesh(
        np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]),
        [[0, 1, 2]],
        normals=np.tile([0.0, 0, 1], (3, 1)),
        uv=np.array([[0.0, 0], [1, 0], [0, 1]]),
        name=name,
    )


def base_scene(animation=None, transform=None):
    cam = Camera.look_at((0, 0, 5), (0, 0, 0), (0, 1, 0), 40.0, 0.1, 100.0)
    objects = (
        SceneObject(tri_mesh(), transform if transform is not None else np.eye(4), name="a"),
        SceneObject(tri_mesh(), name="b"),
    )
    lights = (
        Light(direction=(0, 0, 1)),
        Light(kind="point", position=(1, 2, 3), color=(0.5, 0.5, 0.5)),
    )
    return Scene(
        objects, cam, lights, style={"name": "toon", "n": 2}, name="anim", animation=animation
    )


def two_keys(target, v0, v1, f1=10.0, **kw):
    return Track(target, ((0.0, v0), (f1, v1)), **kw)


@pytest.mark.parametrize(
    "target, v0, v1, read",
    [
        ("camera.eye", (0, 0, 5), (0, 2, 9), lambda s: tuple(s.camera.eye)),
        ("camera.target", (0, 0, 0), (2, 0, 0), lambda s: tuple(s.camera.target)),
        ("camera.up", (0, 1, 0), (1, 1, 0), lambda s: tuple(s.camera.up)),
        ("camera.fov_y", 40.0, 60.0, lambda s: (s.camera.fov_y,)),
        ("camera.near", 0.1, 0.5, lambda s: (s.camera.near,)),
        ("camera.far", 100.0, 50.0, lambda s: (s.camera.far,)),
        ("light[1].position", (1, 2, 3), (3, 2, 1), lambda s: s.lights[1].position),
        ("light[1].color", (0.5, 0.5, 0.5), (1.0, 0.0, 0.5), lambda s: s.lights[1].color),
        (
            'object "a".translation',
            (0, 0, 0),
            (4, -2, 6),
            lambda s: tuple(s.objects[0].transform[:3, 3]),
        ),
        ("style.c", 2.0, 6.0, lambda s: (s.style["c"],)),
    ],
)
def test_at_interpolates_every_vector_track_linearly(target, v0, v1, read):
    scene = base_scene(Animation(11, 24.0, (two_keys(target, v0, v1),)))
    v0 = np.atleast_1d(np.asarray(v0, float))
    v1 = np.atleast_1d(np.asarray(v1, float))
    for f in (0, 2.5, 7, 10):
        got = np.asarray(read(scene.at(f)), float)
        np.testing.assert_allclose(got, v0 + (v1 - v0) * f / 10.0, rtol=1e-12, atol=1e-12)


def test_at_light_direction_is_the_normalized_interpolation():
    scene = base_scene(Animation(11, 24.0, (two_keys("light[0].direction", (0, 0, 1), (1, 0, 0)),)))
    d = scene.at(5).lights[0].direction
    np.testing.assert_allclose(d, np.array([0.5, 0, 0.5]) / math.sqrt(0.5), atol=1e-12)


def test_at_rotation_and_scale_compose_as_transform_matrix():
    rot = Track(
        'object "a".rotation',
        (
            (0.0, quaternion_from_axis_angle((0, 1, 0), 0.0)),
            (10.0, quaternion_from_axis_angle((0, 1, 0), 80.0)),
        ),
    )
    tracks = (
        rot,
        two_keys('object "a".scale', 1.0, (2.0, 3.0, 4.0)),
        two_keys('object "a".translation', (0, 0, 0), (10, 0, -10)),
    )
    scene = base_scene(Animation(11, 24.0, tracks))
    for f in (0, 3, 10):
        s = 1.0 + f / 10.0 * np.array([1.0, 2.0, 3.0])
        want = transform_matrix((f, 0, -f), (0, 8.0 * f, 0), s)
        np.testing.assert_allclose(scene.at(f).objects[0].transform, want, atol=1e-12)


def test_untracked_transform_parts_come_from_the_static_transform():
    static = transform_matrix((1, 2, 3), (10, 20, 30), (2, 2, 2))
    q_static = quaternion_from_matrix(static[:3, :3] / 2.0)
    scene = base_scene(
        Animation(5, 24.0, (Track('object "a".rotation', ((0.0, q_static),)),)), transform=static
    )
    np.testing.assert_allclose(scene.at(2).objects[0].transform, static, atol=1e-12)
    moved = base_scene(
        Animation(5, 24.0, (two_keys('object "a".translation', (1, 2, 3), (5, 2, 3), f1=4.0),)),
        transform=static,
    )
    want = static.copy()
    want[0, 3] = 3.0
    np.testing.assert_allclose(moved.at(2).objects[0].transform, want, atol=1e-12)


def test_style_tracks_with_integer_keys_round():
    scene = base_scene(Animation(11, 24.0, (two_keys("style.n", 2, 5, integer=True),)))
    assert [scene.at(f).style["n"] for f in (0, 1, 2, 5, 10)] == [2, 2, 3, 4, 5]
    assert scene.at(3).style["name"] == "toon"  # the rest of the table stays


def test_at_keeps_untouched_parts_and_clears_the_animation():
    scene = base_scene(
        Animation(11, 24.0, (two_keys('object "a".translation', (0, 0, 0), (1, 0, 0)),))
    )
    still = scene.at(4)
    assert still.animation is None and still.frames == 1
    assert still.objects[1] is scene.objects[1]  # same object: its world mesh stays memoized
    assert still.objects[0].mesh is scene.objects[0].mesh
    assert still.lights == scene.lights and still.camera is scene.camera


def test_frames_outside_the_range_are_errors():
    scene = base_scene(Animation(11, 24.0, (two_keys("camera.fov_y", 40.0, 60.0),)))
    for bad in (-0.5, 10.01, math.inf, math.nan, 10**400):  # 10**400: float() overflows
        with pytest.raises(
            ValueError, match=r"frame: .* is outside the animation's frames \[0, 10\]"
        ):
            scene.at(bad)
    with pytest.raises(TypeError, match="frame: expected a number"):
        scene.at("3")
    still = base_scene()
    assert still.at(0) is still and still.frames == 1
    with pytest.raises(ValueError, match="is a still .* only frame 0"):
        still.at(1)


def test_invalid_interpolated_values_name_the_frame():
    scene = base_scene(Animation(11, 24.0, (two_keys("camera.eye", (0, 0, 5), (0, 0, -5)),)))
    with pytest.raises(ValueError, match=r"frame 5: target: equals eye"):
        scene.at(5)


@pytest.mark.parametrize(
    "make, exc, match",
    [
        (
            lambda: Track("camera.zoom", ((0, 1.0),)),
            ValueError,
            "unknown track target 'camera.zoom'",
        ),
        (lambda: Track("lights[0].color", ((0, 1.0),)), ValueError, "valid targets"),
        (
            lambda: Track("camera.eye", ((0, (1, 2)),)),
            ValueError,
            r"keys\[0\]: camera.eye expects 3 numbers, got 2",
        ),
        (
            lambda: Track("camera.eye", ((5, (0, 0, 1)), (5, (0, 0, 2)))),
            ValueError,
            r"keys\[1\]: frame 5 is not after",
        ),
        (
            lambda: Track("camera.eye", ((5, (0, 0, 1)), (2, (0, 0, 2)))),
            ValueError,
            "increasing frame",
        ),
        (
            lambda: Track('object "a".rotation', ((0, (0, 0, 0, 2.0)),)),
            ValueError,
            "has length 2, expected a unit quaternion",
        ),
        (
            lambda: Track('object "a".rotation', ((0, (0, 0, 0, 1.0)),), "linear"),
            ValueError,
            r"'linear' is not available .* \('slerp',\)",
        ),
        (lambda: Track("camera.eye", ()), ValueError, "at least one key"),
        (
            lambda: Track("style.n", ((0, 1), (1, (1, 2)))),
            ValueError,
            r"keys\[1\]: style.n expects 1 numbers",
        ),
        (lambda: Animation(0, 24.0), ValueError, "frames: expected an integer >= 1"),
        (lambda: Animation(5, 0.0), ValueError, "fps: expected a positive number"),
        (
            lambda: Animation(5, 24.0, (two_keys("camera.fov_y", 40, 50, f1=7.0),)),
            ValueError,
            "lies after the last frame 4",
        ),
        (
            lambda: Animation(
                11, 24.0, (two_keys("camera.fov_y", 40, 50), two_keys("camera.fov_y", 40, 50))
            ),
            ValueError,
            "a second track for 'camera.fov_y'",
        ),
    ],
)
def test_track_and_animation_errors(make, exc, match):
    with pytest.raises(exc, match=match):
        make()


@pytest.mark.parametrize(
    "track, match",
    [
        (
            two_keys("light[2].color", 1.0, 0.0),
            r"the scene has 2 light\(s\), numbered from 0; light\[2\]",
        ),
        (
            two_keys("light[1].direction", (1, 0, 0), (0, 1, 0)),
            "light.1. is a point light, which has no animated direction",
        ),
        (
            two_keys("light[0].position", (1, 0, 0), (0, 1, 0)),
            "directional light, which has no animated position",
        ),
        (two_keys('object "c".scale', 1.0, 2.0), "no object named 'c'; objects: 'a', 'b'"),
    ],
)
def test_tracks_must_name_parts_of_the_scene(track, match):
    with pytest.raises(ValueError, match=match):
        base_scene(Animation(11, 24.0, (track,)))


def test_a_sheared_static_transform_cannot_be_partly_animated():
    shear = np.eye(4)
    shear[0, 1] = 0.5
    with pytest.raises(ValueError, match="static transform has shear"):
        base_scene(
            Animation(3, 24.0, (two_keys('object "a".scale', 1.0, 2.0, f1=2.0),)), transform=shear
        )


# ------------------------------------------------------------------------------ scene files
SCENE = {
    "camera": {"eye": [0, 0, 5], "target": [0, 0, 0]},
    "light": [{"direction": [0, 0, 1]}],
    "object": [{"name": "ball", "mesh": "uv_sphere", "n_u": 8, "n_v": 4}],
    "style": {"name": "toon", "n": 2},
}


def with_animation(animation):
    return {**SCENE, "animation": animation}


def test_scene_file_animation_round_trip():
    data = with_animation(
        {
            "frames": 25,
            "fps": 12,
            "track": [
                {
                    "target": "camera.eye",
                    "interpolation": "catmull_rom",
                    "keys": [
                        {"frame": 0, "value": [0, 0, 5]},
                        {"time": 1.0, "value": [5, 0, 0]},
                        {"frame": 24, "value": [0, 0, -5]},
                    ],
                },
                {
                    "target": 'object "ball".rotation',
                    "keys": [
                        {"frame": 0, "axis": [0, 1, 0], "angle_deg": 0},
                        {
                            "frame": 24,
                            "quaternion": [0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4)],
                        },
                    ],
                },
                {
                    "target": "style.n",
                    "keys": [{"frame": 0, "value": 2}, {"frame": 24, "value": 4}],
                },
            ],
        }
    )
    scene = parse_scene(data, source="spin.toml")
    assert scene.frames == 25 and scene.animation.fps == 12.0
    eye, _, n = scene.animation.tracks
    assert eye.target == "camera.eye" and eye.keys[1].frame == 12.0  # time 1 s at 12 fps
    np.testing.assert_array_equal(scene.at(12).camera.eye, [5, 0, 0])
    np.testing.assert_allclose(
        scene.at(12).objects[0].transform, transform_matrix(rotate_deg=(0, 45, 0)), atol=1e-12
    )
    assert n.target == "style.n" and n.integer
    assert scene.at(18).style == {"name": "toon", "n": 4}  # 3.5 rounds up
    assert parse_scene(SCENE).animation is None


@pytest.mark.parametrize(
    "animation, match",
    [
        ({"fps": 24}, r"x.toml: \[animation\]: missing key 'frames'"),
        (
            {"frames": 5, "speed": 2},
            r"\[animation\]: unknown key 'speed'; valid keys: frames, fps, track",
        ),
        (
            {"frames": 5, "track": [{"target": "camera.eye"}]},
            r"\[\[animation.track\]\] #1 'camera.eye': keys: expected a non-empty array",
        ),
        (
            {"frames": 5, "track": [{"target": "camera.zoom", "keys": [{"frame": 0, "value": 1}]}]},
            r"#1 'camera.zoom': target: unknown track target",
        ),
        (
            {
                "frames": 5,
                "track": [{"target": "camera.eye", "keys": [{"frame": 0, "value": [1, 2]}]}],
            },
            r"#1 'camera.eye': keys\[0\]: camera.eye expects 3 numbers",
        ),
        (
            {
                "frames": 5,
                "track": [
                    {
                        "target": "camera.fov_y",
                        "keys": [{"frame": 3, "value": 40}, {"frame": 1, "value": 50}],
                    }
                ],
            },
            r"keys\[1\]: frame 1 is not after the previous key's frame 3",
        ),
        (
            {"frames": 5, "track": [{"target": "camera.fov_y", "keys": [{"value": 40}]}]},
            r"keys\[0\]: give exactly one of `frame = N` or `time = SECONDS`, got neither",
        ),
        (
            {
                "frames": 5,
                "track": [{"target": "camera.fov_y", "keys": [{"time": 1.0, "value": 40}]}],
            },
            r"keys\[0\]: frame 24 \(time 1 s at 24 fps\) lies after the last frame 4",
        ),
        (
            {
                "frames": 5,
                "track": [
                    {
                        "target": 'object "ball".rotation',
                        "keys": [{"frame": 0, "quaternion": [0, 0, 1, 1]}],
                    }
                ],
            },
            r"keys\[0\]: value: quaternion .* has length 1.41421356, expected a unit quaternion",
        ),
        (
            {
                "frames": 5,
                "track": [
                    {
                        "target": 'object "ball".rotation',
                        "keys": [{"frame": 0, "value": [0, 0, 0, 1]}],
                    }
                ],
            },
            r"a rotation key needs `quaternion",
        ),
        (
            {
                "frames": 5,
                "track": [
                    {
                        "target": 'object "ball".rotation',
                        "keys": [{"frame": 0, "axis": [0, 0, 0], "angle_deg": 3}],
                    }
                ],
            },
            r"axis: must not be the zero vector",
        ),
        (
            {
                "frames": 5,
                "track": [{"target": 'object "cube".scale', "keys": [{"frame": 0, "value": 2}]}],
            },
            r"x.toml: \[\[animation.track\]\] #1 'object \"cube\".scale': no object named 'cube'",
        ),
        (
            {
                "frames": 5,
                "track": [{"target": "light[1].color", "keys": [{"frame": 0, "value": 1}]}],
            },
            r"#1 'light\[1\].color': the scene has 1 light",
        ),
        (
            {
                "frames": 5,
                "track": [
                    {"target": "camera.fov_y", "keys": [{"frame": 0, "value": 40}], "ease": 1}
                ],
            },
            r"#1: unknown key 'ease'",
        ),
    ],
)
def test_scene_file_animation_errors_name_file_table_and_key(animation, match):
    with pytest.raises(SceneFileError, match=match):
        parse_scene(with_animation(animation), source="x.toml")


ANIMATED_BUILTINS = {
    "veryovka_dolly": 49,
    "halftone_light_orbit": 49,
    "xtoon_flow": 36,
    "tamiss_knot_orbit": 49,
}


@pytest.mark.parametrize("name", sorted(ANIMATED_BUILTINS))
def test_builtin_animated_scenes_load_and_name_their_paper_style(name):
    scene = load_scene(name)
    assert scene.frames == ANIMATED_BUILTINS[name] == scene_frames(name)
    assert scene.style.get("name") in {"threshold", "halftone", "xtoon", "tamiss"}
    first, last = scene.at(0), scene.at((scene.frames - 1) // 2)  # the orbit is a loop
    moved = (
        not np.array_equal(first.camera.eye, last.camera.eye)
        or first.lights != last.lights
        or any(
            not np.array_equal(a.transform, b.transform)
            for a, b in zip(first.objects, last.objects, strict=True)
        )
    )
    assert moved, f"{name}: nothing changes between the first and the last frame"


def test_dolly_doubles_the_distance_every_twelve_frames():
    scene = load_scene("veryovka_dolly")
    heights = [scene.at(f).camera.eye[1] for f in (0, 12, 24, 36, 48)]
    assert heights == [2.0, 4.0, 8.0, 16.0, 32.0]


def test_knot_orbit_stays_on_its_circle():
    scene = load_scene("tamiss_knot_orbit")
    for f in np.linspace(0, 48, 17):
        eye = scene.at(f).camera.eye
        assert abs(math.hypot(eye[0], eye[2]) - 5.3) < 5.3 * 5e-4  # Catmull-Rom, 3.75 deg keys
        assert eye[1] == 1.2


def test_still_scenes_have_one_frame():
    stills = [n for n in list_scenes() if n not in ANIMATED_BUILTINS]
    assert stills and all(scene_frames(n) == 1 for n in stills)


def test_dataclasses_replace_keeps_the_animation_checked():
    scene = base_scene(Animation(3, 24.0, (two_keys('object "a".scale', 1.0, 2.0, f1=2.0),)))
    with pytest.raises(ValueError, match="no object named 'a'"):
        dataclasses.replace(scene, objects=(SceneObject(tri_mesh(), name="z"),))
