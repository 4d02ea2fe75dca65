"""The G-buffer pass: rasterize a case's meshes on the sample grid into one texture per channel.

The sample grid (n W x n H) is rendered with the case's exact view and projection matrices
(aspect W / H, as refnpr does), y negated in clip space so that texel row 0 is the top image row
(array layout); tri_id is ``gl_PrimitiveID`` of one indexed draw of every object's triangles
concatenated in object order, so it equals refnpr's global triangle index.

Two derivative modes:

``analytic``
    Every value is computed in the fragment shader, in double precision, from the triangle's
    three vertices fetched by ``gl_PrimitiveID`` from storage buffers: the clip positions
    (a compute pass: clip = VP p in float64) give the perspective-correct barycentric planes
    lambda'_i = b_i / w (refnpr's ``_lam_rows``), attributes are f = P / Q and their per-pixel
    derivatives follow from the quotient rule df = (dP - f dQ) / Q. This reproduces refnpr's
    rasterizer to float32 rounding.
``quad``
    A normal GPU shader: attributes are the hardware's perspective-correct varyings (float32),
    depth is 1 / gl_FragCoord.w, and derivatives are ``dFdx``/``dFdy`` (2 x 2 quad finite
    differences) times n (refnpr's derivatives are per pixel, the quad's per sample). With y
    flipped, ``dFdy`` is already d/dy downward (image rows). ``bary`` stays analytic (GL 4.5 has
    no barycentric built-in).

Coverage: every vertex inside the clip volume (refnpr's guard band) is first snapped, in the
vertex shader, to refnpr's 1/256-pixel grid (round half up), which lies on GL's sub-pixel grid
of the sample grid; GL then rasterizes the same snapped triangles, and llvmpipe's fill
convention on the y-flipped target equals refnpr's top-left rule, so tri_id matches refnpr
exactly (``snap=False``: GL's own snapping, 1/256 of a sample). Triangles crossing a clip plane
are clipped by GL, not by refnpr's Sutherland-Hodgman (new vertices may snap differently).
Visibility is the same in both derivative modes: depth test GL_LESS on w / far written to
gl_FragDepth (a GL_DEPTH_COMPONENT32F attachment) from the exact 1/w, ties keeping the earlier
triangle as refnpr does; samples whose 1/w lies outside [1/far, 1/near] (with refnpr's relative
slack) are discarded. At most GL_MAX_DRAW_BUFFERS channels are written per pass; more channels
take several passes over the same geometry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl
import numpy as np

from .context import GL
from .kit_io import Case

__all__ = ["rasterize", "BUILTIN", "channel_layout", "DERIVATIVE_MODES"]

DERIVATIVE_MODES = ("analytic", "quad")

#: Built-in channels: name -> (components, dtype, value where empty).
BUILTIN: dict[str, tuple[int, str, str]] = {
    "depth": (1, "f4", "1.0 / 0.0"),
    "ndc_z": (1, "f4", "1.0"),
    "tri_id": (1, "i4", "-1"),
    "mesh_id": (1, "i4", "-1"),
    "bary": (3, "f4", "vec3(0.0)"),
    "position": (3, "f4", "vec3(0.0)"),
    "normal": (3, "f4", "vec3(0.0)"),
    "uv": (2, "f4", "vec2(0.0)"),
    "duv_dx": (2, "f4", "vec2(0.0)"),
    "duv_dy": (2, "f4", "vec2(0.0)"),
    "lod": (1, "f4", "0.0"),
    "dyadic_scale": (1, "f4", "0.0"),
    "dposition_dx": (3, "f4", "vec3(0.0)"),
    "dposition_dy": (3, "f4", "vec3(0.0)"),
}
_DEPTH_CLIP_SLACK = 1e-6  # refnpr's relative slack of the per-sample near/far clip
_LOD_FLOOR = "5.421010862427522e-20LF"  # 2**-64
_GLSL = {1: "float", 2: "vec2", 3: "vec3", 4: "vec4"}
_DGLSL = {1: "double", 2: "dvec2", 3: "dvec3", 4: "dvec4"}
_ZERO = {1: "0.0", 2: "vec2(0.0)", 3: "vec3(0.0)", 4: "vec4(0.0)"}


@dataclass(frozen=True)
class Column:
    """A per-vertex quantity in the vertex table: name, first column, components."""

    name: str
    start: int
    width: int


def _attribute_widths(case: Case) -> dict[str, int]:
    meshes = case.meshes
    names = set(meshes[0].attributes)
    for m in meshes[1:]:
        names &= set(m.attributes)
    out = {}
    for a in sorted(names):
        arr = meshes[0].attributes[a]
        out[a] = 1 if arr.ndim == 1 else int(arr.shape[1])
    return out


def channel_layout(case: Case, channels: list[str]) -> dict[str, tuple[int, str]]:
    """Channel -> (components, dtype) for ``channels`` of ``case`` (built-ins and attributes)."""
    attrs = _attribute_widths(case)
    out = {}
    for c in channels:
        if c in BUILTIN:
            out[c] = BUILTIN[c][:2]
        elif c == "coverage":
            out[c] = (1, "f4")
        elif c in attrs:
            out[c] = (attrs[c], "f4")
        elif c.startswith("d") and c[-3:] in ("_dx", "_dy") and c[1:-3] in attrs:
            out[c] = (attrs[c[1:-3]], "f4")
        else:
            raise ValueError(
                f"channels: unknown channel {c!r} for case {case.name!r}; built-ins are "
                f"{sorted(BUILTIN)} and the meshes' attributes {sorted(attrs)}"
            )
    return out


def _vertex_table(case: Case, quantities: list[str]) -> tuple[np.ndarray, list[Column]]:
    """(N, S) float64 of the concatenated meshes' uv / position / normal / attributes."""
    cols, parts, start = [], [], 0
    for q in quantities:
        arrays = []
        for m in case.meshes:
            a = {"uv": m.uv, "position": m.positions, "normal": m.normals}.get(q)
            if q not in ("uv", "position", "normal"):
                a = m.attributes.get(q)
            if a is None:
                raise ValueError(f"case {case.name!r}: mesh {m.name!r} has no {q!r} data")
            arrays.append(np.asarray(a, dtype=np.float64).reshape(a.shape[0], -1))
        block = np.concatenate(arrays)
        cols.append(Column(q, start, block.shape[1]))
        parts.append(block)
        start += block.shape[1]
    n = sum(m.positions.shape[0] for m in case.meshes)
    table = np.concatenate(parts, axis=1) if parts else np.zeros((n, 1))
    return np.ascontiguousarray(table, dtype=np.float64), cols


def _glsl_double(x: float) -> str:
    return f"{float(x)!r}LF"


_COMPUTE_CLIP = """
#version 450 core
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Pos { double pos[]; };
layout(std430, binding = 1) writeonly buffer Clip { dvec4 clip[]; };
uniform double vp[16];
uniform int n_verts;
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= n_verts) return;
    double x = pos[3 * i], y = pos[3 * i + 1], z = pos[3 * i + 2];
    precise dvec4 c;
    for (int r = 0; r < 4; ++r) {
        // refnpr's evaluation order, no contraction: ((a x + b y) + c z) + d
        precise double ax = vp[4 * r] * x;
        precise double by = vp[4 * r + 1] * y;
        precise double cz = vp[4 * r + 2] * z;
        precise double s = ((ax + by) + cz) + vp[4 * r + 3];
        c[r] = s;
    }
    clip[i] = c;
}
"""

_HEADER = """
#version 450 core
layout(std430, binding = 1) readonly buffer Clip { dvec4 clip[]; };
layout(std430, binding = 2) readonly buffer Faces { int faces[]; };
layout(std430, binding = 3) readonly buffer TriMesh { int tri_mesh[]; };
layout(std430, binding = 4) readonly buffer VTab { double vtab[]; };
const int STRIDE = @STRIDE@;
"""


_SNAP = """
    // refnpr's vertex snapping: a vertex inside every clip plane (guard band G) is moved to its
    // position rounded to 1/256 PIXEL (round half up), which lies on GL's sub-pixel grid of the
    // n-times sample grid, so GL's coverage is decided on the same snapped triangle as refnpr's
    const double W_ = @W@, H_ = @H@, G_ = @G@;
    if (c.z + c.w >= 0.0LF && c.w - c.z >= 0.0LF && c.x + G_ * c.w >= 0.0LF
            && G_ * c.w - c.x >= 0.0LF && c.y + G_ * c.w >= 0.0LF && G_ * c.w - c.y >= 0.0LF) {
        double X = floor((c.x / c.w + 1.0LF) * (0.5LF * W_) * 256.0LF + 0.5LF);
        double Y = floor((1.0LF - c.y / c.w) * (0.5LF * H_) * 256.0LF + 0.5LF);
        double nx = 2.0LF * (X / 256.0LF) / W_ - 1.0LF;
        double ny = 2.0LF * (Y / 256.0LF) / H_ - 1.0LF;  // image row -> NDC of the flipped target
        gl_Position = vec4(nx * c.w, ny * c.w, c.z, c.w);
    }
"""


def _vertex_source(
    cols: list[Column], quad: bool, snap: tuple[int, int, float] | None = None
) -> str:
    out = [_HEADER]
    body = ["    dvec4 c = clip[gl_VertexID];", "    gl_Position = vec4(c.x, -c.y, c.z, c.w);"]
    if snap is not None:
        w, h, g = snap
        body.append(
            _SNAP.replace("@W@", f"{float(w)!r}LF")
            .replace("@H@", f"{float(h)!r}LF")
            .replace("@G@", f"{float(g)!r}LF")
        )
    if quad:
        for col in cols:
            out.append(f"out {_GLSL[col.width]} v_{col.name};")
            comps = ", ".join(
                f"float(vtab[STRIDE * gl_VertexID + {col.start + k}])" for k in range(col.width)
            )
            body.append(f"    v_{col.name} = {_GLSL[col.width]}({comps});")
        out.append("out float v_zclip;")
        body.append("    v_zclip = float(c.z);")
    out += ["void main() {", *body, "}"]
    return "\n".join(out)


def _fragment_source(
    layout: dict[str, tuple[int, str]],
    cols: list[Column],
    *,
    quad: bool,
    n: int,
    nw: int,
    nh: int,
    near: float,
    far: float,
    texture_size: tuple[int, int] | None,
    line_period: float,
    dyadic_coord: str,
) -> str:
    src = [_HEADER]
    for k, (name, (comps, dtype)) in enumerate(layout.items()):
        typ = "int" if dtype == "i4" else _GLSL[comps]
        src.append(f"layout(location = {k}) out {typ} o_{name};")
    if quad:
        for col in cols:
            src.append(f"in {_GLSL[col.width]} v_{col.name};")
        src.append("in float v_zclip;")
    d = _glsl_double
    q_lo = (1.0 - _DEPTH_CLIP_SLACK) / far
    q_hi = (1.0 + _DEPTH_CLIP_SLACK) / near
    b = [
        "void main() {",
        "    int t = gl_PrimitiveID;",
        "    int i0 = faces[3 * t], i1 = faces[3 * t + 1], i2 = faces[3 * t + 2];",
        "    dvec4 c0 = clip[i0], c1 = clip[i1], c2 = clip[i2];",
        # refnpr _lam_rows: M^-1 S for M = [[x0 x1 x2], [y0 y1 y2], [w0 w1 w2]]
        "    double x0 = c0.x, x1 = c1.x, x2 = c2.x;",
        "    double y0 = c0.y, y1 = c1.y, y2 = c2.y;",
        "    double w0 = c0.w, w1 = c1.w, w2 = c2.w;",
        "    precise double a00 = y1 * w2 - y2 * w1, a01 = x2 * w1 - x1 * w2,"
        " a02 = x1 * y2 - x2 * y1;",
        "    precise double a10 = y2 * w0 - y0 * w2, a11 = x0 * w2 - x2 * w0,"
        " a12 = x2 * y0 - x0 * y2;",
        "    precise double a20 = y0 * w1 - y1 * w0, a21 = x1 * w0 - x0 * w1,"
        " a22 = x0 * y1 - x1 * y0;",
        "    precise double det = x0 * a00 + x1 * a10 + x2 * a20;",
        "    if (det == 0.0LF) discard;",
        "    precise double inv = 1.0LF / det;",
        f"    const double sxx = 2.0LF / {d(nw)}, sx1 = 1.0LF / {d(nw)} - 1.0LF;",
        f"    const double syy = -2.0LF / {d(nh)}, sy1 = 1.0LF - 1.0LF / {d(nh)};",
        "    precise dvec3 L0 = dvec3(a00 * inv * sxx, a01 * inv * syy,"
        " (a00 * sx1 + a01 * sy1 + a02) * inv);",
        "    precise dvec3 L1 = dvec3(a10 * inv * sxx, a11 * inv * syy,"
        " (a10 * sx1 + a11 * sy1 + a12) * inv);",
        "    precise dvec3 L2 = dvec3(a20 * inv * sxx, a21 * inv * syy,"
        " (a20 * sx1 + a21 * sy1 + a22) * inv);",
        "    double sx = floor(double(gl_FragCoord.x)), sy = floor(double(gl_FragCoord.y));",
        "    precise dvec3 qp = L0 + L1 + L2;",
        "    precise double qv = qp.x * sx + qp.y * sy + qp.z;",
        f"    if (!(qv >= {d(q_lo)} && qv <= {d(q_hi)})) discard;",
        "    precise double l0 = L0.x * sx + L0.y * sy + L0.z;",
        "    precise double l1 = L1.x * sx + L1.y * sy + L1.z;",
        "    precise double l2 = L2.x * sx + L2.y * sy + L2.z;",
        "    precise double inv_q = 1.0LF / (l0 + l1 + l2);",
        # depth test value w / far in [near / far, 1]: float32 keeps 1/w to 6e-8 relative
        f"    gl_FragDepth = float((1.0LF / qv) / {d(far)});",
    ]
    if not quad:
        b += [
            f"    const double n_ = {d(n)};",
            "    double ax0 = L0.x * n_, ax1 = L1.x * n_, ax2 = L2.x * n_;",
            "    double ay0 = L0.y * n_, ay1 = L1.y * n_, ay2 = L2.y * n_;",
            "    double qx = ax0 + ax1 + ax2, qy = ay0 + ay1 + ay2;",
        ]
    for col in cols:
        w = col.width
        dt, ft = _DGLSL[w], _GLSL[w]
        if quad:
            val = f"v_{col.name}"
            b.append(f"    {ft} f_{col.name} = {val};")
            b.append(f"    {ft} dx_{col.name} = dFdx({val}) * {float(n)!r};")
            b.append(f"    {ft} dy_{col.name} = dFdy({val}) * {float(n)!r};")
            continue

        def fetch(i: str, col: Column = col, w: int = w, dt: str = dt) -> str:
            comps = ", ".join(f"vtab[STRIDE * {i} + {col.start + k}]" for k in range(w))
            return f"{dt}({comps})"

        b += [
            f"    {dt} F0_{col.name} = {fetch('i0')}, F1_{col.name} = {fetch('i1')},"
            f" F2_{col.name} = {fetch('i2')};",
        ]
        if col.name == "normal":
            b.append(
                f"    precise {dt} f_{col.name} = l0 * F0_{col.name} + l1 * F1_{col.name}"
                f" + l2 * F2_{col.name};"
            )
            continue
        b += [
            f"    precise {dt} f_{col.name} = (l0 * F0_{col.name} + l1 * F1_{col.name}"
            f" + l2 * F2_{col.name}) * inv_q;",
            f"    precise {dt} dx_{col.name} = (ax0 * F0_{col.name} + ax1 * F1_{col.name}"
            f" + ax2 * F2_{col.name} - f_{col.name} * qx) * inv_q;",
            f"    precise {dt} dy_{col.name} = (ay0 * F0_{col.name} + ay1 * F1_{col.name}"
            f" + ay2 * F2_{col.name} - f_{col.name} * qy) * inv_q;",
        ]
    for name, (comps, _dtype) in layout.items():
        b.append(_write(name, comps, quad, texture_size, line_period, dyadic_coord))
    b.append("}")
    return "\n".join(src + b)


def _write(
    name: str,
    comps: int,
    quad: bool,
    texture_size: tuple[int, int] | None,
    line_period: float,
    dyadic_coord: str,
) -> str:
    ft = _GLSL[comps]
    if name == "tri_id":
        return "    o_tri_id = t;"
    if name == "mesh_id":
        return "    o_mesh_id = tri_mesh[t];"
    if name == "depth":
        return "    o_depth = 1.0 / gl_FragCoord.w;" if quad else "    o_depth = float(inv_q);"
    if name == "ndc_z":
        # refnpr: z_clip interpolated (P / Q), divided by depth (1 / Q), in float64
        if quad:
            return "    o_ndc_z = v_zclip * gl_FragCoord.w;"
        return (
            "    { dvec3 Z = dvec3(c0.z, c1.z, c2.z);"
            " precise double z = (l0 * Z.x + l1 * Z.y + l2 * Z.z) * inv_q;"
            " o_ndc_z = float(z / inv_q); }"
        )
    if name == "bary":
        return "    o_bary = vec3(dvec3(l0 * inv_q, l1 * inv_q, l2 * inv_q));"
    if name == "normal":
        if quad:
            return "    { vec3 nn = f_normal; float len = length(nn);" \
                   " o_normal = len > 0.0 ? nn / len : vec3(0.0); }"  # fmt: skip
        return (
            "    { precise double len = sqrt(dot(f_normal, f_normal));"
            " double il = len > 0.0LF ? 1.0LF / len : 0.0LF;"
            " o_normal = vec3(f_normal * il); }"
        )
    if name == "lod":
        if texture_size is None:
            raise ValueError("raster_options: the lod channel needs texture_size")
        tw, th = (float(v) for v in texture_size)
        return (
            "    { dvec2 ddx = dvec2(vec2(dx_uv)), ddy = dvec2(vec2(dy_uv));"
            f" double rx = sqrt(ddx.x * {tw!r}LF * ddx.x * {tw!r}LF"
            f" + ddx.y * {th!r}LF * ddx.y * {th!r}LF);"
            f" double ry = sqrt(ddy.x * {tw!r}LF * ddy.x * {tw!r}LF"
            f" + ddy.y * {th!r}LF * ddy.y * {th!r}LF);"
            f" o_lod = log2(float(max(max(rx, ry), {_LOD_FLOOR}))); }}"
        )
    if name == "dyadic_scale":
        k = "y" if dyadic_coord == "v" else "x"
        return (
            f"    {{ double gx = double(float(dx_uv.{k})), gy = double(float(dy_uv.{k}));"
            f" double g = sqrt(gx * gx + gy * gy);"
            f" float s = -log2(float(max(g, {_LOD_FLOOR}))) - {math.log2(line_period)!r};"
            " o_dyadic_scale = clamp(s, -64.0, 64.0); }"
        )
    if name.startswith("d") and name.endswith(("_dx", "_dy")):
        q = name[1:-3]
        return f"    o_{name} = {ft}(d{name[-1]}_{q});"
    return f"    o_{name} = {ft}(f_{name});"


def _clear_source(layout: dict[str, tuple[int, str]]) -> str:
    src = ["#version 450 core"]
    body = []
    for k, (name, (comps, dtype)) in enumerate(layout.items()):
        typ = "int" if dtype == "i4" else _GLSL[comps]
        src.append(f"layout(location = {k}) out {typ} o_{name};")
        empty = BUILTIN[name][2] if name in BUILTIN else _ZERO[comps]
        body.append(f"    o_{name} = {empty};")
    return "\n".join(src + ["void main() {", *body, "}"])


def _coverage(gl: GL, tri_id: moderngl.Texture, n: int, size: tuple[int, int]):
    out = gl.empty(size, 1, "f4")
    gl.fullscreen(
        f"""
#version 450 core
uniform isampler2D tri_id;
out float o;
void main() {{
    ivec2 p = ivec2(gl_FragCoord.xy) * {n};
    int k = 0;
    for (int j = 0; j < {n}; ++j)
        for (int i = 0; i < {n}; ++i)
            k += texelFetch(tri_id, p + ivec2(i, j), 0).r >= 0 ? 1 : 0;
    o = float(k) / float({n * n});
}}""",
        out,
        {"tri_id": tri_id},
    )
    return out


class Uploaded:
    """Geometry of a case on the GPU (storage buffers), reusable across frames and passes."""

    def __init__(self, gl: GL, case: Case, quantities: list[str]) -> None:
        meshes = case.meshes
        offsets = np.cumsum([0] + [m.positions.shape[0] for m in meshes])
        self.positions = np.concatenate([m.positions for m in meshes])
        faces = np.concatenate([m.indices + o for m, o in zip(meshes, offsets[:-1], strict=True)])
        self.n_verts = int(self.positions.shape[0])
        self.n_faces = int(faces.shape[0])
        tri_mesh = np.concatenate([np.full(m.n_faces, m.mesh_id, dtype=np.int32) for m in meshes])
        table, self.cols = _vertex_table(case, quantities)
        self.stride = table.shape[1]
        ctx = gl.ctx
        self.pos = ctx.buffer(np.ascontiguousarray(self.positions, dtype=np.float64).tobytes())
        self.clip = ctx.buffer(reserve=max(32, 32 * self.n_verts))
        self.faces = ctx.buffer(np.ascontiguousarray(faces, dtype=np.int32).tobytes())
        self.index = ctx.buffer(np.ascontiguousarray(faces, dtype=np.uint32).tobytes())
        self.tri_mesh = ctx.buffer(tri_mesh.tobytes())
        self.vtab = ctx.buffer(table.tobytes())

    def release(self) -> None:
        for b in (self.pos, self.clip, self.faces, self.index, self.tri_mesh, self.vtab):
            b.release()


def _quantities(layout: dict[str, tuple[int, str]], attrs: set[str]) -> list[str]:
    want = set(layout)
    q = []
    if want & {"uv", "duv_dx", "duv_dy", "lod", "dyadic_scale"}:
        q.append("uv")
    if want & {"position", "dposition_dx", "dposition_dy"}:
        q.append("position")
    if "normal" in want:
        q.append("normal")
    for a in sorted(attrs):
        if want & {a, f"d{a}_dx", f"d{a}_dy"}:
            q.append(a)
    return q


def _draw(
    gl: GL,
    geo: Uploaded,
    prog: moderngl.Program,
    layout: dict[str, tuple[int, str]],
    targets: list[moderngl.Texture],
    size: tuple[int, int],
) -> None:
    """One G-buffer pass: clear ``targets`` to their empty values, draw every triangle with
    the depth test (float32 depth where raw GL is available)."""
    ctx = gl.ctx
    fbo = ctx.framebuffer(color_attachments=targets)
    depth32 = gl.depth32f(fbo, size)  # float32 depth: 1/w resolved to 6e-8 relative
    depth = None
    if depth32 is None:  # no raw GL entry points: moderngl's 24-bit depth texture
        fbo.release()
        depth = ctx.depth_texture(size)
        fbo = ctx.framebuffer(color_attachments=targets, depth_attachment=depth)
    try:
        fbo.use()
        ctx.viewport = (0, 0, *size)
        if depth is not None:
            fbo.clear(depth=1.0)
        else:
            gl.clear_depth32f()
        # empty values (inf, -1, 0) per channel, depth untouched
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        clear = gl.program(
            "#version 450 core\nvoid main() { vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0,"
            " float((gl_VertexID & 2) << 1) - 1.0); gl_Position = vec4(p, 0.0, 1.0); }",
            _clear_source(layout),
        )
        cvao = ctx.vertex_array(clear, [])
        cvao.render(moderngl.TRIANGLES, vertices=3)
        cvao.release()
        for k, buf in ((1, geo.clip), (2, geo.faces), (3, geo.tri_mesh), (4, geo.vtab)):
            buf.bind_to_storage_buffer(k)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        if depth is None:
            gl.depth_write(True)
        vao = ctx.vertex_array(prog, [], index_buffer=geo.index, index_element_size=4)
        vao.render(moderngl.TRIANGLES, vertices=3 * geo.n_faces)
        vao.release()
    finally:
        ctx.disable(moderngl.DEPTH_TEST)
        fbo.release()
        if depth is not None:
            depth.release()
        else:
            gl.delete_texture(depth32)


def rasterize(
    gl: GL,
    case: Case,
    channels: list[str] | None = None,
    *,
    derivatives: str = "analytic",
    camera: dict | None = None,
    uploaded: Uploaded | None = None,
    snap: bool = True,
) -> dict[str, moderngl.Texture]:
    """Rasterize ``case`` into G-buffer textures on its sample grid (array layout).

    Parameters
    ----------
    gl : GL
    case : Case
    channels : list of str, optional
        Default ``case.channels``. Float channels are R32F/RG32F/RGB32F/RGBA32F with refnpr's
        component count, tri_id and mesh_id R32I with -1 where empty; ``coverage`` is per pixel
        (W, H).
    derivatives : {"analytic", "quad"}
    camera : dict, optional
        A camera dict with "view_matrix", "projection_matrix", "near", "far" (default: the
        case's camera; multi-frame cases pass each frame's).
    uploaded : Uploaded, optional
        Geometry already on the GPU (from a previous call with the same quantities).
    snap : bool
        Snap vertices inside the clip volume to refnpr's 1/256-pixel grid before GL rasterizes
        them (default), so that coverage matches refnpr's fixed-point rasterizer; False leaves
        GL's own snapping (1/256 of a sample on llvmpipe).

    Returns
    -------
    dict channel -> moderngl.Texture of size (n W, n H) (coverage: (W, H)).
    """
    if derivatives not in DERIVATIVE_MODES:
        raise ValueError(f"derivatives: expected one of {DERIVATIVE_MODES}, got {derivatives!r}")
    channels = list(case.channels if channels is None else channels)
    if not channels:
        raise ValueError(f"channels: case {case.name!r} asks for no channels")
    layout_all = channel_layout(case, channels)
    want_cov = "coverage" in layout_all
    layout = {k: v for k, v in layout_all.items() if k != "coverage"}
    if want_cov and "tri_id" not in layout:
        layout["tri_id"] = BUILTIN["tri_id"][:2]
    if not layout:
        layout["tri_id"] = BUILTIN["tri_id"][:2]
    cam = camera or case.camera
    ro = case.raster_options
    ts = ro.get("texture_size")
    if ts is not None:
        ts = (int(ts), int(ts)) if np.isscalar(ts) else (int(ts[0]), int(ts[1]))
    line_period = float(ro.get("line_period", 1.0))
    dyadic_coord = ro.get("dyadic_coord", "v")
    n = case.n
    nw, nh = case.sample_size
    quad = derivatives == "quad"
    attrs = set(_attribute_widths(case))
    quantities = _quantities(layout, attrs)
    geo = uploaded or Uploaded(gl, case, quantities)
    if [c.name for c in geo.cols] != quantities and not (not quantities and not geo.cols):
        geo = Uploaded(gl, case, quantities)
    ctx = gl.ctx
    vp = np.asarray(cam["projection_matrix"], np.float64) @ np.asarray(
        cam["view_matrix"], np.float64
    )
    near, far = float(cam["near"]), float(cam["far"])
    guard = min(16.0, 2.0 * 2.0**30 / (max(nw, nh) * 512.0) - 1.0)  # refnpr's guard band

    # vertex stage: clip = VP p in float64 (compute shader)
    cs = gl.compute(_COMPUTE_CLIP)
    cs["vp"].write(np.ascontiguousarray(vp.ravel(), dtype=np.float64).tobytes())
    cs["n_verts"].value = geo.n_verts
    geo.pos.bind_to_storage_buffer(0)
    geo.clip.bind_to_storage_buffer(1)
    cs.run(group_x=-(-geo.n_verts // 64))
    ctx.memory_barrier()

    targets = {
        name: gl.empty((nw, nh), comps, "i4" if dt == "i4" else "f4")
        for name, (comps, dt) in layout.items()
    }
    vs = _vertex_source(geo.cols, quad, (case.width, case.height, guard) if snap else None)
    vs = vs.replace("@STRIDE@", str(geo.stride))
    # at most GL_MAX_DRAW_BUFFERS (8 on llvmpipe) render targets per pass: more channels are
    # drawn in several passes over the same geometry (each with its own depth test, so every
    # pass resolves visibility identically)
    per_pass = max(1, int(ctx.info.get("GL_MAX_DRAW_BUFFERS", 8)))
    names = list(layout)
    try:
        for first in range(0, len(names), per_pass):
            group = {k: layout[k] for k in names[first : first + per_pass]}
            fs = _fragment_source(
                group,
                geo.cols,
                quad=quad,
                n=n,
                nw=nw,
                nh=nh,
                near=near,
                far=far,
                texture_size=ts,
                line_period=line_period,
                dyadic_coord=dyadic_coord,
            ).replace("@STRIDE@", str(geo.stride))
            _draw(gl, geo, gl.program(vs, fs), group, [targets[k] for k in group], (nw, nh))
    finally:
        if uploaded is None:
            geo.release()
    if want_cov:
        targets["coverage"] = _coverage(gl, targets["tri_id"], n, (case.width, case.height))
        if "tri_id" not in layout_all:
            targets.pop("tri_id").release()
    return {c: targets[c] for c in channels}
