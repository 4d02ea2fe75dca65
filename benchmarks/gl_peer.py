"""Mesa llvmpipe peer: the full refnpr G-buffer rendered by OpenGL 4.5 (moderngl, EGL, headless).

The peer draws one indexed triangle mesh with the camera's ``projection @ view`` matrix used
verbatim in the vertex shader and writes, per fragment, into float32 multiple render targets:

====================  =========  ==========================================================
attachment            format     value
====================  =========  ==========================================================
0  ``depth``          R32F       ``1 / gl_FragCoord.w`` = w_clip, the view-axis distance
1  ``tri_id``         R32F       ``float(gl_PrimitiveID)`` (exact below 2**24 triangles)
2  ``uv``             RG32F      perspective-correct uv
3  ``duv_dx``         RG32F      ``dFdx(uv)`` (GL's own derivative, per 2x2 quad)
4  ``duv_dy``         RG32F      ``dFdy(uv)`` (GL's window y points *up*)
5  ``normal``         RGBA32F    ``normalize(n)``, read back as 3 components
====================  =========  ==========================================================

plus a 24-bit depth renderbuffer with ``GL_LESS``. That is the ``"six"`` layout. The ``"packed"``
layout (``open_peer(..., layout="packed")``, usually the faster on llvmpipe: fewer render targets
to blend and store per fragment, three large reads) writes the same eleven floats into three
RGBA32F textures plus a depth texture:

==========  ==============================================
attachment  value (RGBA32F)
==========  ==============================================
0           ``uv.x, uv.y, dFdx(uv).x, dFdx(uv).y``
1           ``dFdy(uv).x, dFdy(uv).y, tri_id, depth (w)``
2           ``normal.x, normal.y, normal.z, 0``
==========  ==============================================

and its ``readback`` returns the same named arrays, as views into the three RGBA reads.

The ``"plain"`` layout is the configuration a GPU user writes: one draw pass whose fragment shader
writes the attributes and their quad derivatives into three RGBA32F colour textures, depth in a
depth texture (the depth buffer itself, no colour copy of it), and a readback with
``Framebuffer.read_into`` into numpy arrays allocated once when the peer is opened (a
``glReadPixels`` into memory that is already mapped: no per-frame allocation, no first-touch page
faults; ``fbo.read`` in the other two layouts returns fresh ``bytes`` every frame):

============  ==============================================
attachment    value
============  ==============================================
0 (RGBA32F)   ``uv.x, uv.y, dFdx(uv).x, dFdx(uv).y``
1 (RGBA32F)   ``dFdy(uv).x, dFdy(uv).y, tri_id, 0``
2 (RGBA32F)   ``normal.x, normal.y, normal.z, 0``
depth         window-space depth in [0, 1] (``DEPTH_COMPONENT24`` texture), read as float32
============  ==============================================

Its ``readback`` returns ``depth_window`` instead of ``depth``; :meth:`GLPeer.refnpr_convention`
turns it into the view-axis distance w (``z_ndc = a + b / w``, with ``a``, ``b`` taken from the
view-projection matrix's z and w rows) outside the timed readback.

``"six_into"`` is the ``six`` layout read the plain way: ``read_into`` the attachments' own
preallocated arrays (``normal`` as RGB), no per-frame allocation.

In every layout the depth test is ``GL_LESS`` (the first-drawn, i.e. lower, triangle wins a
tie, as in refnpr). Every colour attachment is cleared to -1 (so ``tri_id`` is -1 where empty),
depth to 1.

Timings: ``render`` is clear + draw + ``glFinish``; ``readback`` is one ``glReadPixels`` per
attachment into host memory. The vertex and index buffers are uploaded once (``setup``), like a
GPU backend that keeps its mesh resident. Arrays come back in GL's window orientation (row 0 is the
*bottom* row); :func:`to_refnpr_convention` (or :meth:`GLPeer.refnpr_convention`, which also
converts the plain layout's window depth) flips them to refnpr's (row 0 on top, d/dy downward).

Needs ``moderngl`` and a working EGL (on Debian: libegl1, libgl1-mesa-dri, libegl-mesa0). Set
``LP_NUM_THREADS`` before the first context is created to choose llvmpipe's thread count.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

__all__ = [
    "ATTACHMENTS",
    "LAYOUTS",
    "GLPeer",
    "GLUnavailable",
    "clip_z_ab",
    "open_peer",
    "to_refnpr_convention",
    "window_depth_to_w",
]

#: (channel name, texture components, components read back)
ATTACHMENTS: tuple[tuple[str, int, int], ...] = (
    ("depth", 1, 1),
    ("tri_id", 1, 1),
    ("uv", 2, 2),
    ("duv_dx", 2, 2),
    ("duv_dy", 2, 2),
    ("normal", 4, 3),
)

VERTEX_SHADER = """
#version 450 core
uniform mat4 u_view_projection;   // camera.projection_matrix(W, H) @ camera.view_matrix()
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 v_normal;
out vec2 v_uv;
void main() {
    v_normal = in_normal;
    v_uv = in_uv;
    gl_Position = u_view_projection * vec4(in_position, 1.0);
}
"""

FRAGMENT_SHADER = """
#version 450 core
in vec3 v_normal;
in vec2 v_uv;
layout(location = 0) out float out_depth;
layout(location = 1) out float out_tri_id;
layout(location = 2) out vec2 out_uv;
layout(location = 3) out vec2 out_duv_dx;
layout(location = 4) out vec2 out_duv_dy;
layout(location = 5) out vec4 out_normal;
void main() {
    out_depth = 1.0 / gl_FragCoord.w;       // w_clip: view-axis distance
    out_tri_id = float(gl_PrimitiveID);
    out_uv = v_uv;
    out_duv_dx = dFdx(v_uv);
    out_duv_dy = dFdy(v_uv);                // window y is bottom-up in GL
    out_normal = vec4(normalize(v_normal), 0.0);
}
"""

FRAGMENT_SHADER_PACKED = """
#version 450 core
in vec3 v_normal;
in vec2 v_uv;
layout(location = 0) out vec4 out_uv_dx;    // uv, dFdx(uv)
layout(location = 1) out vec4 out_dy_id_w;  // dFdy(uv), tri_id, w_clip
layout(location = 2) out vec4 out_normal;   // normalize(n), 0
void main() {
    out_uv_dx = vec4(v_uv, dFdx(v_uv));
    out_dy_id_w = vec4(dFdy(v_uv), float(gl_PrimitiveID), 1.0 / gl_FragCoord.w);
    out_normal = vec4(normalize(v_normal), 0.0);
}
"""
FRAGMENT_SHADER_PLAIN = """
#version 450 core
in vec3 v_normal;
in vec2 v_uv;
layout(location = 0) out vec4 out_uv_dx;    // uv, dFdx(uv)
layout(location = 1) out vec4 out_dy_id;    // dFdy(uv), tri_id, 0
layout(location = 2) out vec4 out_normal;   // normalize(n), 0
void main() {
    out_uv_dx = vec4(v_uv, dFdx(v_uv));
    out_dy_id = vec4(dFdy(v_uv), float(gl_PrimitiveID), 0.0);
    out_normal = vec4(normalize(v_normal), 0.0);
}
"""
#: Layouts (module docstring): six per-channel attachments; three RGBA32F with w in a colour
#: channel, read with ``fbo.read``; three RGBA32F + depth texture read with ``read_into``; the
#: six attachments read with ``read_into``.
LAYOUTS = ("six", "packed", "plain", "six_into")
_FRAGMENT = {
    "six": FRAGMENT_SHADER,
    "packed": FRAGMENT_SHADER_PACKED,
    "plain": FRAGMENT_SHADER_PLAIN,
    "six_into": FRAGMENT_SHADER,
}


class GLUnavailable(RuntimeError):
    """No headless OpenGL 4.5 context could be made (moderngl or EGL missing, or too old a GL)."""


@dataclass
class GLPeer:
    """A ready-to-draw llvmpipe pipeline for one mesh at one image size."""

    ctx: object
    fbo: object
    vao: object
    program: object
    width: int
    height: int
    setup_s: float
    layout: str = "six"
    #: ``z_clip = a * w_clip + b`` (taken from the view-projection matrix): window depth -> w
    clip_z_ab: tuple[float, float] = (0.0, 0.0)
    #: ``read_into`` targets (plain: three (H, W, 4) and one (H, W); six_into: one per attachment)
    host: tuple[np.ndarray, ...] = ()

    @property
    def renderer(self) -> str:
        with self.ctx:
            return str(self.ctx.info.get("GL_RENDERER", "?"))

    @property
    def version(self) -> str:
        with self.ctx:
            return str(self.ctx.info.get("GL_VERSION", "?"))

    def render(self) -> float:
        """Clear, draw and ``glFinish``; returns seconds."""
        t0 = time.perf_counter()
        with self.ctx:  # current on this thread: several peers may be open at once
            self.fbo.use()
            self.fbo.clear(-1.0, -1.0, -1.0, -1.0, depth=1.0)
            self.vao.render()
            self.ctx.finish()
        return time.perf_counter() - t0

    def readback(self) -> tuple[dict[str, np.ndarray], float]:
        """``glReadPixels`` of every attachment; returns ({name: (H, W[, C]) float32}, seconds).

        Arrays are in GL window orientation (row 0 = bottom row).
        """
        with self.ctx:  # current on this thread: several peers may be open at once
            return self._readback()

    def _readback(self) -> tuple[dict[str, np.ndarray], float]:
        out: dict[str, np.ndarray] = {}
        t0 = time.perf_counter()
        if self.layout == "plain":
            a0, a1, a2, zwin = self.host
            for i, dest in enumerate((a0, a1, a2)):
                self.fbo.read_into(dest, components=4, attachment=i, dtype="f4")
            self.fbo.read_into(zwin, components=1, attachment=-1, dtype="f4")
            t = time.perf_counter() - t0
            out = {
                "depth_window": zwin,
                "tri_id": a1[..., 2],
                "uv": a0[..., 0:2],
                "duv_dx": a0[..., 2:4],
                "duv_dy": a1[..., 0:2],
                "normal": a2[..., 0:3],
            }
            return out, t  # views of the peer's own arrays: the next readback overwrites them
        if self.layout == "six_into":
            for i, ((name, _, comps), dest) in enumerate(zip(ATTACHMENTS, self.host, strict=True)):
                self.fbo.read_into(dest, components=comps, attachment=i, dtype="f4")
                out[name] = dest
            return out, time.perf_counter() - t0
        if self.layout == "packed":
            a0, a1, a2 = (
                np.frombuffer(
                    self.fbo.read(components=4, attachment=i, dtype="f4"), dtype=np.float32
                ).reshape(self.height, self.width, 4)
                for i in range(3)
            )
            t = time.perf_counter() - t0
            out = {
                "depth": a1[..., 3],
                "tri_id": a1[..., 2],
                "uv": a0[..., 0:2],
                "duv_dx": a0[..., 2:4],
                "duv_dy": a1[..., 0:2],
                "normal": a2[..., 0:3],
            }
            return out, t
        for i, (name, _, comps) in enumerate(ATTACHMENTS):
            raw = self.fbo.read(components=comps, attachment=i, dtype="f4")
            shape = (self.height, self.width) if comps == 1 else (self.height, self.width, comps)
            out[name] = np.frombuffer(raw, dtype=np.float32).reshape(shape)
        return out, time.perf_counter() - t0

    def refnpr_convention(self, gl: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """:func:`to_refnpr_convention`, with the plain layout's ``depth_window`` turned into w."""
        if "depth_window" in gl:
            gl = dict(gl)
            gl["depth"] = window_depth_to_w(gl.pop("depth_window"), *self.clip_z_ab)
        return to_refnpr_convention(gl)

    def release(self) -> None:
        with self.ctx:
            for obj in (self.vao, self.fbo, self.program):
                obj.release()
        self.ctx.release()


def open_peer(
    positions: np.ndarray,
    faces: np.ndarray,
    normals: np.ndarray,
    uv: np.ndarray,
    view_projection: np.ndarray,
    width: int,
    height: int,
    *,
    layout: str = "six",
) -> GLPeer:
    """Make an EGL context, upload the mesh and build the MRT framebuffer.

    Parameters
    ----------
    positions, normals : (N, 3) float
    faces : (M, 3) int
    uv : (N, 2) float
    view_projection : (4, 4) float64
        ``projection_matrix(width, height) @ view_matrix()`` (row-major numpy; uploaded transposed
        because GL matrices are column-major).
    width, height : int
    layout : {"six", "packed", "plain", "six_into"}
        Six per-channel attachments; three RGBA32F ones plus a depth texture, w in a colour
        channel, read with ``fbo.read``; the plain GPU layout, three RGBA32F and the depth
        texture read with ``read_into`` into preallocated arrays; or the six attachments read
        with ``read_into`` (module docstring).

    Raises
    ------
    GLUnavailable
        With the reason, if moderngl is missing or no EGL/GL 4.5 context can be created.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"layout: expected one of {LAYOUTS}, got {layout!r}")
    t0 = time.perf_counter()
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise GLUnavailable(f"moderngl is not installed ({exc}); pip install moderngl") from exc
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=450)
    except Exception as exc:  # moderngl raises plain Exception for EGL failures
        raise GLUnavailable(
            f"no EGL OpenGL 4.5 context ({type(exc).__name__}: {exc}); on Debian install "
            "libegl1 libgl1-mesa-dri libegl-mesa0"
        ) from exc
    fragment = _FRAGMENT[layout]
    prog = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=fragment)
    prog["u_view_projection"].write(np.asarray(view_projection, dtype="f4").T.copy().tobytes())
    verts = np.hstack(
        [
            np.asarray(positions, dtype="f4"),
            np.asarray(normals, dtype="f4"),
            np.asarray(uv, dtype="f4"),
        ]
    )
    vbo = ctx.buffer(np.ascontiguousarray(verts).tobytes())
    ibo = ctx.buffer(np.ascontiguousarray(faces, dtype="u4").tobytes())
    vao = ctx.vertex_array(
        prog,
        [(vbo, "3f 3f 2f", "in_position", "in_normal", "in_uv")],
        index_buffer=ibo,
        index_element_size=4,
    )
    size = (int(width), int(height))
    if layout in ("packed", "plain"):
        colors = [ctx.texture(size, 4, dtype="f4") for _ in range(3)]
        depth = ctx.depth_texture(size)
    else:
        colors = [ctx.renderbuffer(size, components=c, dtype="f4") for _, c, _ in ATTACHMENTS]
        depth = ctx.depth_renderbuffer(size)
    fbo = ctx.framebuffer(color_attachments=colors, depth_attachment=depth)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.depth_func = "<"
    ctx.disable(moderngl.CULL_FACE)
    fbo.use()
    fbo.viewport = (0, 0, size[0], size[1])
    host: tuple[np.ndarray, ...] = ()
    if layout == "plain":
        # allocated and touched once: every readback lands in memory that is already mapped
        host = tuple(np.zeros((size[1], size[0], 4), np.float32) for _ in range(3))
        host += (np.zeros((size[1], size[0]), np.float32),)
    elif layout == "six_into":
        host = tuple(
            np.zeros((size[1], size[0]) + ((comps,) if comps > 1 else ()), np.float32)
            for _, _, comps in ATTACHMENTS
        )
    peer = GLPeer(
        ctx, fbo, vao, prog, size[0], size[1], 0.0, layout, clip_z_ab(view_projection), host
    )
    peer.render()  # llvmpipe JIT-compiles the shaders on the first draw: keep that out of the runs
    peer.readback()
    peer.setup_s = time.perf_counter() - t0
    return peer


def clip_z_ab(view_projection: np.ndarray) -> tuple[float, float]:
    """(a, b) with ``z_clip = a * w_clip + b`` for every point, read off a perspective
    view-projection matrix (its z row is a times its w row plus b in the last column), so that
    ``z_ndc = a + b / w``. Raises ``ValueError`` for a matrix without that form (orthographic)."""
    m = np.asarray(view_projection, dtype=np.float64)
    zr, wr = m[2], m[3]
    a = float(zr[:3] @ wr[:3] / (wr[:3] @ wr[:3]))
    b = float(zr[3] - a * wr[3])
    if not np.allclose(zr[:3], a * wr[:3], rtol=1e-9, atol=1e-12 * np.abs(zr).max()):
        raise ValueError("view_projection: z_clip is not a * w_clip + b (not a perspective matrix)")
    return a, b


def window_depth_to_w(depth_window: np.ndarray, a: float, b: float) -> np.ndarray:
    """View-axis distance w (float32) from window depth in [0, 1] (``glDepthRange(0, 1)``)."""
    z_ndc = 2.0 * np.asarray(depth_window, dtype=np.float64) - 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return (b / (z_ndc - a)).astype(np.float32)


def to_refnpr_convention(gl: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Flip GL readbacks to refnpr's convention: row 0 on top, ``duv_dy`` downward, int tri ids.

    ``depth`` becomes +inf where empty, ``tri_id`` int32 with -1 where empty.
    """
    out = {k: np.ascontiguousarray(v[::-1]) for k, v in gl.items()}
    tri = np.rint(out["tri_id"]).astype(np.int32)
    empty = tri < 0
    tri[empty] = -1
    out["tri_id"] = tri
    if "duv_dy" in out:
        out["duv_dy"] = -out["duv_dy"]  # GL's dFdy is along +y of the window = upward on screen
    if "depth" in out:
        depth = out["depth"].copy()
        depth[empty] = np.inf
        out["depth"] = depth
    return out
