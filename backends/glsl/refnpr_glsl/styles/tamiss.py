"""TAMISS (Szécsi, Szirányi, Kacsó) on the GPU, the way the paper does it.

Passes (shaders in ``shaders/tamiss/``), all on the GPU; numpy only packs the kit's data into
buffers and reads back two counts (fragments, strokes) to size the next buffers:

1. ``gather.comp`` (compute, per G-buffer sample): the stroke field's inputs (uv, smooth
   d(uv)/d(x, y) from the per-vertex tangent frames, chart orientation, darkness) and every
   stroke fragment (x, y, t, id) of the RPTAM field over the sample. Run twice: count, then emit
   at the offsets of ``scan.comp`` (exclusive prefix sum), so that the fragment buffer is in
   refnpr's order (sample, layer, level, row, cell).
2. ``route.comp``: each fragment finds its stroke's slot in a table of 2^j slots by double
   hashing of the 32-bit key of its id (refnpr's h1, h2); slots are claimed with
   atomicCompSwap; the full 64-bit id decides (aliases of a key probe on), in rounds until every
   fragment has a slot: exact aggregation, no stroke dropped.
3. ``agg.vert``: one point per fragment into its slot's texel of float render targets: MIN and
   MAX blending of (t, x, y), then the 15 regressors in float32 with additive blending (four
   RGBA32F targets), blended in fragment order as refnpr sums.
4. ``order.comp``: the claimed slots listed and ranked by id (refnpr's stroke order).
5. ``fit.comp`` (compute, per stroke): Legendre-basis CG fit of x(t), y(t), v(t) in float32,
   drop rule, visible segments (bisection in double), extent, and the extruded strip (double).
6. ``strip.vert`` / ``strip.frag``: one instanced quad per piece over its bounding box; the
   fragment shader computes the union coverage of the strip's triangles on aa x aa sub-samples
   and the brush, blended "over" in piece order into an RGBA32F target.
7. ``compose.frag``: ink over the paper (or the show view's colours).

``aggregation = "hashed"`` replaces pass 2 by the paper's table pair across frames
(``route_hashed.comp``: read-only last-frame table, write-only new one, atomicMin claims,
``warmup_frames`` + 1 routings of the still frame, contested slots not drawn), as refnpr's
``StrokeHashTable`` does it.

Not implemented (no golden case uses them): ``dtype = "float64"`` sums, ``base`` styles and the
aggregate history of multi-frame cases. They raise ``ValueError``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import moderngl
import numpy as np

__all__ = ["shade", "shader_source", "SHOWS", "EXTENTS"]

_DIR = Path(__file__).resolve().parent.parent / "shaders" / "tamiss"
_HEADER = (
    "#version 450 core\n#extension GL_ARB_gpu_shader_int64 : require\n"
    "#extension GL_ARB_gpu_shader_fp64 : enable\n"
)
SHOWS = ("color", "ids", "fits", "strokes", "levels")
EXTENTS = ("visible", "range", "stroke", "overdraw")
_EMPTY = 0xFFFFFFFF
_MAX_ROUNDS = 32
_MAX_PROBES = 64

#: Set to a dict to keep read-backs of the intermediate buffers of the last ``shade`` (tests).
DEBUG: dict | None = None


def shader_source(name: str, *, common: bool = True) -> str:
    """The GLSL source of ``shaders/tamiss/<name>`` with the version, extensions and (for the
    shaders that hash ids) ``common.glsl`` prepended."""
    body = (_DIR / name).read_text()
    pre = (_DIR / "common.glsl").read_text() if common else ""
    return _HEADER + pre + "\n" + body


def _param(params: dict[str, Any], key: str) -> Any:
    if key not in params:
        raise ValueError(
            f"style.params: missing key {key!r} (export the kit with refnpr's tamiss module)"
        )
    return params[key]


def _ssbo(ctx: moderngl.Context, data: np.ndarray | bytes, binding: int) -> moderngl.Buffer:
    raw = data.tobytes() if isinstance(data, np.ndarray) else data
    buf = ctx.buffer(raw if len(raw) else b"\0" * 16)
    buf.bind_to_storage_buffer(binding)
    return buf


def _scene_buffers(case: Any) -> dict[str, np.ndarray]:
    """Faces (global vertex indices), frames (V x 6 float64: hi + lo), chart data (V x 8)."""
    faces, frames, charts = [], [], []
    v_off = 0
    for k, m in enumerate(case.meshes):
        a = m.attributes
        need = ("tamiss_frame_u", "tamiss_frame_v", "tamiss_chart", "tamiss_chart_map",
                "tamiss_chart_offset", "tamiss_chart_group")  # fmt: skip
        missing = [n for n in need if n not in a]
        if missing:
            raise ValueError(
                f"case {case.name!r}: mesh of object {k} lacks the attributes "
                f"{['_' + n.upper() for n in missing]} (export with refnpr's tamiss kit module)"
            )
        fu = a["tamiss_frame_u"] + a.get("tamiss_frame_u_lo", 0.0)
        fv = a["tamiss_frame_v"] + a.get("tamiss_frame_v_lo", 0.0)
        frames.append(np.concatenate([fu, fv], axis=1))
        ch = np.concatenate(
            [
                a["tamiss_chart_map"].reshape(-1, 4),
                a["tamiss_chart_offset"].reshape(-1, 2),
                a["tamiss_chart_group"].reshape(-1, 1),
                a["tamiss_chart"].reshape(-1, 1),
            ],
            axis=1,
        )
        charts.append(ch)
        faces.append(np.asarray(m.indices, dtype=np.int64) + v_off)
        v_off += m.positions.shape[0]
    return {
        "faces": np.ascontiguousarray(np.concatenate(faces), dtype=np.int32),
        "frames": np.ascontiguousarray(np.concatenate(frames), dtype=np.float64),
        "charts": np.ascontiguousarray(np.concatenate(charts), dtype=np.float32),
    }


def _objects(case: Any) -> np.ndarray:
    rows = []
    for m in case.meshes:
        mat = m.material
        amb = np.broadcast_to(np.asarray(mat.get("ambient", 0.0), dtype=np.float64), (3,))
        dif = np.broadcast_to(np.asarray(mat.get("diffuse", 0.0), dtype=np.float64), (3,))
        sc = np.broadcast_to(np.asarray(mat.get("uv_scale", 1.0), dtype=np.float64), (2,))
        rows.append(np.concatenate([amb, dif, sc]))
    return np.ascontiguousarray(np.array(rows, dtype=np.float64))


def _lights(case: Any) -> np.ndarray:
    rows = []
    for i, light in enumerate(case.lights):
        color = np.asarray(light["color"], dtype=np.float64)
        if light["kind"] == "point":
            rows.append([1.0, *np.asarray(light["position"], dtype=np.float64), *color, 0.0])
        elif light["kind"] == "directional":
            d = np.asarray(light["direction"], dtype=np.float64)
            rows.append([0.0, *(d / np.linalg.norm(d)), *color, 0.0])
        else:
            raise ValueError(
                f"lights[{i}].kind: expected 'directional' or 'point', got {light['kind']!r}"
            )
    return np.ascontiguousarray(np.array(rows, dtype=np.float64).reshape(-1, 8))


def _check(params: dict[str, Any]) -> None:
    if _param(params, "aggregation") not in ("exact", "hashed"):
        raise ValueError(
            f"style.params.aggregation: expected 'exact' or 'hashed', got {params['aggregation']!r}"
        )
    if _param(params, "dtype") != "float32":
        raise ValueError(
            f"style.params.dtype: the GLSL backend sums in float32, got {params['dtype']!r}"
        )
    if params.get("base") is not None:
        raise ValueError("style.params.base: a base style under the strokes is not supported")
    if params.get("show", "color") not in SHOWS:
        raise ValueError(
            f"style.params.show: expected one of {list(SHOWS)}, got {params['show']!r}"
        )
    if params.get("extent") not in EXTENTS:
        raise ValueError(
            f"style.params.extent: expected one of {list(EXTENTS)}, got {params['extent']!r}"
        )


def _groups(n: int, size: int) -> int:
    return max(1, (int(n) + size - 1) // size)


def _route_exact(gl: Any, counter: moderngl.Buffer, n_frags: int, m: int) -> int:
    """Rounds of ``route.comp`` until every fragment has its stroke's slot; returns the rounds."""
    route = gl.compute(shader_source("route.comp"))
    route["n_frags"].value = n_frags
    route["table_mask"].value = m - 1
    route["max_probes"].value = _MAX_PROBES
    pending = lost = 0
    for rnd in range(_MAX_ROUNDS):
        counter.write(np.zeros(2, np.uint32).tobytes())
        route["round_"].value = rnd
        route.run(_groups(n_frags, 64))
        gl.ctx.memory_barrier()
        pending, lost = np.frombuffer(counter.read(8), np.uint32)
        if pending == 0:
            break
    else:
        raise RuntimeError(f"tamiss: {pending} fragments unrouted after {_MAX_ROUNDS} rounds")
    if lost:
        raise RuntimeError(f"tamiss: {lost} fragments found no slot in {_MAX_PROBES} probes")
    return rnd + 1


def _route_hashed(gl: Any, ssbo: Any, p: dict[str, Any], n_frags: int, m: int) -> int:
    """``route_hashed.comp``: warmup_frames + 1 routings of this frame's fragments through the
    read-only / write-only table pair (a still view held that long), then the per-slot owner
    id and contest test of the last frame. Leaves the Keys (drawable marks) and Ids buffers
    bound (Ids is the last buffer made); returns the number of routings."""
    ctx = gl.ctx
    cs = gl.compute(shader_source("route_hashed.comp"))
    cs["table_mask"].value = m - 1
    cs["max_probes"].value = int(p["max_probes"])
    tables = [ssbo(np.full(m, _EMPTY, np.uint32), 22), ssbo(np.full(m, _EMPTY, np.uint32), 23)]
    frames = int(p["warmup_frames"]) + 1
    cs["n_items"].value = n_frags
    for f in range(frames):
        read, write = tables[f % 2], tables[(f + 1) % 2]
        write.clear(chunk=b"\xff\xff\xff\xff")
        read.bind_to_storage_buffer(22)
        write.bind_to_storage_buffer(23)
        cs["stage"].value = 0
        cs.run(_groups(n_frags, 64))
        ctx.memory_barrier()
    owner = np.zeros((m, 4), np.uint32)
    owner[:, :2] = _EMPTY
    ssbo(owner, 24)
    ssbo(np.full(m, _EMPTY, np.uint32), 11)  # keys: drawable marks
    ssbo(np.zeros(m, np.uint64), 12)  # ids (the last buffer: the caller takes it)
    for stage in (1, 2, 3):
        cs["stage"].value = stage
        cs.run(_groups(n_frags, 64))
        ctx.memory_barrier()
    cs["stage"].value = 4
    cs["n_items"].value = m
    cs.run(_groups(m, 64))
    ctx.memory_barrier()
    return frames


def shade(
    gl: Any, case: Any, gbuffer: dict[str, moderngl.Texture], size: tuple[int, int]
) -> moderngl.Texture:
    """Per-sample straight-alpha linear RGBA (RGBA32F, ``size`` = (n W, n H), array layout) of
    the tamiss style: exactly what refnpr's ``TamissStyle.shade`` returns.

    Parameters
    ----------
    gl : refnpr_glsl.context.GL
    case : refnpr_glsl.kit_io.Case
    gbuffer : dict channel -> moderngl.Texture
        uv, duv_dx, duv_dy (RG32F), tri_id, mesh_id (R32I) and, as the case's channels say,
        normal, position, bary, dposition_dx, dposition_dy (RGB32F).
    size : (nW, nH)

    Returns
    -------
    moderngl.Texture, RGBA32F of ``size``.
    """
    ctx = gl.ctx
    p = case.params
    _check(p)
    nw, nh = int(size[0]), int(size[1])
    n_axis = int(case.n)
    n_items = nw * nh
    smooth = p["derivatives"] == "smooth"
    const_tone = p.get("constant_tone")
    for ch in ("uv", "duv_dx", "duv_dy", "tri_id", "mesh_id"):
        if ch not in gbuffer:
            raise ValueError(
                f"gbuffer: the tamiss style needs channel {ch!r}; got {sorted(gbuffer)}"
            )
    if smooth and not {"bary", "normal", "position", "dposition_dx", "dposition_dy"} <= set(
        gbuffer
    ):
        smooth = False  # refnpr warns and uses the flat derivatives
    scene = _scene_buffers(case)
    objs = _objects(case)
    lights = _lights(case)
    angles = np.radians(np.asarray(p["directions"], dtype=np.float64))
    layers = np.stack(
        [
            np.cos(angles),
            np.sin(angles),
            np.asarray(p["layer_tones"], dtype=np.float64),
            np.zeros_like(angles),
        ],
        axis=1,
    )
    eye = np.asarray(case.eye, dtype=np.float64)
    gparams = np.array(
        [p["density"], p["period"], p["length"], p["length_jitter"], 0.5 * p["gather_width"],
         0.0 if const_tone is None else const_tone, *eye, *case.ambient],
        dtype=np.float64,
    )  # fmt: skip
    bufs: list[moderngl.Buffer] = []

    def ssbo(data, binding):
        b = _ssbo(ctx, data, binding)
        bufs.append(b)
        return b

    zero = gl.empty((1, 1), 3, "f4")
    tex = {
        "t_uv": gbuffer["uv"],
        "t_duv_dx": gbuffer["duv_dx"],
        "t_duv_dy": gbuffer["duv_dy"],
        "t_tri_id": gbuffer["tri_id"],
        "t_mesh_id": gbuffer["mesh_id"],
        "t_normal": gbuffer.get("normal", zero),
        "t_position": gbuffer.get("position", zero),
        "t_bary": gbuffer.get("bary", zero),
        "t_dpos_dx": gbuffer.get("dposition_dx", zero),
        "t_dpos_dy": gbuffer.get("dposition_dy", zero),
    }
    try:
        # 1. gather: count, scan, emit
        ssbo(np.zeros(n_items, np.uint32), 0)  # counts
        ssbo(np.zeros(n_items, np.uint32), 1)  # offsets
        ssbo(np.zeros(6, np.uint32), 2)
        ssbo(scene["faces"], 3)
        ssbo(scene["frames"], 4)
        ssbo(scene["charts"], 5)
        ssbo(objs, 6)
        ssbo(np.ascontiguousarray(layers), 7)
        ssbo(lights if lights.size else np.zeros(8), 8)
        ssbo(gparams, 9)
        gather = gl.compute(shader_source("gather.comp"))
        for unit, (name, t) in enumerate(tex.items()):
            t.use(location=unit)
            if name in gather:
                gather[name].value = unit
        uni = {
            "grid": (nw, nh), "n_axis": n_axis, "n_layers": len(angles), "n_lights": len(lights),
            "max_level": int(p["max_level"]), "use_smooth": int(smooth),
            "orient": int(bool(p["orient_charts"])), "use_constant_tone": int(const_tone is not None),
            "salt_tone": int(p["constants"]["salt_tone"]), "salt_len": int(p["constants"]["salt_length"]),
        }  # fmt: skip
        for k, v in uni.items():
            if k in gather:
                gather[k].value = v
        gather["mode"].value = 0
        gather.run(_groups(n_items, 64))
        ctx.memory_barrier()
        n_blocks = _groups(n_items, 256)
        blocks = ssbo(np.zeros(n_blocks + 1, np.uint32), 10)
        scan = gl.compute(shader_source("scan.comp", common=False))
        scan["n_items"].value = n_items
        scan["n_blocks"].value = n_blocks
        for stage in range(3):
            scan["stage"].value = stage
            scan.run(n_blocks if stage != 1 else 1)
            ctx.memory_barrier()
        n_frags = int(np.frombuffer(blocks.read(4, offset=4 * n_blocks), np.uint32)[0])
        frags = ssbo(np.zeros(max(n_frags, 1) * 6, np.uint32), 2)  # 24 bytes per fragment
        gather["mode"].value = 1
        gather.run(_groups(n_items, 64))
        ctx.memory_barrier()
        # 2. route by double hashing: exact (CAS claims, full ids) or the paper's frame tables
        counter = ssbo(np.zeros(4, np.uint32), 15)
        state = np.zeros((max(n_frags, 1), 2), np.int32)
        state[:, 0] = -1
        ssbo(state, 14)
        if p["aggregation"] == "hashed":
            m = int(p["table_size"])
            rnd = _route_hashed(gl, ssbo, p, n_frags, m)
            ids = bufs[-1]
        else:
            m = 1 << max(6, int(math.ceil(math.log2(max(2 * n_frags, 2)))))
            ssbo(np.full(m, _EMPTY, np.uint32), 11)  # keys
            ids = ssbo(np.zeros(m, np.uint64), 12)
            ssbo(np.full(m, _EMPTY, np.uint32), 13)
            rnd = _route_exact(gl, counter, n_frags, m)
        # 3. aggregate by blending into float render targets
        tw = min(m, 1024)
        th = m // tw
        mn = gl.empty((tw, th), 4, "f4")
        mx = gl.empty((tw, th), 4, "f4")
        sums = [gl.empty((tw, th), 4, "f4") for _ in range(4)]
        agg = gl.program(shader_source("agg.vert"), _HEADER + (_DIR / "agg.frag").read_text())
        agg["tw"].value = tw
        agg["tsize"].value = (tw, th)
        vao = ctx.vertex_array(agg, [])
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        ctx.enable(moderngl.BLEND)
        try:
            for mode, target, eq, clear in (
                (0, mn, moderngl.MIN, 3.0e38),
                (1, mx, moderngl.MAX, -3.0e38),
            ):
                fbo = ctx.framebuffer(color_attachments=[target])
                fbo.use()
                ctx.viewport = (0, 0, tw, th)
                fbo.clear(clear, clear, clear, clear)
                ctx.blend_equation = eq
                agg["mode"].value = mode
                vao.render(moderngl.POINTS, vertices=n_frags)
                fbo.release()
            fbo = ctx.framebuffer(color_attachments=sums)
            fbo.use()
            ctx.viewport = (0, 0, tw, th)
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            ctx.blend_equation = moderngl.FUNC_ADD
            ctx.blend_func = moderngl.ONE, moderngl.ONE
            mn.use(location=0)
            mx.use(location=1)
            agg["t_mn"].value = 0
            agg["t_mx"].value = 1
            agg["mode"].value = 2
            vao.render(moderngl.POINTS, vertices=n_frags)
            fbo.release()
        finally:
            ctx.blend_equation = moderngl.FUNC_ADD
            ctx.disable(moderngl.BLEND)
            vao.release()
        # 4. strokes in id order
        ssbo(np.zeros(max(n_frags, 1), np.uint32), 16)
        sorted_buf = ssbo(np.zeros(max(n_frags, 1), np.uint32), 17)
        order = gl.compute(shader_source("order.comp"))
        order["n_slots"].value = m
        order["stage"].value = 0
        order.run(_groups(m, 64))
        ctx.memory_barrier()
        n_strokes = int(np.frombuffer(counter.read(4, offset=8), np.uint32)[0])
        order["stage"].value = 1
        order.run(_groups(n_strokes, 64))
        ctx.memory_barrier()
        # 5. fit, extent, extrusion
        K = int(p["samples"])
        view = SHOWS.index(p.get("show", "color"))
        thr = p["visibility_threshold"]
        ink = np.asarray(p["ink"], dtype=np.float64)
        levels = np.asarray(p["constants"]["level_colors"], dtype=np.float64).reshape(-1)[:21]
        fp = np.array(
            [p["prior_weight"], p["min_t_span"], -1.0 if p["max_stretch"] is None else p["max_stretch"],
             1.0 / (p["gather_width"] * n_axis * n_axis), thr, p["overdraw"], p["width"], p["taper"],
             p["wobble"], p["wobble_frequency"], p["end_jitter"], p["width_jitter"],
             8.0 * float(np.finfo(np.float32).eps), *ink, *levels],
            dtype=np.float64,
        )  # fmt: skip
        ssbo(fp, 20)
        n_pieces = 2 * max(n_strokes, 1)
        pieces_buf = ssbo(np.zeros(n_pieces * 12, np.uint32), 18)  # 48 bytes per piece
        verts_buf = ssbo(np.zeros(n_pieces * K * 5, np.float64), 19)
        fit = gl.compute(shader_source("fit.comp"))
        for unit, (name, t) in enumerate(
            zip(("t_s0", "t_s1", "t_bx", "t_by", "t_mn", "t_mx"), (*sums, mn, mx), strict=True)
        ):
            t.use(location=unit)
            fit[name].value = unit
        for k, v in {"tw": tw, "K": K, "iterations": int(p["iterations"]), "min_fragments": int(p["min_fragments"]),
                     "extent": EXTENTS.index(p["extent"]), "view": view, "n_axis": n_axis,
                     "grid": (nw, nh)}.items():  # fmt: skip
            if k in fit:
                fit[k].value = v
        fit.run(_groups(n_strokes, 64))
        ctx.memory_barrier()
        if DEBUG is not None:
            DEBUG.update(
                sums=[gl.read(t) for t in sums], mn=gl.read(mn), mx=gl.read(mx),
                ids=np.frombuffer(ids.read(), np.uint64).copy(), tw=tw, frags=frags.read(),
                sorted=np.frombuffer(sorted_buf.read(), np.uint32)[:n_strokes].copy(),
                pieces=np.frombuffer(pieces_buf.read(), np.uint32).reshape(-1, 12).copy(),
                verts=np.frombuffer(verts_buf.read(), np.float64).reshape(-1, K, 5).copy(),
            )  # fmt: skip
        # 6. strips: instanced quads, union coverage + brush, "over" in piece order
        strokes_tex = gl.empty((nw, nh), 4, "f4")
        levels_b = case.texture(p["brush"]["role"])
        brush = gl.texture_from_array(np.asarray(levels_b[0], dtype=np.float32), dtype="f4")
        prog = gl.program(shader_source("strip.vert"), shader_source("strip.frag"))
        prog["grid"].value = (nw, nh)
        prog["K"].value = K
        prog["aa"].value = int(p["aa"])
        prog["wrap_t"].value = int(bool(p["brush"]["wrap_t"]))
        prog["opacity"].value = float(p["opacity"])
        brush.use(location=0)
        prog["t_brush"].value = 0
        vao = ctx.vertex_array(prog, [])
        fbo = ctx.framebuffer(color_attachments=[strokes_tex])
        try:
            fbo.use()
            ctx.viewport = (0, 0, nw, nh)
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            ctx.enable(moderngl.BLEND)
            ctx.blend_equation = moderngl.FUNC_ADD
            ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
            if n_strokes:
                vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=2 * n_strokes)
        finally:
            ctx.disable(moderngl.BLEND)
            fbo.release()
            vao.release()
            brush.release()
        # 7. compose
        out = gl.empty((nw, nh), 4, "f4")
        paper = p.get("paper")
        gl.fullscreen(
            shader_source("compose.frag"),
            out,
            {"t_ink": strokes_tex, "t_tri_id": gbuffer["tri_id"]},
            {
                "view": view,
                "use_paper": int(paper is not None),
                "paper": tuple(float(c) for c in (paper if paper is not None else (0, 0, 0))),
                "ink_color": tuple(float(c) for c in ink),
                "grid": (nw, nh),
            },
        )
        for t in (mn, mx, *sums, strokes_tex, zero):
            t.release()
        shade.last_stats = {
            "fragments": n_frags,
            "strokes": n_strokes,
            "table_size": m,
            "rounds": rnd,
        }
        return out
    finally:
        for b in bufs:
            b.release()
