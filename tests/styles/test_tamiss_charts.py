"""uv charts of the stroke field: vertex frames, chart orientation, smooth derivatives.

Oracles: affine maps (a planar quad's frame is exact), a hand-built pair of quads whose second
chart has u and v swapped, the exact sphere (uv from the ray hit of each pixel's centre and of
points half a pixel away, by finite differences), and measured properties of the teapot (hatching
directions on both sides of its patch borders; jumps of the level field at triangle edges).
"""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import Camera, Mesh, rasterize
from refnpr.render import render
from refnpr.scenes import Light, Material, Scene, SceneObject, load_scene
from refnpr.styles import get_style
from refnpr.styles.tamiss import StrokeField, field_inputs, layer_scale
from refnpr.styles.tamiss.charts import (
    SYMMETRIES,
    _shared_vertices,
    _unit_columns,
    chart_layout,
    vertex_frames,
)
from refnpr.styles.tamiss.compose import field_channels
from refnpr.styles.tamiss.gather import scene_charts


def chart_adjacency(mesh, labels) -> np.ndarray:
    """(E, 2) int64 pairs of charts (a < b) that share a border, as chart_layout finds them."""
    pa, pb, v_chart = _shared_vertices(mesh, labels, _unit_columns(vertex_frames(mesh)))
    ca, cb = v_chart[pa], v_chart[pb]
    return np.unique(np.stack([np.minimum(ca, cb), np.maximum(ca, cb)], axis=1), axis=0)


def _quad(corners, uv) -> Mesh:
    return Mesh(
        np.asarray(corners, dtype=float),
        np.array([[0, 1, 2], [0, 2, 3]]),
        np.tile([0, 0, 1.0], (4, 1)),
        np.asarray(uv, dtype=float),
    )


def test_symmetries_are_the_eight_signed_permutations():
    assert SYMMETRIES.shape == (8, 2, 2)
    for m in SYMMETRIES:
        np.testing.assert_array_equal(m @ m.T, np.eye(2))
    assert len({m.tobytes() for m in SYMMETRIES}) == 8
    np.testing.assert_array_equal(SYMMETRIES[0], np.eye(2))


def test_vertex_frames_of_an_affine_map_are_exact():
    # P = (2 u + 0.5 v, -u + 3 v, 0): dP/du = (2, -1, 0), dP/dv = (0.5, 3, 0) everywhere
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    pos = np.stack([2 * uv[:, 0] + 0.5 * uv[:, 1], -uv[:, 0] + 3 * uv[:, 1], 0 * uv[:, 0]], 1)
    f = vertex_frames(_quad(pos, uv))
    np.testing.assert_allclose(f[:, :, 0], np.tile([2, -1, 0.0], (4, 1)), atol=1e-12)
    np.testing.assert_allclose(f[:, :, 1], np.tile([0.5, 3, 0.0], (4, 1)), atol=1e-12)


def _two_charts(m_second) -> Mesh:
    """Two unit quads side by side (x in [0, 1] and [1, 2]) sharing the edge x = 1, each its own
    chart (duplicated vertices); the first has u = x, v = y, the second uv = m^-1 (x - 1, y)."""
    left = _quad([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0], [1, 0], [1, 1], [0, 1]])
    xy = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    uv_r = xy @ np.linalg.inv(m_second).T  # uv' = M uv = xy
    pos = np.concatenate([left.positions, left.positions + [1, 0, 0]])
    faces = np.concatenate([left.faces, left.faces + 4])
    uv = np.concatenate([left.uv, uv_r])
    return Mesh(pos, faces, np.tile([0, 0, 1.0], (8, 1)), uv)


@pytest.mark.parametrize("k", range(8))
def test_orientation_undoes_a_swapped_or_flipped_chart(k):
    mesh = _two_charts(SYMMETRIES[k])
    labels = np.array([0, 0, 1, 1])
    np.testing.assert_array_equal(chart_adjacency(mesh, labels), [[0, 1]])
    orient = chart_layout(mesh, labels).symmetry
    assert orient[0] == 0  # the root keeps its mapping
    # oriented, both charts run u along x and v along y: their frames agree
    frames = vertex_frames(mesh)
    for c, verts in ((0, slice(0, 4)), (1, slice(4, 8))):
        oriented = frames[verts] @ SYMMETRIES[orient[c]].T
        np.testing.assert_allclose(oriented[:, :2, :], np.tile(np.eye(2), (4, 1, 1)), atol=1e-12)
    # and offset, the second continues the first: one uv map u = x, v = y, one id group
    layout = chart_layout(mesh, labels)
    mapped = mesh.uv[4:] @ SYMMETRIES[layout.symmetry[1]].T + layout.offset[1]
    np.testing.assert_allclose(mapped, mesh.positions[4:, :2], atol=1e-12)
    np.testing.assert_array_equal(layout.group, [0, 0])


def test_overlapping_or_discontinuous_charts_keep_their_own_ids():
    # the second quad's uv continues the first's at the shared edge but only half-way (its uv
    # is squeezed): no offset fits every shared vertex, so it is not merged
    mesh = _two_charts(np.eye(2))
    uv = mesh.uv.copy()
    uv[4:, 1] *= 0.5
    squeezed = Mesh(mesh.positions, mesh.faces, mesh.normals, uv)
    layout = chart_layout(squeezed, np.array([0, 0, 1, 1]))
    np.testing.assert_array_equal(layout.group, [0, 1])
    np.testing.assert_array_equal(layout.offset, np.zeros((2, 2)))


def test_strokes_run_on_across_the_teapots_patch_borders():
    """With the charts laid out as one atlas, a stroke's fragments come from several patches
    (no break at every border); with each patch its own chart, never."""
    sc = load_scene("tamiss_teapot")
    st = get_style("tamiss", directions=["u"])
    _, gb = render(sc, st, 384, 288, return_gbuffer=True)
    patch = scene_charts(sc)
    from refnpr.styles.tamiss import gather_fragments

    counts = {}
    for orient in (True, False):
        inp = field_inputs(gb, sc, orient_charts=orient)
        f = gather_fragments(inp, st.pipeline_params.field)
        p = patch[gb["tri_id"].ravel()[f.sample]]
        pairs = np.unique(np.stack([f.id, p], axis=1), axis=0)
        ids, n_patches = np.unique(pairs[:, 0], return_counts=True)
        counts[orient] = int(np.sum(n_patches > 1))
    assert counts[False] == 0
    assert counts[True] > 30, counts


def test_orientation_skips_collapsed_edges_and_unshared_charts():
    # a fan of 4 patches meeting at a pole (the teapot lid): directions agree once oriented
    sc = load_scene("tamiss_teapot")
    mesh = sc.world_meshes()[0]
    from refnpr.styles.tamiss.gather import _mesh_charts

    labels = _mesh_charts(mesh)
    orient = chart_layout(mesh, labels).symmetry
    assert orient.shape == (32,)
    # the lid and the body keep u around the axis on every patch: at most flips, never a swap
    body_and_lid = [c for c in range(32) if c not in range(12, 20)]
    assert np.all(orient[body_and_lid] < 4)


def _border_angles(inp, gb, patch, adj, angle_deg):
    """Angle (deg) between the screen directions of a layer at ``angle_deg`` on neighbouring
    samples of two charts (patches, before any grouping) that share a border."""
    h, w = inp.shape
    a = np.radians(angle_deg)
    su, sv = inp.uv_scale[:, 0], inp.uv_scale[:, 1]
    qx = -np.sin(a) * inp.duv_dx[:, 0] * su + np.cos(a) * inp.duv_dx[:, 1] * sv
    qy = -np.sin(a) * inp.duv_dy[:, 0] * su + np.cos(a) * inp.duv_dy[:, 1] * sv
    ang = np.full(h * w, np.nan)
    ang[inp.sample] = np.arctan2(qy, qx)  # grad q: the strokes run perpendicular to it
    ch = np.where(gb["tri_id"] >= 0, patch[np.maximum(gb["tri_id"], 0)], -1)
    ang = ang.reshape(h, w)
    out = []
    for sa, sb in (
        ((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
        ((slice(None, -1),), (slice(1, None),)),
    ):
        ca, cb = ch[sa], ch[sb]
        lo, hi = np.minimum(ca, cb), np.maximum(ca, cb)
        touching = np.isin(lo * 4096 + hi, adj[:, 0] * 4096 + adj[:, 1]) & (ca >= 0) & (ca != cb)
        d = ang[sa][touching] - ang[sb][touching]
        out.append(np.abs((d + np.pi / 2) % np.pi - np.pi / 2))  # lines: modulo 180 degrees
    return np.degrees(np.concatenate(out))


def test_hatching_direction_is_continuous_across_the_teapots_patch_borders():
    """Szécsi et al. sec. 2 / 4.1: the direction of hatching is the uv mapping's, which must be
    oriented consistently; the teapot's mirrored patches (handle, bottom) reverse u, so a layer
    at 30 degrees turns to -30 degrees at their borders unless the charts are oriented."""
    sc = load_scene("tamiss_teapot")
    st = get_style("tamiss", directions=[30.0])
    _, gb = render(sc, st, 384, 288, return_gbuffer=True)
    mesh = sc.world_meshes()[0]
    labels = scene_charts(sc)
    orient = chart_layout(mesh, labels).symmetry
    adj = chart_adjacency(mesh, labels)
    flipped = adj[orient[adj[:, 0]] != orient[adj[:, 1]]]
    assert len(flipped) >= 4
    on = _border_angles(field_inputs(gb, sc), gb, labels, flipped, 30.0)
    off = _border_angles(field_inputs(gb, sc, orient_charts=False), gb, labels, flipped, 30.0)
    assert on.size > 100
    assert np.mean(on > 30.0) < 0.05 and np.median(on) < 3.0
    assert np.mean(off > 30.0) > 0.07  # the measure sees the jump when orientation is off
    # over all borders the u direction agrees to a few degrees
    all_on = _border_angles(field_inputs(gb, sc), gb, labels, adj, 0.0)
    assert np.median(all_on) < 3.0 and np.percentile(all_on, 90) < 20.0


def _facing(gb, sc, lo=0.3):
    """(H, W - 1) bool: both horizontal neighbours covered and facing the eye (|n.v| > lo):
    near silhouettes the level falls steeply anyway (D_q -> 0) and grazing samples keep the
    flat derivatives."""
    v = np.asarray(sc.camera.eye, dtype=float) - gb["position"]
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    ndv = np.abs(np.sum(gb["normal"] * v, axis=-1))
    ok = (gb["tri_id"] >= 0) & (ndv > lo)
    return ok[:, 1:] & ok[:, :-1]


def _sphere_scene():
    cam = Camera.look_at((0, 0, 3.2), (0, 0, 0), (0, 1, 0), 40.0, 0.1, 100.0)
    sc = load_scene("sphere")
    return Scene(objects=sc.objects, camera=cam, lights=(Light(direction=(0, 0, 1)),))


def _exact_sphere_uv(sc, gb, dx, dy):
    """uv of the exact sphere hit by the ray through each pixel centre offset by (dx, dy)."""
    cam = sc.camera
    h, w = gb.sample_shape
    inv = np.linalg.inv(cam.projection_matrix(w, h) @ cam.view_matrix())
    ys, xs = np.mgrid[0:h, 0:w]
    ndc_x = 2 * (xs + 0.5 + dx) / w - 1
    ndc_y = 1 - 2 * (ys + 0.5 + dy) / h
    far = np.stack([ndc_x, ndc_y, np.ones_like(ndc_x), np.ones_like(ndc_x)], -1) @ inv.T
    far = far[..., :3] / far[..., 3:]
    eye = np.asarray(cam.eye, dtype=float)
    d = far - eye
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    r = float(sc.objects[0].mesh.positions[0] @ sc.objects[0].mesh.positions[0]) ** 0.5
    b = d @ eye
    disc = b * b - (eye @ eye - r * r)
    t = -b - np.sqrt(np.maximum(disc, 0))
    p = eye + t[..., None] * d
    return p, disc > 0


def test_smooth_derivatives_follow_the_surface_and_do_not_jump_at_edges():
    sc = _sphere_scene()
    st = get_style("tamiss", directions=["u"])
    _, gb = render(sc, st, 192, 144, return_gbuffer=True)
    smooth = field_inputs(gb, sc, orient_charts=False)
    flat = field_inputs(gb, sc, derivatives="flat", orient_charts=False)
    # the oracle: finite differences of uv over the exact sphere's hits (u from the mesh's own
    # uv at its vertices: fit u, v as functions of the hit point by the mesh's convention)
    mesh = sc.objects[0].mesh
    pos, uv = mesh.positions, mesh.uv
    inner = (uv[:, 1] > 0.05) & (uv[:, 1] < 0.95)
    # the mesh's v is the polar angle / pi from +y or -y; u the azimuth / 2 pi from some origin:
    # read both conventions off the vertices
    pol = np.arccos(np.clip(pos[inner, 1] / np.linalg.norm(pos[inner], axis=1), -1, 1)) / np.pi
    v_sign = 1.0 if np.corrcoef(pol, uv[inner, 1])[0, 1] > 0 else -1.0

    def v_of(p):
        pv = np.arccos(np.clip(p[..., 1] / np.linalg.norm(p, axis=-1), -1, 1)) / np.pi
        return pv if v_sign > 0 else 1 - pv

    p0, hit = _exact_sphere_uv(sc, gb, 0.0, 0.0)
    px, hx = _exact_sphere_uv(sc, gb, 0.5, 0.0)
    mx, hmx = _exact_sphere_uv(sc, gb, -0.5, 0.0)
    py, hy = _exact_sphere_uv(sc, gb, 0.0, 0.5)
    my, hmy = _exact_sphere_uv(sc, gb, 0.0, -0.5)
    ok_px = (hit & hx & hmx & hy & hmy).ravel()[smooth.sample]
    dv_dx = (v_of(px) - v_of(mx)).ravel()[smooth.sample]
    dv_dy = (v_of(py) - v_of(my)).ravel()[smooth.sample]
    lat = np.abs(v_of(p0).ravel()[smooth.sample] - 0.5) < 0.35  # away from the poles
    ok = ok_px & lat
    ref = np.hypot(dv_dx, dv_dy)[ok]
    err_s = np.hypot(smooth.duv_dx[ok, 1] - dv_dx[ok], smooth.duv_dy[ok, 1] - dv_dy[ok]) / ref
    err_f = np.hypot(flat.duv_dx[ok, 1] - dv_dx[ok], flat.duv_dy[ok, 1] - dv_dy[ok]) / ref
    assert ok.sum() > 5000
    assert np.median(err_s) < 0.02 and np.percentile(err_s, 99) < 0.08
    assert np.median(err_s) < np.median(err_f)
    # jumps of the level field: |delta s| between neighbouring samples on different triangles
    # against the same on one triangle (the flat field is constant-ish per triangle, then jumps)
    field = StrokeField.from_params(directions=["u"])
    for inp, bound in ((smooth, 3.0), (flat, None)):
        h, w = inp.shape
        s = np.full(h * w, np.nan)
        s[inp.sample] = layer_scale(inp, field)[:, 0]
        s = s.reshape(h, w)
        tri = gb["tri_id"]
        ds = np.abs(s[:, 1:] - s[:, :-1])
        across = tri[:, 1:] != tri[:, :-1]
        lat2 = np.isfinite(ds) & _facing(gb, sc)
        ratio = np.percentile(ds[across & lat2], 99) / np.percentile(ds[~across & lat2], 99)
        if bound is not None:
            assert ratio < bound, ratio
        else:
            assert ratio > 2 * 3.0, ratio  # the measure sees the per-triangle steps


def test_teapot_level_field_has_no_steps_at_triangle_edges():
    """The stair-stepped cross-hatching of Fig. 7 came from the level decided per triangle."""
    sc = load_scene("tamiss_teapot")
    st = get_style("tamiss")
    _, gb = render(sc, st, 384, 288, return_gbuffer=True)
    field = st.pipeline_params.field
    tri = gb["tri_id"]
    ratios = {}
    for mode in ("smooth", "flat"):
        inp = field_inputs(gb, sc, derivatives=mode)
        h, w = inp.shape
        s = np.full((h * w, field.n_layers), np.nan)
        s[inp.sample] = layer_scale(inp, field)
        s = s.reshape(h, w, -1)[..., 1]  # the cross-hatching layer (along v)
        ch = np.full(h * w, -1)
        ch[inp.sample] = inp.chart
        ch = ch.reshape(h, w)
        ds = np.abs(s[:, 1:] - s[:, :-1])
        same_chart = (ch[:, 1:] == ch[:, :-1]) & np.isfinite(ds) & _facing(gb, sc)
        across = same_chart & (tri[:, 1:] != tri[:, :-1])
        within = same_chart & (tri[:, 1:] == tri[:, :-1])
        ratios[mode] = np.percentile(ds[across], 95) / np.percentile(ds[within], 95)
    assert ratios["smooth"] < 5.0, ratios
    assert ratios["flat"] > 20.0, ratios


def test_smooth_needs_its_channels_else_warns_and_uses_flat():
    sc = _sphere_scene()
    chans = sorted(field_channels(sc, None, "flat"))
    gb = rasterize(sc, None, 32, 24, chans, dtype=np.float64)
    with pytest.warns(RuntimeWarning, match=r"derivatives='smooth' needs the G-buffer channels"):
        inp = field_inputs(gb, sc)
    np.testing.assert_array_equal(inp.duv_dx, field_inputs(gb, sc, derivatives="flat").duv_dx)


@pytest.mark.parametrize(
    ("kwargs", "err", "match"),
    [
        ({"derivatives": "exact"}, ValueError, r"derivatives: expected one of \['smooth', 'flat'"),
        ({"orient_charts": 1}, TypeError, r"orient_charts: expected a bool \(true/false\), got 1"),
    ],
)
@pytest.mark.parametrize("style", ["tamiss", "tam"])
def test_parameter_errors(style, kwargs, err, match):
    with pytest.raises(err, match=match):
        get_style(style, **kwargs)


def test_planar_quads_are_unchanged_by_smoothing():
    # an affine uv on a plane: the smooth reconstruction is the exact derivative
    mesh = _quad([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 0], [2, 0], [2, 2], [0, 2]])
    cam = Camera.look_at((0.3, 0.2, 3), (0, 0, 0), (0, 1, 0), 40.0, 0.1, 100.0)
    sc = Scene(objects=(SceneObject(mesh, material=Material()),), camera=cam)
    gb = rasterize(sc, None, 64, 48, sorted(field_channels(sc, None)), dtype=np.float64)
    a = field_inputs(gb, sc)
    b = field_inputs(gb, sc, derivatives="flat")
    np.testing.assert_allclose(a.duv_dx, b.duv_dx, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(a.duv_dy, b.duv_dy, rtol=1e-9, atol=1e-12)
