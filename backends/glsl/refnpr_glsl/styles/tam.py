"""TAM / RPTAM (the texture-space baseline of TAMISS, Szécsi et al.) in the fragment shader.

One full-screen pass per case (``shaders/tam/shade.frag.glsl``): per sample, the smooth uv
derivatives (interpolated vertex tangent frames), the chart orientation, the darkness, then the
enumeration of the nested RPTAM seed field with 64-bit stroke ids and SplitMix64 hashes
(``GL_ARB_gpu_shader_int64``), anti-aliased ink with a per-sample density decision, composited
over the paper. Per-vertex chart data come from the kit's ``_TAM_*`` glTF attributes (see the
case's ``derived`` texts), fetched by ``tri_id`` from shader storage buffers.

Precision: the geometry of the field is evaluated in double precision (``GL_ARB_gpu_shader_fp64``,
core since 4.0) from the float32 G-buffer; ``log2``/``exp2`` of the level are float32 (GLSL has no
double transcendentals). refnpr rasterizes this style in float64, so uv and its derivatives
differ by float32 rounding (~1e-7 relative): a stroke end or a density decision can flip at a
sample where refnpr's value sits on the boundary.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["shade", "fragment_source", "defines"]

_SHADER = Path(__file__).resolve().parent.parent / "shaders" / "tam" / "shade.frag.glsl"
_VERTEX_FLOATS = 14
_ATTRS = ("tam_frame_u", "tam_frame_v", "tam_chart", "tam_symmetry", "tam_offset")


def _u64(name: str, value: Any) -> str:
    try:
        v = int(value, 16) if isinstance(value, str) else int(value)
    except (TypeError, ValueError):
        raise ValueError(
            f"style.params.{name}: expected a 64-bit hex string, got {value!r}"
        ) from None
    if not 0 <= v < 1 << 64:
        raise ValueError(f"style.params.{name}: {value!r} is not a uint64")
    return f"0x{v:016X}UL"


def defines(params: dict[str, Any], n_lights: int, n_objects: int) -> dict[str, Any]:
    """The shader's ``#define`` values for a case's resolved tam ``params``.

    Raises
    ------
    ValueError
        For a ``base`` style under the strokes (not implemented by this backend), more than 4
        layers or constants that differ from the shader's (seed columns, id layout).
    """
    if params.get("base") is not None:
        raise ValueError(
            f"style.params.base: a style under the tam strokes ({params['base'].get('name')!r}) "
            "is not implemented by the GLSL backend; use paper = [r, g, b] or no base"
        )
    n_layers = len(params["directions"])
    if not 1 <= n_layers <= 4:
        raise ValueError(f"style.params.directions: expected 1 to 4 layers, got {n_layers}")
    if list(params.get("kx", [])) != [0, 6, 5, 1, 3, 4, 2] or params.get("cell_bits") != 22:
        raise ValueError(
            "style.params.kx / cell_bits: this shader is written for kx = [0, 6, 5, 1, 3, 4, 2] "
            f"and 22-bit cells, got {params.get('kx')} / {params.get('cell_bits')}"
        )
    if params["density_mode"] not in ("clip", "fade"):
        raise ValueError(f"style.params.density_mode: {params['density_mode']!r}")
    sm, salts = params["splitmix"], params["salts"]
    return {
        "N_LAYERS": n_layers,
        "MAX_LEVEL": int(params["max_level"]),
        "CAP": int(params["cap"]),
        "FADE_MODE": int(params["density_mode"] == "fade"),
        "SMOOTH": int(params["derivatives"] == "smooth"),
        "ORIENT": int(bool(params["orient_charts"])),
        "CONSTANT_TONE": int(params.get("constant_tone") is not None),
        "HAS_PAPER": int(params.get("paper") is not None),
        "N_LIGHTS": int(n_lights),
        "N_OBJECTS": int(n_objects),
        "M1": _u64("splitmix.m1", sm["m1"]),
        "M2": _u64("splitmix.m2", sm["m2"]),
        "M3": _u64("splitmix.m3", sm["m3"]),
        "SALT_TONE": _u64("salts.tone", salts["tone"]),
        "SALT_LENGTH": _u64("salts.length", salts["length"]),
        "SALT_WIDTH": _u64("salts.width", salts["width"]),
    }


def fragment_source(defs: dict[str, Any]) -> str:
    """The fragment shader with ``defs`` inserted after its ``#extension`` line."""
    text = _SHADER.read_text()
    block = "\n".join(f"#define {k} {v}" for k, v in sorted(defs.items()))
    return text.replace("//DEFINES", block, 1)


def _buffers(case: Any) -> tuple[np.ndarray, ...]:
    """faces (3 T,) int32, verts (14 V,) float32, objects (8 n,) float32, lights (8 L,)."""
    faces, verts = [], []
    offset = 0
    for k, m in enumerate(case.meshes):
        expected = sum(mm.n_faces for mm in case.meshes[:k])
        if m.first_tri_id != expected:
            raise ValueError(
                f"case {case.name!r}: object {m.name!r} has first_tri_id {m.first_tri_id}, "
                f"expected {expected}"
            )
        n_v = m.positions.shape[0]
        missing = [a for a in _ATTRS if a not in m.attributes]
        if missing:
            raise ValueError(
                f"case {case.name!r}: mesh {m.name!r} lacks the tam vertex attributes "
                f"{['_' + a.upper() for a in missing]} (has {sorted(m.attributes)})"
            )
        cols = [np.asarray(m.attributes[a], dtype=np.float64).reshape(n_v, -1) for a in _ATTRS]
        block = np.concatenate([*cols, np.zeros((n_v, 1))], axis=1)
        if block.shape[1] != _VERTEX_FLOATS:
            raise ValueError(
                f"case {case.name!r}: mesh {m.name!r}: tam attributes have {block.shape[1] - 1} "
                "floats per vertex, expected 13 (3 + 3 + 1 + 4 + 2)"
            )
        faces.append(np.asarray(m.indices, dtype=np.int64) + offset)
        verts.append(block)
        offset += n_v
    objs = []
    for m in case.meshes:
        mat = m.material
        objs.append(
            [
                *mat.get("uv_scale", (1.0, 1.0)),
                *mat.get("ambient", (0.0,) * 3),
                *mat.get("diffuse", (1.0,) * 3),
            ]  # fmt: skip
        )
    lights = []
    for li in case.lights:
        point = li["kind"] == "point"
        xyz = li["position"] if point else li["direction"]
        lights.append([1.0 if point else 0.0, *xyz, *li["color"], 0.0])
    lights = lights or [[0.0] * 8]
    return (
        np.concatenate(faces).astype(np.int32).ravel(),
        np.concatenate(verts).astype(np.float32).ravel(),
        np.asarray(objs, dtype=np.float32).ravel(),
        np.asarray(lights, dtype=np.float32).ravel(),
    )


def _pad4(values: list[float]) -> np.ndarray:
    out = np.zeros(4, dtype=np.float64)
    out[: len(values)] = values
    return out


def shade(gl: Any, case: Any, gbuffer: dict[str, Any], size: tuple[int, int]) -> Any:
    """Per-sample straight-alpha linear RGBA of the tam style (RGBA32F texture of ``size`` =
    (n W, n H), array layout; alpha = the ink where no paper), as refnpr's ``TamStyle.shade``.

    Parameters
    ----------
    gl : refnpr_glsl.context.GL
    case : refnpr_glsl.kit_io.Case
    gbuffer : dict channel -> moderngl.Texture
        tri_id, mesh_id, uv, duv_dx, duv_dy; normal (lit tone); position (point lights, smooth
        derivatives); bary, dposition_dx, dposition_dy (smooth derivatives).
    size : (int, int)
        The sample grid (n W, n H).

    Returns
    -------
    moderngl.Texture
    """
    params = case.params
    defs = defines(params, len(case.lights), len(case.meshes))
    need = {"tri_id", "mesh_id", "uv", "duv_dx", "duv_dy"}
    if not defs["CONSTANT_TONE"]:
        need.add("normal")
        if any(li["kind"] == "point" for li in case.lights):
            need.add("position")
    if defs["SMOOTH"]:
        need |= {"bary", "normal", "position", "dposition_dx", "dposition_dy"}
    missing = sorted(need - set(gbuffer))
    if missing:
        raise ValueError(
            f"case {case.name!r}: the tam pass needs G-buffer channels {missing} "
            f"(given {sorted(gbuffer)})"
        )
    textures = {f"g_{c}": gbuffer[c] for c in sorted(need)}
    paper = params.get("paper") or (0.0, 0.0, 0.0)
    uniforms = {
        "eye": tuple(float(x) for x in case.eye),
        "ambient": tuple(float(x) for x in case.ambient),
        "luma": tuple(float(x) for x in params["luma"]),
        "ink_color": tuple(float(x) for x in params["ink"]),
        "paper": tuple(float(x) for x in paper),
        "cos_a": _pad4(params["cos_a"]),
        "sin_a": _pad4(params["sin_a"]),
        "tone_lo": _pad4(params["layer_tones"]),
        "density": float(params["density"]),
        "period": float(params["period"]),
        "lam": float(params["length"]),
        "len_jit": float(params["length_jitter"]),
        "wid_jit": float(params["width_jitter"]),
        "width_px": float(params["width"]),
        "fade": float(params["fade"]),
        "constant_tone": float(params.get("constant_tone") or 0.0),
    }
    bufs = [gl.ctx.buffer(a.tobytes()) for a in _buffers(case)]
    for binding, buf in enumerate(bufs):
        buf.bind_to_storage_buffer(binding)
    target = gl.empty(size, 4, "f4")
    try:
        gl.fullscreen(fragment_source(defs), target, textures, uniforms)
    finally:
        for buf in bufs:
            buf.release()
    return target
