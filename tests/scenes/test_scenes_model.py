"""The scene data model: Material, Light, transforms, SceneObject, Scene."""

import math

import numpy as np
import pytest

from refnpr.raster import Camera
from refnpr.scenes import Light, Material, Scene, SceneObject, icosphere, transform_matrix


def _camera():
    return Camera.look_at((0, 0, 5), (0, 0, 0))


def test_material_defaults_and_broadcast():
    m = Material()
    assert m.ambient == (0.15, 0.15, 0.15) and m.diffuse == (0.8, 0.8, 0.8)
    assert m.specular == (0.3, 0.3, 0.3) and m.shininess == 32.0
    assert m.texture is None and m.uv_scale == (1.0, 1.0)
    g = Material(diffuse=0.5, uv_scale=4, ambient=[0, 0.1, 0.2])
    assert g.diffuse == (0.5, 0.5, 0.5) and g.uv_scale == (4.0, 4.0)
    assert g.ambient == (0.0, 0.1, 0.2) and isinstance(g.ambient, tuple)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(diffuse=(1, 2)), ValueError, "diffuse: expected 3 numbers, got 2"),
        (dict(specular=(-0.1, 0, 0)), ValueError, r"specular\[0\]: expected a number >= 0"),
        (dict(shininess=0), ValueError, "shininess: expected a positive number, got 0.0"),
        (dict(texture=3), TypeError, "texture: expected a texture name or a file path"),
        (dict(uv_scale=(1, 0)), ValueError, r"uv_scale\[1\]: expected a positive number"),
        (dict(ambient="grey"), TypeError, "ambient: expected a list of 3 numbers"),
    ],
)
def test_material_validation(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        Material(**kwargs)


@pytest.mark.parametrize(
    ("direction", "unit"),
    [
        ((1e200, 0.0, 0.0), (1.0, 0.0, 0.0)),  # the squares overflow
        ((1e-200, 0.0, 0.0), (1.0, 0.0, 0.0)),  # the squares underflow to 0
        ((1e-160, 1e-160, 0.0), (math.sqrt(0.5), math.sqrt(0.5), 0.0)),  # subnormal squares
        ((-3e300, 4e300, 0.0), (-0.6, 0.8, 0.0)),
    ],
)
def test_light_direction_of_any_finite_length_is_normalized(direction, unit):
    d = Light(direction=direction).direction
    assert d == pytest.approx(unit, rel=1e-15)
    assert math.hypot(*d) == pytest.approx(1.0, rel=1e-15)


def test_light_normalizes_and_validates():
    d = Light().direction
    assert d == pytest.approx((1 / math.sqrt(3),) * 3)
    assert Light(direction=(0, 3, 4)).direction == pytest.approx((0, 0.6, 0.8))
    p = Light(kind="point", position=(1, 2, 3), color=0.5)
    assert p.position == (1.0, 2.0, 3.0) and p.color == (0.5, 0.5, 0.5)
    with pytest.raises(ValueError, match="kind: unknown light kind 'spot'"):
        Light(kind="spot")
    with pytest.raises(ValueError, match="position: a point light needs a position"):
        Light(kind="point")
    with pytest.raises(ValueError, match="position: a directional light has no position"):
        Light(position=(0, 1, 0))
    with pytest.raises(ValueError, match="direction: must not be the zero vector"):
        Light(direction=(0, 0, 0))


def test_transform_matrix_order():
    m = transform_matrix(translate=(1, 2, 3), rotate_deg=(0, 90, 0), scale=2.0)
    # scale, then rotate +90 about y (x -> -z), then translate
    assert np.allclose(m @ [1, 0, 0, 1], [1, 2, 1, 1])
    assert np.allclose(m @ [0, 1, 0, 1], [1, 4, 3, 1])
    # x, then y, then z: compare with composing single-axis transforms
    rx = transform_matrix(rotate_deg=(30, 0, 0))
    ry = transform_matrix(rotate_deg=(0, 40, 0))
    rz = transform_matrix(rotate_deg=(0, 0, 50))
    assert np.allclose(transform_matrix(rotate_deg=(30, 40, 50)), rz @ ry @ rx)
    assert np.allclose(
        rz[:3, :3] @ [1, 0, 0], [math.cos(math.radians(50)), math.sin(math.radians(50)), 0]
    )
    s = transform_matrix(scale=(1, 2, 3))
    assert np.allclose(np.diag(s), [1, 2, 3, 1])
    with pytest.raises(ValueError, match="scale: must be non-zero on every axis"):
        transform_matrix(scale=(1, 0, 1))
    with pytest.raises(ValueError, match="translate: expected 3 numbers, got 2"):
        transform_matrix(translate=(1, 2))


def test_scene_object_and_world_meshes():
    ball = icosphere(1)
    mat = transform_matrix(translate=(5, 0, 0), scale=2.0)
    a = SceneObject(ball)
    b = SceneObject(ball, mat, Material(diffuse=0.2), name="big")
    assert a.name == "icosphere" and b.name == "big"
    assert np.array_equal(a.transform, np.eye(4)) and not a.transform.flags.writeable
    scene = Scene((a, b), _camera())
    w = scene.world_meshes()
    assert w[0] is ball
    assert np.allclose(w[1].positions, ball.positions * 2.0 + [5, 0, 0])
    assert np.allclose(w[1].normals, ball.normals)
    assert scene.world_meshes()[1] is w[1]  # memoized
    lo, hi = scene.bounds()
    both = np.vstack([ball.positions, ball.positions * 2.0 + [5, 0, 0]])
    assert np.array_equal(lo, both.min(axis=0)) and np.array_equal(hi, both.max(axis=0))
    other = Camera.look_at((3, 3, 3), (0, 0, 0))
    moved = scene.with_camera(other)
    assert moved.camera is other and moved.objects is scene.objects and scene.camera is not other


def test_scene_defaults_and_validation():
    scene = Scene((SceneObject(icosphere(0)),), _camera())
    assert scene.lights == (Light(),) and scene.ambient == (1.0, 1.0, 1.0)
    assert scene.background == (1.0, 1.0, 1.0, 1.0) and scene.style == {}
    obj = SceneObject(icosphere(0))
    with pytest.raises(ValueError, match="objects: a scene needs at least one object"):
        Scene((), _camera())
    with pytest.raises(TypeError, match="camera: expected a Camera"):
        Scene((obj,), camera=None)
    with pytest.raises(TypeError, match=r"lights\[0\]: expected a Light, got dict"):
        Scene((obj,), _camera(), lights=({},))
    with pytest.raises(ValueError, match=r"background: RGBA components must lie in \[0, 1\]"):
        Scene((obj,), _camera(), background=(2, 0, 0, 1))
    with pytest.raises(TypeError, match="mesh: expected a refnpr Mesh, got str"):
        SceneObject("teapot")
    with pytest.raises(ValueError, match=r"transform: the last row must be \(0, 0, 0, 1\)"):
        SceneObject(icosphere(0), np.ones((4, 4)))
    with pytest.raises(ValueError, match="transform: the 3x3 part is singular"):
        SceneObject(icosphere(0), np.diag([1.0, 0.0, 1.0, 1.0]))
