"""X-Toon (Barla, Thollot, Markosian 2006) on the GPU: one full-screen fragment pass per case.

The pass reads the G-buffer (array layout, one texel per sample), the case's 2D toon texture
(``textures.toon``) and, for the per-vertex quantities of the paper's vertex shader (D or the
flow vector per vertex in ``detail_mode = "vertex"``, the per-vertex normal blend of shape
abstraction), the scene's vertices and faces in shader storage buffers: the triangle of a sample
is ``tri_id`` and its three vertices' values are interpolated with the G-buffer ``bary``, which
is exactly what a vertex-shader output becomes at a fragment. Shader:
``shaders/xtoon/shade.frag.glsl``; configuration by ``#define`` (one program per variant).

Precision: float32 throughout (refnpr evaluates in float64). The logarithms of the depth and
focus maps and the powers of the orientation and highlight maps stay within ~1e-6 of refnpr's;
toon textures with hard steps (``loa_levels``, ``toon``) can flip a sample where tone or D sits
on a step, which the case tolerance's position deviation absorbs.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["shade", "fragment_source", "defines"]

_SHADER = Path(__file__).resolve().parent.parent / "shaders" / "xtoon" / "shade.frag.glsl"
_DETAILS = ("depth", "focus", "orientation", "highlight", "flow", "map", "none")
_WEIGHTS = ("global", "detail", "texture", "map")
_SHOWS = ("color", "detail", "inverse_detail", "tone")


def _choice(name: str, value: Any, choices: tuple[str, ...]) -> int:
    if value not in choices:
        raise ValueError(f"style.params.{name}: expected one of {list(choices)}, got {value!r}")
    return choices.index(value)


def defines(params: dict[str, Any], lights: list[dict[str, Any]], channels: list[str]) -> dict:
    """The shader's ``#define`` values for a case's resolved xtoon ``params``.

    Parameters
    ----------
    params : dict
        ``case.json`` ``style.params`` (refnpr/kit/styles/xtoon.py's layout).
    lights : list of dict
        ``case.json`` ``lights``.
    channels : list of str
        The G-buffer channels of the case.

    Returns
    -------
    dict name -> int
    """
    detail = _choice("detail", params["detail"], _DETAILS)
    vertex_mode = params["detail_mode"] == "vertex"
    shaped = params.get("shape") is not None
    blend_vertex = shaped and params.get("shape_blend") == "vertex"
    weight = _choice("shape_weight.kind", params["shape_weight"]["kind"], _WEIGHTS) if shaped else 0
    li = int(params["light"])
    if not 0 <= li < len(lights):
        raise ValueError(f"style.params.light: index {li} out of range of {len(lights)} lights")
    vertex_names = blend_vertex or (vertex_mode and detail not in (5, 6))
    need_tri = vertex_names or (shaped and not blend_vertex)
    return {
        "DETAIL": detail,
        "DIST_EYE": int(params.get("distance") == "eye"),
        "VERTEX_MODE": int(vertex_mode),
        "SHAPED": int(shaped),
        "BLEND_VERTEX": int(blend_vertex),
        "WEIGHT": weight,
        "HALF_LAMBERT": int(params["tone"] == "half_lambert"),
        "LIGHT_POINT": int(lights[li]["kind"] == "point"),
        "ONE_SIDED": int(bool(params.get("one_sided"))),
        "MODULATE": int(bool(params.get("modulate"))),
        "NEED_TRI": int(need_tri),
        "PIXEL_DEPTH": int(
            detail in (0, 1) and params.get("distance") == "axis" and "depth" in channels
        ),  # fmt: skip
        "PIXEL_POSITION": int("position" in channels),
        "SHOW": _choice("show", params["show"], _SHOWS),
    }


def fragment_source(defs: dict[str, int]) -> str:
    """The fragment shader with ``defs`` inserted after its ``#version`` line."""
    text = _SHADER.read_text()
    block = "\n".join(f"#define {k} {int(v)}" for k, v in sorted(defs.items()))
    return text.replace("//DEFINES", block, 1)


def _scene_buffers(case: Any, shaped: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """faces (3 T,) int32 global vertex indices in tri_id order, verts (9 V,) float32
    (position, normal, abstracted normal), diffuse (3 n_objects,) float32."""
    faces, verts = [], []
    offset = 0
    for k, m in enumerate(case.meshes):
        expected = sum(mm.n_faces for mm in case.meshes[:k])
        if m.first_tri_id != expected:
            raise ValueError(
                f"case {case.name!r}: object {m.name!r} has first_tri_id {m.first_tri_id}, "
                f"expected {expected} (objects in mesh_id order, triangles in glTF index order)"
            )
        n_v = m.positions.shape[0]
        if m.normals is None:
            raise ValueError(f"case {case.name!r}: mesh {m.name!r} has no NORMAL attribute")
        if shaped:
            a = m.attributes.get("abstract_normal")
            if a is None or a.shape != (n_v, 3):
                raise ValueError(
                    f"case {case.name!r}: mesh {m.name!r} lacks _ABSTRACT_NORMAL (N, 3) "
                    f"(attributes: {sorted(m.attributes)})"
                )
        else:
            a = np.zeros((n_v, 3))
        faces.append(np.asarray(m.indices, dtype=np.int64) + offset)
        verts.append(np.concatenate([m.positions, m.normals, a], axis=1))
        offset += n_v
    f = np.concatenate(faces).astype(np.int32).ravel()
    v = np.concatenate(verts).astype(np.float32).ravel()
    diffuse = case.materials("diffuse", (1.0, 1.0, 1.0)).astype(np.float32).reshape(-1, 3)
    return f, v, diffuse.ravel()


def _uniforms(case: Any, params: dict[str, Any]) -> dict[str, Any]:
    light = case.lights[int(params["light"])]
    view = case.view_matrix()
    vp_now = case.projection_matrix() @ view
    prev = params.get("prev_camera")
    vp_prev = (
        np.asarray(prev["projection_matrix"]) @ np.asarray(prev["view_matrix"])
        if prev is not None
        else vp_now
    )
    z_min = params.get("z_min") or 1.0
    r = params.get("r")
    r = 2.0 if r is None else float(r)
    z_c = params.get("z_focus") or 0.0
    log_near = log_far = 1.0
    if params["detail"] == "focus":
        log_near = math.log((z_c - r * z_min) / (z_c - z_min))
        log_far = math.log((z_c + r * z_min) / (z_c + z_min))
    d = np.asarray(light.get("direction", (0.0, 0.0, 1.0)), dtype=np.float64)
    weight = params.get("shape_weight") or {}
    uv_scale = weight.get("uv_scale") or (1.0, 1.0)
    return {
        "eye": tuple(float(x) for x in case.eye),
        "light_dir": tuple(float(x) for x in d / np.linalg.norm(d)),
        "light_pos": tuple(float(x) for x in light.get("position") or (0.0, 0.0, 0.0)),
        "view_row2": tuple(float(x) for x in view[2]),
        "vp_now": vp_now.astype(np.float64),
        "vp_prev": vp_prev.astype(np.float64),
        "image_size": (float(case.width), float(case.height)),
        "z_min": float(z_min),
        "r_exp": float(r),
        "log_r": math.log(r) if r > 0 else 1.0,
        "z_focus": float(z_c),
        "log_near": log_near,
        "log_far": log_far,
        "s_exp": float(params.get("s") or 1.0),
        "flow_min": float(params.get("flow_min") or 0.0),
        "flow_max": float(params.get("flow_max") or 1.0),
        "flow_behind": float(params["flow_behind"]),
        "tiny": float(params["tiny"]),
        "weight_value": float(weight.get("value") or 0.0),
        "uv_scale": tuple(float(s) for s in uv_scale),
        "n_axis": int(case.n),
    }


def _per_sample(arr: np.ndarray, case: Any, role: str) -> int:
    h, w = arr.shape[:2]
    nw, nh = case.sample_size
    if (h, w) == (nh, nw):
        return 1
    if (h, w) == (case.height, case.width):
        return 0
    raise ValueError(
        f"case {case.name!r}: texture {role!r} of shape {arr.shape} is neither per pixel "
        f"({case.height}, {case.width}) nor per sample ({nh}, {nw})"
    )


def shade(gl: Any, case: Any, gbuffer: dict[str, Any], size: tuple[int, int]) -> Any:
    """Per-sample straight-alpha linear RGBA of the xtoon style (RGBA32F texture of ``size`` =
    (n W, n H), array layout; alpha 0 where no surface), as refnpr's ``XToonStyle.shade``.

    Parameters
    ----------
    gl : refnpr_glsl.context.GL
    case : refnpr_glsl.kit_io.Case
    gbuffer : dict channel -> moderngl.Texture
        At least the case's channels (mesh_id; normal, depth, position, tri_id, bary, uv as the
        configuration needs).
    size : (int, int)
        The sample grid (n W, n H).

    Returns
    -------
    moderngl.Texture
    """
    params = case.params
    channels = list(gbuffer)
    defs = defines(params, case.lights, channels)
    need = {"mesh_id"}
    if defs["NEED_TRI"]:
        need |= {"tri_id", "bary"}
    if not defs["SHAPED"] or not defs["BLEND_VERTEX"]:
        need.add("normal")
    if defs["PIXEL_DEPTH"]:
        need.add("depth")
    if defs["WEIGHT"] == 2 and defs["SHAPED"]:
        need.add("uv")
    # D per sample: the pixel mode, and a per-pixel "detail" weight of a pixel blend
    pixel_d = not defs["VERTEX_MODE"] or (
        defs["SHAPED"] and not defs["BLEND_VERTEX"] and defs["WEIGHT"] == 1
    )
    if not pixel_d:
        need.discard("depth")
    pixel_p = bool(defs["LIGHT_POINT"]) or (
        pixel_d
        and (defs["DETAIL"] in (2, 3, 4) or (defs["DETAIL"] in (0, 1) and not defs["PIXEL_DEPTH"]))
    )
    if pixel_p:
        need.add("position")
    missing = sorted(need - set(gbuffer))
    if missing:
        raise ValueError(
            f"case {case.name!r}: the xtoon pass needs G-buffer channels {missing} "
            f"(given {sorted(gbuffer)})"
        )
    ctx = gl.ctx
    owned = []
    textures = {f"g_{c}": gbuffer[c] for c in need}
    toon = case.texture(params["texture"])[0]
    textures["toon_tex"] = gl.texture_from_array(
        np.asarray(toon, dtype=np.float32), dtype="f4", wrap="clamp", filter="nearest"
    )
    owned.append(textures["toon_tex"])
    uniforms = _uniforms(case, params)
    if params["detail"] == "map":
        dm = case.texture(params["detail_map"])[0]
        uniforms["detail_map_per_sample"] = _per_sample(dm, case, "detail_map")
        textures["detail_map_tex"] = gl.texture_from_array(
            np.asarray(dm, dtype=np.float32), dtype="f4", wrap="clamp", filter="nearest"
        )
        owned.append(textures["detail_map_tex"])
    if defs["SHAPED"] and defs["WEIGHT"] in (2, 3):
        role = params["shape_weight"]["texture"]
        wt = np.asarray(case.texture(role)[0], dtype=np.float32)
        if wt.ndim == 3:
            wt = wt[..., 0]
        if defs["WEIGHT"] == 3:
            uniforms["weight_map_per_sample"] = _per_sample(wt, case, role)
        textures["weight_tex"] = gl.texture_from_array(
            wt, dtype="f4", wrap="repeat", filter="nearest"
        )
        owned.append(textures["weight_tex"])
    faces, verts, diffuse = _scene_buffers(case, bool(defs["SHAPED"]))
    buffers = [ctx.buffer(a.tobytes()) for a in (faces, verts, diffuse)]
    for binding, buf in enumerate(buffers):
        buf.bind_to_storage_buffer(binding)
    target = gl.empty(size, 4, "f4")
    try:
        gl.fullscreen(fragment_source(defs), target, textures, uniforms)
    finally:
        for obj in owned + buffers:
            obj.release()
    return target
