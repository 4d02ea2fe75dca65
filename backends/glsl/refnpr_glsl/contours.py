"""The contour layer on the GPU, as refnpr's ``contours`` (Veryovka 2002 sec. 5): silhouette,
boundary and crease edges, hidden parts removed against the depth channel, drawn as
anti-aliased capsules and composited over the style's per-sample output.

Pipeline (per frame):

1. Setup (once per mesh, numpy, like any GPU app precomputing adjacency): the edge table of the
   mesh welded by position (refnpr's ``edge_table``: unique edges, their two faces, -1 for
   boundaries, dihedral angle), and the static crease flag (dihedral > crease_angle).
2. Compute shader, one invocation per edge: clip = VP p (double), front-facing test of both
   faces (geometric normal towards the eye), selection (silhouette: front != back; boundary;
   crease), clipping to the near plane (z >= -w), projection to the sample grid, splitting into
   ``ceil(length / 0.5)`` pieces (at most 4 (nW + nH)), and per piece the visibility test of
   its midpoint (eye depth w <= (1 + depth_tolerance) * the farthest depth of the 3 x 3 samples
   around it). Visible pieces are appended to a buffer (atomic counter: a first pass counts,
   a second writes).
3. One instanced draw: every piece is a quad over its capsule's bounding box; the fragment
   shader writes min(radius + 0.5 - distance(sample centre, segment), 1) with blend equation
   MAX into an R32F coverage target (order independent, so deterministic), radius =
   width * n / 2 samples.
4. A full-screen pass: straight-alpha "over" of the ink with that coverage on the style's RGBA.
"""

from __future__ import annotations

from typing import Any

import moderngl
import numpy as np

from .context import GL
from .kit_io import Case, MeshData

__all__ = ["edge_table", "coverage", "composite", "apply", "contour_params"]

_STEP = 0.5  # piece length in samples (refnpr: 0.5)


def edge_table(positions: np.ndarray, faces: np.ndarray) -> dict[str, np.ndarray]:
    """Unique edges of a mesh welded by position (refnpr ``edge_table``, numpy only).

    Returns
    -------
    dict with "edges" (E, 2) int64 vertex indices, "faces" (E, 2) int64 (-1: boundary),
    "dihedral_deg" (E,) float64.
    """
    _, weld, inverse = np.unique(positions, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    wf = inverse[faces]
    e = np.concatenate([wf[:, [0, 1]], wf[:, [1, 2]], wf[:, [2, 0]]])
    face_of = np.tile(np.arange(faces.shape[0]), 3)
    keep = e[:, 0] != e[:, 1]
    e, face_of = e[keep], face_of[keep]
    key = np.sort(e, axis=1)
    order = np.lexsort((face_of, key[:, 1], key[:, 0]))
    key, face_of = key[order], face_of[order]
    start = np.concatenate([[True], np.any(key[1:] != key[:-1], axis=1)])
    idx = np.flatnonzero(start)
    counts = np.diff(np.concatenate([idx, [key.shape[0]]]))
    f0 = face_of[idx]
    f1 = np.where(counts >= 2, face_of[np.minimum(idx + 1, key.shape[0] - 1)], -1)
    edges = weld[key[idx]]
    p = positions[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    normals = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    cosang = np.where(f1 >= 0, np.sum(normals[f0] * normals[np.maximum(f1, 0)], axis=1), 1.0)
    dihedral = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
    return {
        "edges": edges.astype(np.int64),
        "faces": np.stack([f0, f1], axis=1).astype(np.int64),
        "dihedral_deg": dihedral,
    }


def contour_params(params: dict[str, Any]) -> dict[str, Any]:
    """The layer's parameters with refnpr's defaults filled in (the kit exports all of them)."""
    out = {
        "width": 1.5,
        "ink": [0.0, 0.0, 0.0],
        "silhouettes": True,
        "boundaries": True,
        "crease_angle": None,
        "depth_tolerance": 0.01,
    }
    out.update(params or {})
    if "color" in out and "ink" not in (params or {}):
        out["ink"] = out.pop("color")
    return out


_SELECT = """
#version 450 core
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Pos { double pos[]; };
layout(std430, binding = 1) readonly buffer Faces { int faces[]; };
layout(std430, binding = 2) readonly buffer Edges { ivec4 edges[]; };  // v0, v1, f0, f1
layout(std430, binding = 3) readonly buffer Crease { int crease[]; };
layout(std430, binding = 4) buffer Counter { uint count; };
layout(std430, binding = 5) writeonly buffer Pieces { dvec4 pieces[]; };
uniform sampler2D depth;
uniform double vp[16];
uniform int n_edges;
uniform int emit;  // 0: count the visible pieces; 1: write them
uniform uint capacity;
const int NW = @NW@, NH = @NH@;
const dvec3 EYE = @EYE@;
const bool SILHOUETTES = @SIL@, BOUNDARIES = @BND@;
const double REL_TOL = @TOL@;
const double STEP = @STEP@;

dvec3 P(int i) { return dvec3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]); }
dvec4 clip_of(int i) {
    dvec3 p = P(i);
    dvec4 c;
    for (int r = 0; r < 4; ++r)
        c[r] = vp[4 * r] * p.x + vp[4 * r + 1] * p.y + vp[4 * r + 2] * p.z + vp[4 * r + 3];
    return c;
}
bool front(int f) {
    dvec3 a = P(faces[3 * f]), b = P(faces[3 * f + 1]), c = P(faces[3 * f + 2]);
    dvec3 n = cross(b - a, c - a);
    double len = length(n);
    if (!(len > 0.0LF)) return false;
    dvec3 ctr = (a + b + c) / 3.0LF;
    return dot(n / len, EYE - ctr) > 0.0LF;
}
bool visible(double x, double y, double w) {
    int cx = int(floor(x)), cy = int(floor(y));
    double far_ = -1.0LF;
    for (int j = cy - 1; j <= cy + 1; ++j)
        for (int i = cx - 1; i <= cx + 1; ++i)
            if (i >= 0 && i < NW && j >= 0 && j < NH)
                far_ = max(far_, double(texelFetch(depth, ivec2(i, j), 0).r));
    if (far_ < 0.0LF) return false;
    return w <= far_ * (1.0LF + REL_TOL);
}
void main() {
    int e = int(gl_GlobalInvocationID.x);
    if (e >= n_edges) return;
    ivec4 E = edges[e];
    bool boundary = E.w < 0;
    bool sel = false;
    if (SILHOUETTES && !boundary) sel = sel || (front(E.z) != front(E.w));
    if (BOUNDARIES) sel = sel || boundary;
    if (!boundary && crease[e] != 0) sel = true;
    if (!sel) return;
    dvec4 a = clip_of(E.x), b = clip_of(E.y);
    double da = a.z + a.w, db = b.z + b.w;
    if (da < 0.0LF && db < 0.0LF) return;
    double t0 = 0.0LF, t1 = 1.0LF;
    if (da < 0.0LF) t0 = da / (da - db);
    else if (db < 0.0LF) t1 = da / (da - db);
    double ax = a.x + t0 * (b.x - a.x), ay = a.y + t0 * (b.y - a.y), aw = a.w + t0 * (b.w - a.w);
    double bx = a.x + t1 * (b.x - a.x), by = a.y + t1 * (b.y - a.y), bw = a.w + t1 * (b.w - a.w);
    if (aw <= 0.0LF || bw <= 0.0LF) return;
    double sax = (ax / aw + 1.0LF) * 0.5LF * double(NW);
    double say = (1.0LF - ay / aw) * 0.5LF * double(NH);
    double sbx = (bx / bw + 1.0LF) * 0.5LF * double(NW);
    double sby = (1.0LF - by / bw) * 0.5LF * double(NH);
    double len = sqrt((sbx - sax) * (sbx - sax) + (sby - say) * (sby - say));
    if (isinf(len) || isnan(len)) return;
    int npieces = max(1, int(ceil(len / STEP)));
    npieces = min(npieces, 4 * (NW + NH));
    double ia = 1.0LF / aw, ib = 1.0LF / bw;
    for (int k = 0; k < npieces; ++k) {
        double s0 = double(k) / double(npieces), s1 = double(k + 1) / double(npieces);
        double sm = 0.5LF * (s0 + s1);
        double px = sax + sm * (sbx - sax), py = say + sm * (sby - say);
        double w = 1.0LF / (ia + sm * (ib - ia));  // 1/w is affine in screen space
        if (!visible(px, py, w)) continue;
        uint slot = atomicAdd(count, 1u);
        if (emit == 1 && slot < capacity)
            pieces[slot] = dvec4(sax + s0 * (sbx - sax), say + s0 * (sby - say),
                                 sax + s1 * (sbx - sax), say + s1 * (sby - say));
    }
}
"""

_CAPSULE_VS = """
#version 450 core
layout(std430, binding = 5) readonly buffer Pieces { dvec4 pieces[]; };
uniform double radius;
const int NW = @NW@, NH = @NH@;
flat out dvec4 seg;
void main() {
    dvec4 s = pieces[gl_InstanceID];
    seg = s;
    double pad = radius + 1.0LF;
    dvec2 lo = min(s.xy, s.zw) - pad, hi = max(s.xy, s.zw) + pad;
    dvec2 c = dvec2((gl_VertexID & 1) != 0 ? hi.x : lo.x, (gl_VertexID & 2) != 0 ? hi.y : lo.y);
    // sample-grid coordinates -> NDC of an array-layout target (row y = window y)
    gl_Position = vec4(vec2(2.0LF * c.x / double(NW) - 1.0LF, 2.0LF * c.y / double(NH) - 1.0LF),
                       0.0, 1.0);
}
"""

_CAPSULE_FS = """
#version 450 core
uniform double radius;
flat in dvec4 seg;
out float o_cov;
void main() {
    dvec2 p = dvec2(floor(double(gl_FragCoord.x)) + 0.5LF, floor(double(gl_FragCoord.y)) + 0.5LF);
    dvec2 a = seg.xy, d = seg.zw - seg.xy;
    double len2 = d.x * d.x + d.y * d.y;
    double t = 0.0LF;
    if (len2 > 0.0LF) t = clamp(((p.x - a.x) * d.x + (p.y - a.y) * d.y) / len2, 0.0LF, 1.0LF);
    dvec2 e = a + t * d - p;
    double c = radius + 0.5LF - sqrt(e.x * e.x + e.y * e.y);
    o_cov = float(min(c, 1.0LF));  // blended with MAX into the coverage target (cleared to 0)
}
"""

_COMPOSITE = """
#version 450 core
uniform sampler2D rgba;
uniform sampler2D cov;
const dvec3 INK = @INK@;
out vec4 o_rgba;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    dvec4 s = dvec4(texelFetch(rgba, p, 0));
    double c = double(texelFetch(cov, p, 0).r);
    // straight-alpha "over": lines on top of the base (refnpr Contoured.shade)
    double a = c + s.a * (1.0LF - c);
    dvec3 premult = INK * c + s.rgb * s.a * (1.0LF - c);
    o_rgba = vec4(vec3(a > 0.0LF ? premult / a : dvec3(0.0LF)), float(a));
}
"""


def _lit(x: float) -> str:
    return f"{float(x)!r}LF"


def _vec3(v: Any) -> str:
    a = np.asarray(v, dtype=np.float64).reshape(3)
    return f"dvec3({_lit(a[0])}, {_lit(a[1])}, {_lit(a[2])})"


class _MeshEdges:
    """A mesh's positions, faces and edge table on the GPU (built once)."""

    def __init__(self, gl: GL, mesh: MeshData, crease_angle: float | None) -> None:
        table = edge_table(mesh.positions, mesh.indices)
        e = table["edges"]
        f = table["faces"]
        self.n_edges = int(e.shape[0])
        packed = np.concatenate([e, f], axis=1).astype(np.int32)
        crease = (
            np.zeros(self.n_edges, np.int32)
            if crease_angle is None
            else (table["dihedral_deg"] > float(crease_angle)).astype(np.int32)
        )
        ctx = gl.ctx
        self.pos = ctx.buffer(np.ascontiguousarray(mesh.positions, np.float64).tobytes())
        self.faces = ctx.buffer(np.ascontiguousarray(mesh.indices, np.int32).tobytes())
        self.edges = ctx.buffer(packed.tobytes() if self.n_edges else b"\0" * 16)
        self.crease = ctx.buffer(crease.tobytes() if self.n_edges else b"\0" * 4)

    def release(self) -> None:
        for b in (self.pos, self.faces, self.edges, self.crease):
            b.release()


def coverage(
    gl: GL,
    case: Case,
    depth: moderngl.Texture,
    params: dict[str, Any],
    *,
    camera: dict[str, Any] | None = None,
    cache: dict | None = None,
) -> moderngl.Texture:
    """(n W, n H) R32F line coverage in [0, 1] on the sample grid (refnpr ContourLayer.coverage).

    ``depth``: the G-buffer depth channel (eye depth, +inf where empty). ``cache``: a dict kept
    across frames for the per-mesh edge tables.
    """
    p = contour_params(params)
    cam = camera or case.camera
    n = case.n
    nw, nh = case.sample_size
    vp = np.asarray(cam["projection_matrix"], np.float64) @ np.asarray(
        cam["view_matrix"], np.float64
    )
    cache = {} if cache is None else cache
    ctx = gl.ctx
    src = (
        _SELECT.replace("@NW@", str(nw))
        .replace("@NH@", str(nh))
        .replace("@EYE@", _vec3(cam["eye"]))
        .replace("@SIL@", "true" if p["silhouettes"] else "false")
        .replace("@BND@", "true" if p["boundaries"] else "false")
        .replace("@TOL@", _lit(p["depth_tolerance"]))
        .replace("@STEP@", _lit(_STEP))
    )
    cs = gl.compute(src)
    radius = 0.5 * float(p["width"]) * n
    cov = gl.empty((nw, nh), 1, "f4")
    fbo = ctx.framebuffer(color_attachments=[cov])
    fbo.use()
    ctx.viewport = (0, 0, nw, nh)
    fbo.clear(0.0, 0.0, 0.0, 0.0)
    vs = _CAPSULE_VS.replace("@NW@", str(nw)).replace("@NH@", str(nh))
    prog = gl.program(vs, _CAPSULE_FS)
    prog["radius"].value = radius
    counter = ctx.buffer(reserve=4)
    try:
        for k, mesh in enumerate(case.meshes):
            key = (k, p["crease_angle"])
            if key not in cache:
                cache[key] = _MeshEdges(gl, mesh, p["crease_angle"])
            me = cache[key]
            if me.n_edges == 0:
                continue
            me.pos.bind_to_storage_buffer(0)
            me.faces.bind_to_storage_buffer(1)
            me.edges.bind_to_storage_buffer(2)
            me.crease.bind_to_storage_buffer(3)
            counter.bind_to_storage_buffer(4)
            depth.use(location=0)
            cs["depth"].value = 0
            cs["vp"].write(np.ascontiguousarray(vp.ravel(), np.float64).tobytes())
            cs["n_edges"].value = me.n_edges
            groups = -(-me.n_edges // 64)
            counter.write(np.zeros(1, np.uint32).tobytes())
            cs["emit"].value = 0
            cs["capacity"].value = 0
            dummy = ctx.buffer(reserve=32)
            dummy.bind_to_storage_buffer(5)
            cs.run(group_x=groups)
            ctx.memory_barrier()
            total = int(np.frombuffer(counter.read(), np.uint32)[0])
            dummy.release()
            if total == 0:
                continue
            pieces = ctx.buffer(reserve=32 * total)
            pieces.bind_to_storage_buffer(5)
            counter.write(np.zeros(1, np.uint32).tobytes())
            cs["emit"].value = 1
            cs["capacity"].value = total
            cs.run(group_x=groups)
            ctx.memory_barrier()
            fbo.use()
            ctx.viewport = (0, 0, nw, nh)
            ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
            ctx.enable(moderngl.BLEND)
            ctx.blend_equation = moderngl.MAX
            ctx.blend_func = moderngl.ONE, moderngl.ONE
            vao = ctx.vertex_array(prog, [])
            vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=total)
            vao.release()
            pieces.release()
    finally:
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.disable(moderngl.BLEND)
        counter.release()
        fbo.release()
    return cov


def composite(gl: GL, rgba: moderngl.Texture, cov: moderngl.Texture, ink: Any) -> moderngl.Texture:
    """Straight-alpha "over" of ``ink`` with coverage ``cov`` on ``rgba`` (both (n W, n H))."""
    out = gl.empty(rgba.size, 4, "f4")
    gl.fullscreen(_COMPOSITE.replace("@INK@", _vec3(ink)), out, {"rgba": rgba, "cov": cov})
    return out


def apply(
    gl: GL,
    case: Case,
    rgba: moderngl.Texture,
    gbuffer: dict[str, moderngl.Texture],
    params: dict[str, Any],
    *,
    camera: dict[str, Any] | None = None,
    cache: dict | None = None,
) -> moderngl.Texture:
    """The style's per-sample RGBA with the contour layer drawn over it (needs ``depth``)."""
    if "depth" not in gbuffer:
        raise ValueError(
            f"case {case.name!r}: contours need the depth channel; case.channels = {case.channels}"
        )
    cov = coverage(gl, case, gbuffer["depth"], params, camera=camera, cache=cache)
    out = composite(gl, rgba, cov, contour_params(params)["ink"])
    cov.release()
    return out
