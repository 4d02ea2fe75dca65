"""The contour layer: edge tables, silhouette placement against the analytic outline, hiding."""

import numpy as np
import pytest
import trimesh

from refnpr.raster import Camera, Mesh, rasterize
from refnpr.scenes import Light, Material, Scene, SceneObject, uv_sphere
from refnpr.styles import ShadeContext, get_style
from refnpr.styles.contours import ContourLayer, edge_table


def _scene(mesh, eye=(0.0, 0.0, 5.0)):
    cam = Camera.look_at(eye, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 0.1, 100.0)
    return Scene(
        objects=(SceneObject(mesh, np.eye(4), Material(), "m"),),
        camera=cam,
        lights=(Light(),),
        name="t",
    )


def _cube() -> Mesh:
    tm = trimesh.creation.box(extents=(1.6, 1.6, 1.6))
    return Mesh(tm.vertices, tm.faces, normals=tm.vertex_normals, name="cube")


def test_cube_edge_table():
    m = _cube()
    t = edge_table(m.positions, m.faces)
    assert len(t.edges) == 18  # 12 cube edges + 6 face diagonals
    assert np.all(t.faces[:, 1] >= 0)  # closed
    np.testing.assert_allclose(np.sort(t.dihedral_deg), [0.0] * 6 + [90.0] * 12, atol=1e-9)


def test_uv_seams_are_not_boundaries():
    s = uv_sphere(1.0, 32, 16)
    t = edge_table(s.positions, s.faces)
    assert np.all(t.faces[:, 1] >= 0)


def _coverage(scene, layer, size=(160, 160), spp=1):
    gb = rasterize(scene, scene.camera, *size, ("depth",), spp)
    return layer.coverage(ShadeContext(gb, scene)), gb


def test_sphere_silhouette_lies_on_the_projected_outline():
    scene = _scene(uv_sphere(1.0, 128, 64))
    cov, gb = _coverage(scene, ContourLayer(width=2.0))
    # analytic outline: a sphere of radius 1 at distance 5 subtends sin(a) = 1/5
    f = 1.0 / np.tan(np.radians(20.0))
    r_px = np.tan(np.arcsin(1 / 5)) * f * 80  # NDC radius * half height
    y, x = np.mgrid[0:160, 0:160] + 0.5
    dist = np.hypot(x - 80, y - 80)
    assert cov[np.abs(dist - r_px) < 0.4].mean() > 0.9
    assert cov[dist < r_px - 3].max() == 0.0  # no lines inside (smooth surface, no creases)
    assert cov[dist > r_px + 3].max() == 0.0


def test_hidden_cube_edges_are_removed():
    scene = _scene(_cube(), eye=(3.0, 2.5, 4.0))
    layer = ContourLayer(width=1.5, crease_angle=45.0, silhouettes=False)
    cov, gb = _coverage(scene, layer, size=(200, 200))
    vp = gb.view_projection

    def px(p):
        c = vp @ np.append(p, 1.0)
        return (c[0] / c[3] + 1) * 100, (1 - c[1] / c[3]) * 100

    front = px(np.array([0.8, 0.8, 0.0]))  # middle of the edge nearest the eye (visible)
    back = px(np.array([-0.8, -0.8, 0.0]))  # middle of the edge farthest away (hidden)
    assert cov[int(front[1]), int(front[0])] > 0.9
    assert cov[int(back[1]), int(back[0])] == 0.0


def test_contoured_wraps_any_style_and_adds_depth():
    scene = _scene(uv_sphere())
    style = get_style(
        "contoured", base={"name": "toon", "specular": False}, contours={"width": 3.0}
    )
    assert style.requires(scene) == {"normal", "mesh_id", "depth"}
    from refnpr.render import render

    img = render(scene, {"name": "toon", "contours": True}, 64, 64)
    assert img.rgba[..., :3].min() == pytest.approx(0.0, abs=1e-6)  # black lines present


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"width": 0.0}, r"width: expected a value in \(0, 256\], got 0.0"),
        ({"crease_angle": 200.0}, r"crease_angle: expected a value in \(0, 180\], got 200.0"),
        ({"ink": (2.0, 0.0, 0.0)}, r"ink: expected 3 values in \[0, 1\]"),
    ],
)
def test_bad_layer_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ContourLayer(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"ink": (np.nan, 0.0, 0.0)}, ValueError, r"ink: expected 3 values in \[0, 1\]"),
        ({"ink": "black"}, ValueError, r"ink: expected 3 values in \[0, 1\]"),
        (
            {"silhouettes": "no"},
            TypeError,
            r"silhouettes: expected a bool \(true/false\), got 'no'",
        ),
        ({"width": 1e300}, ValueError, r"width: expected a value in \(0, 256\], got 1e\+300"),
    ],
)
def test_more_bad_layer_parameters(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        ContourLayer(**kwargs)


def test_unknown_contour_key_lists_valid_keys():
    with pytest.raises(
        TypeError, match=r"contours: unknown parameter\(s\) \['colour'\]; valid parameters: \["
    ):
        get_style("contoured", base="toon", contours={"colour": (0, 0, 0)})


def test_edge_tables_are_built_once_per_mesh(monkeypatch):
    """A still scene's frames reuse the mesh's edge table (no per-frame welding and sorting);
    the kept table equals one built by hand, and another mesh gets its own."""
    import refnpr.styles.contours as C

    built = []
    real = C.edge_table
    monkeypatch.setattr(C, "edge_table", lambda p, f: built.append(1) or real(p, f))
    scene = _scene(_cube(), eye=(2.0, 3.0, 5.0))
    layer = ContourLayer(width=1.5, crease_angle=45.0)
    first, gb = _coverage(scene, layer)
    again = layer.coverage(ShadeContext(gb, scene))
    assert len(built) == 1
    mesh = scene.world_meshes()[0]
    kept, by_hand = C._mesh_edges(mesh).table, real(mesh.positions, mesh.faces)
    assert np.array_equal(first, again)
    for name in ("edges", "faces", "dihedral_deg"):
        assert np.array_equal(getattr(kept, name), getattr(by_hand, name))
    _coverage(_scene(_cube(), eye=(2.0, 3.0, 5.0)), layer)
    assert len(built) == 2
