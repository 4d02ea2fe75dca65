"""The fused TAMISS kernels (inputs, one-pass gathering, grouped sums, strip raster) against
independent references: numpy expressions of the per-sample inputs, a stable argsort, the
gathering with every chunk overflowing its room (rerun straight to its place), the formula
layer's sums, and a naive sub-sample rasterizer. All comparisons are bitwise unless stated;
thread counts 1 and 2 give the same bits."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from refnpr.formulas import lighting
from refnpr.formulas.tamiss import StrokeStrip, aggregate, fragment_regressors, normalize_t
from refnpr.raster import rasterize
from refnpr.scenes import Light, load_scene
from refnpr.styles.base import ShadeContext
from refnpr.styles.tamiss import _kernels as K
from refnpr.styles.tamiss import gather as G
from refnpr.styles.tamiss.aggregate import aggregate_exact
from refnpr.styles.tamiss.charts import SYMMETRIES
from refnpr.styles.tamiss.field import StrokeField
from refnpr.styles.tamiss.gather import Fragments, field_inputs, gather_fragments
from refnpr.styles.tamiss.raster import rasterize_strips
from refnpr.styles.tamiss.strokes import Strips

from ._oracles import light_dirs
from ._threads import outputs_per_thread_count

CHANNELS = ["uv", "duv_dx", "duv_dy", "tri_id", "mesh_id", "normal", "bary", "position",
            "dposition_dx", "dposition_dy"]  # fmt: skip


def _gb(name: str, w: int, h: int, spp: int = 1, scene=None, dtype=np.float64):
    sc = scene if scene is not None else load_scene(name)
    return sc, rasterize(sc, None, w, h, CHANNELS, spp, dtype=dtype)


def _smooth_duv(gb, sel, tri, faces, frames, eye, duv_dx, duv_dy):
    """The smooth derivatives by numpy, sample by sample in the same operations: the vertex
    frames interpolated with the barycentrics, the footprint moved onto the normal's plane,
    least squares in the frame; the flat values where the frame or the view degenerates."""
    f64 = lambda name: gb[name][sel].astype(np.float64)  # noqa: E731
    bary, n, pos = f64("bary"), f64("normal"), f64("position")
    gu, gv = np.zeros((tri.size, 3)), np.zeros((tri.size, 3))
    for c in range(3):
        v = faces[tri, c]
        for k in range(3):
            gu[:, k] = gu[:, k] + bary[:, c] * frames[v, k, 0]
            gv[:, k] = gv[:, k] + bary[:, c] * frames[v, k, 1]

    def dot(a, b):
        return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]

    a00, a01, a11 = dot(gu, gu), dot(gu, gv), dot(gv, gv)
    det = a00 * a11 - a01 * a01
    d = pos - eye
    nd = dot(n, d)
    dlen, nlen = np.sqrt(dot(d, d)), np.sqrt(dot(n, n))
    ok = (det > 1e-12 * (a00 * a11)) & (det > 0) & (np.abs(nd) >= 0.05 * dlen * nlen) & (dlen > 0)
    for name, flat in (("dposition_dx", duv_dx), ("dposition_dy", duv_dy)):
        dp = f64(name)
        with np.errstate(all="ignore"):
            lam = dot(n, dp) / nd
            p = dp - lam[:, None] * d
            r0, r1 = dot(gu, p), dot(gv, p)
            du, dv = (a11 * r0 - a01 * r1) / det, (a00 * r1 - a01 * r0) / det
        flat[ok, 0], flat[ok, 1] = du[ok], dv[ok]


def _reference_inputs(gb, scene, *, constant_tone=None, derivatives="smooth", orient=True):
    """The per-sample inputs by numpy formulas (boolean-mask gathers, einsum, lighting)."""
    ctx = ShadeContext(gb, scene)
    tri = gb["tri_id"]
    sel = tri >= 0
    charts = G.scene_charts(scene, gb)
    scale = np.array([o.material.uv_scale for o in scene.objects], dtype=np.float64)
    mesh_id = np.maximum(gb["mesh_id"][sel], 0)
    uv = np.ascontiguousarray(gb["uv"][sel], dtype=np.float64)
    uv_scale = scale[mesh_id]
    chart = charts[tri[sel]]
    duv_dx = np.ascontiguousarray(gb["duv_dx"][sel], dtype=np.float64)
    duv_dy = np.ascontiguousarray(gb["duv_dy"][sel], dtype=np.float64)
    tri_sel = tri[sel].astype(np.int64)
    faces, frames, sym, offset, group = G._scene_frames(scene)
    if derivatives == "smooth":
        eye = np.asarray(scene.camera.eye, dtype=np.float64)
        _smooth_duv(gb, sel, tri_sel, faces, frames, eye, duv_dx, duv_dy)
    if orient:
        m = SYMMETRIES[sym[tri_sel]]
        uv = np.einsum("nij,nj->ni", m, uv) + offset[tri_sel]
        chart = group[tri_sel]
        duv_dx = np.einsum("nij,nj->ni", m, duv_dx)
        duv_dy = np.einsum("nij,nj->ni", m, duv_dy)
        uv_scale = np.einsum("nij,nj->ni", np.abs(m), uv_scale)
    if constant_tone is not None:
        dark = np.full(uv.shape[0], float(constant_tone))
    else:
        n = gb["normal"][sel].astype(np.float64)
        objs = scene.objects
        m_a = np.array([o.material.ambient for o in objs], dtype=np.float64)[mesh_id]
        m_d = np.array([o.material.diffuse for o in objs], dtype=np.float64)[mesh_id]
        rgb = m_a * np.asarray(scene.ambient, dtype=np.float64)
        for light_dir, color in light_dirs(ctx, sel):
            rgb = rgb + m_d * lighting.diffuse(n, light_dir)[..., None] * color
        lum = (rgb[:, 0] * 0.2126 + rgb[:, 1] * 0.7152) + rgb[:, 2] * 0.0722  # r, g, then b
        dark = 1.0 - np.clip(lum, 0.0, 1.0)
    return np.flatnonzero(sel.ravel()), uv, duv_dx, duv_dy, uv_scale, dark, chart


def _point_lit(name: str):
    sc = load_scene(name)
    lights = (*sc.lights, Light(kind="point", position=(2.0, 3.0, 4.0), color=(0.6, 0.5, 0.4)))
    return dataclasses.replace(sc, lights=lights)


@pytest.mark.parametrize(
    "name, kw",
    [
        ("tamiss_teapot", {}),
        ("tamiss_teapot", {"derivatives": "flat"}),
        ("tamiss_teapot", {"orient_charts": False}),
        ("tamiss_sphere", {"constant_tone": 0.4}),
        ("point", {}),
    ],
)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])  # float32 channels read as float64
def test_field_inputs_match_the_numpy_formulas(name, kw, dtype):
    scene = _point_lit("tamiss_sphere") if name == "point" else None
    sc, gb = _gb(name, 96, 72, scene=scene, dtype=dtype)
    inp = field_inputs(gb, sc, **kw)
    ref = _reference_inputs(
        gb,
        sc,
        constant_tone=kw.get("constant_tone"),
        derivatives=kw.get("derivatives", "smooth"),
        orient=kw.get("orient_charts", True),
    )
    got = (inp.sample, inp.uv, inp.duv_dx, inp.duv_dy, inp.uv_scale, inp.darkness, inp.chart)
    for field, a, b in zip(
        ("sample", "uv", "dx", "dy", "scale", "dark", "chart"), got, ref, strict=True
    ):
        assert a.shape == b.shape and np.array_equal(a, b), field
    assert inp.sample.size > 1000
    assert np.ptp(inp.darkness) > 0.1 or "constant_tone" in kw


@pytest.mark.parametrize("width", [1.0, 2.5])
def test_one_pass_gathering_equals_the_rerun_of_every_chunk(monkeypatch, width):
    """Room for 3 fragments per chunk: nearly every chunk overflows, is gathered again straight
    to its place and copied there; the fragments are the same as with the default room."""
    sc, gb = _gb("tamiss_teapot", 160, 120, spp=4)
    inp = field_inputs(gb, sc)
    field = StrokeField.from_params(directions=["u", "v"], period=2.0, density=1.0)
    ref = gather_fragments(inp, field, gather_width=width)
    monkeypatch.setattr(G, "_ROOM", 3)
    fr = gather_fragments(inp, field, gather_width=width)
    got = (fr.sample, fr.x, fr.y, fr.t, fr.id, fr.layer, fr.level)
    want = (ref.sample, ref.x, ref.y, ref.t, ref.id, ref.layer, ref.level)
    for a, b in zip(got, want, strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    sy, sx = np.divmod(ref.sample, inp.shape[1])
    assert np.array_equal(ref.x, (sx + 0.5) / inp.n) and np.array_equal(ref.y, (sy + 0.5) / inp.n)
    assert np.all(np.diff(ref.sample) >= 0) and len(fr) > 5000


def test_group_keys_is_a_stable_argsort():
    rng = np.random.default_rng(3)
    for n, span in ((0, 1), (1, 1), (1000, 7), (20000, 5000), (5000, 1 << 62)):
        keys = rng.integers(-span, span, n).astype(np.int64)
        uid, starts, perm = K.group_keys(keys)
        order = np.argsort(keys, kind="stable")
        assert np.array_equal(perm, order)
        assert np.array_equal(uid, np.unique(keys))
        assert np.array_equal(np.diff(starts), np.unique(keys, return_counts=True)[1])


def _reference_sums(frags: Fragments, dtype):
    """The aggregates by the formula layer: min/max, normalize_t, regressors, reduceat sums."""
    t_ = frags.t.astype(dtype)
    xy = np.stack([frags.x, frags.y], axis=-1).astype(dtype)
    uid, lo = aggregate(frags.id, t_, op="min")
    _, hi = aggregate(frags.id, t_, op="max")
    _, mn = aggregate(frags.id, xy, op="min")
    _, mx = aggregate(frags.id, xy, op="max")
    origin = (mn + mx) * dtype(0.5)
    inv = np.searchsorted(uid, frags.id)
    s = normalize_t(t_, lo[inv], hi[inv])
    R = fragment_regressors(s, xy[:, 0] - origin[inv, 0], xy[:, 1] - origin[inv, 1])
    _, M = aggregate(frags.id, R, op="sum")
    return uid, np.bincount(inv), lo, hi, origin, M


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_grouped_sums_equal_the_formula_layer(dtype):
    sc, gb = _gb("tamiss_sphere", 200, 150)
    inp = field_inputs(gb, sc)
    # long strokes: groups of hundreds of fragments, past numpy's 8-way and 128-block sums
    field = StrokeField.from_params(directions=["u", "v"], period=3.0, length=4.0, density=1.0)
    fr = gather_fragments(inp, field, gather_width=3.0)
    agg = aggregate_exact(fr, dtype=dtype)
    ref = _reference_sums(fr, dtype)
    got = (agg.stroke_ids, agg.count, agg.t_min, agg.t_max, agg.origin, agg.moments)
    for a, b in zip(got, ref, strict=True):
        assert np.array_equal(a, b)
    assert agg.moments.dtype == dtype and agg.count.max() > 300


def _edge(p, q, px, py):
    return (q[0] - p[0]) * (py - p[1]) - (q[1] - p[1]) * (px - p[0])


def _naive_coverage(strips: Strips, shape, aa):
    """(alpha, pieces) by testing every sub-sample of every bbox pixel against every triangle
    (solid brush, opacity 1): coverage is the fraction of sub-samples in the union."""
    nh, nw = shape
    alpha = np.zeros(shape)
    touched = np.zeros(shape, dtype=np.int32)
    for L, R in zip(strips.strip.left, strips.strip.right, strict=True):
        tris = []
        for i in range(L.shape[0] - 1):
            tris += [(L[i], R[i], L[i + 1]), (R[i], R[i + 1], L[i + 1])]
        pts = np.concatenate([L, R])
        x0, y0 = np.maximum(np.floor(pts.min(0)).astype(int), 0)
        x1, y1 = np.minimum(np.floor(pts.max(0)).astype(int), (nw - 1, nh - 1))
        for y in range(y0, y1 + 1):
            for x in range(x0, x1 + 1):
                inside = np.zeros((aa, aa), dtype=bool)
                for a, b, c in tris:
                    area = _edge(a, b, c[0], c[1])
                    if abs(area) < 1e-12:
                        continue
                    if not (np.floor(min(a[0], b[0], c[0])) <= x <= np.floor(max(a[0], b[0], c[0]))
                            and np.floor(min(a[1], b[1], c[1])) <= y <= np.floor(max(a[1], b[1], c[1]))):  # fmt: skip
                        continue
                    sg = 1.0 if area > 0 else -1.0
                    for sj in range(aa):
                        for si in range(aa):
                            px, py = x + (si + 0.5) * (1.0 / aa), y + (sj + 0.5) * (1.0 / aa)
                            if (_edge(b, c, px, py) * sg >= 0 and _edge(c, a, px, py) * sg >= 0
                                    and _edge(a, b, px, py) * sg >= 0):  # fmt: skip
                                inside[sj, si] = True
                if inside.any():
                    cov = inside.sum() / (aa * aa)
                    alpha[y, x] = alpha[y, x] + cov * (1 - alpha[y, x])
                    touched[y, x] += 1
    return alpha, touched


@pytest.mark.parametrize("aa", [1, 3, 4])
def test_strip_raster_matches_naive_subsamples(aa):
    rng = np.random.default_rng(aa)
    P, Kv = 12, 6
    centre = rng.uniform(4, 36, (P, 1, 2))
    direction = rng.normal(size=(P, 1, 2))
    along = (
        np.linspace(-6, 6, Kv)[None, :, None]
        * direction
        / np.linalg.norm(direction, axis=-1, keepdims=True)
    )
    bend = rng.normal(scale=0.3, size=(P, Kv, 2)).cumsum(1)
    mid = centre + along + bend
    normal = np.stack([-direction[..., 1], direction[..., 0]], -1)
    normal = normal / np.linalg.norm(normal, axis=-1, keepdims=True)
    half = rng.uniform(0.3, 2.0, (P, 1, 1))
    strip = StrokeStrip(left=mid + half * normal, right=mid - half * normal,
                        t=np.broadcast_to(np.linspace(0, 1, Kv), (P, Kv)).copy())  # fmt: skip
    strips = Strips(strip=strip, stroke=np.arange(P), ids=np.arange(P), width=2 * half[:, 0, 0])
    alpha, pieces = rasterize_strips(strips, (40, 44), 1, aa=aa)
    ref_alpha, ref_pieces = _naive_coverage(strips, (40, 44), aa)
    assert np.array_equal(pieces, ref_pieces)
    np.testing.assert_allclose(alpha, ref_alpha, rtol=0, atol=1e-12)  # solid brush: val = 1 +- ulp
    assert pieces.max() >= 2 and 0 < np.mean(alpha > 0) < 0.9


_SCRIPT = """
import json, sys, numpy as np
from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles.tamiss import TamissParams, run_pipeline
sc = load_scene("tamiss_teapot")
ch = ["uv", "duv_dx", "duv_dy", "tri_id", "mesh_id", "normal", "bary", "position",
      "dposition_dx", "dposition_dy"]
gb = rasterize(sc, None, 200, 150, ch, 1, dtype=np.float64)
r = run_pipeline(gb, sc, TamissParams.from_params(period=2.5, density=1.0, brush="pencil"))
out = {k: np.ascontiguousarray(v).tobytes().hex() for k, v in (
    ("dark", r.inputs.darkness), ("ids", r.fragments.id), ("t", r.fragments.t),
    ("M", r.aggregates.moments), ("ink", r.ink), ("pieces", r.pieces))}
print(json.dumps(out))
"""


@pytest.mark.slow
def test_pipeline_bits_do_not_depend_on_the_thread_count():
    runs = outputs_per_thread_count(_SCRIPT)
    assert runs[0] == runs[1]
    assert len(runs[0]["ids"]) > 1000
