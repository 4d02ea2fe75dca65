"""The ``threshold`` style (Veryovka 2002) on the GPU: one full-screen fragment pass per frame.

Reads only the kit: ``case.data["style"]["params"]`` (every parameter resolved by refnpr's
exporter, ``refnpr/kit/styles/threshold.py``), the objects' materials, the lights, the eye, and
the textures the style samples (threshold pyramids with every mip level, interpolation tone
maps, the stipple tone table, the bump pyramid). The shader sources are in
``refnpr_glsl/shaders/threshold/`` (and the pyramid sampling shared with other styles in
``shaders/common/pyramid.glsl``); this module generates the per-case constants (materials,
lights, uv scales, layer schedule, buffer offsets) that precede them, packs the texture levels
into one float storage buffer (:class:`refnpr_glsl.pyramids.TexelBuffer`), and runs the pass.

Precision (``precision``, default :data:`PRECISION` = "float"): "float" runs everything in
float32, as a GPU shader would; "double" runs the line coordinates, their analytic box filter,
the noise and stipple lattices and the texture filtering weights in double, as refnpr's float64
(logarithms, exponentials, atan and lighting stay float32: GLSL has no double exp/log/atan).
Both match refnpr per sample on every golden case (tests/kit/test_glsl_threshold.py). The
splitmix64 hashes of the noise and of the stipple rows are 64-bit integer arithmetic
(GL_ARB_gpu_shader_int64, on llvmpipe and NVIDIA) and the stipple hash reads the float64 bits of
a row's exact v (exact in float too). Texture filtering is done in the shader from the texels
(buffer reads), not by the sampler hardware, whose filtering weights have only 8 fractional bits
on common GPUs.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..pyramids import PYRAMID_GLSL, TexelBuffer

__all__ = [
    "shade",
    "fragment_source",
    "SHADER_DIR",
    "PRECISION",
    "PRECISIONS",
    "SAMPLING",
    "SAMPLINGS",
]

#: Default arithmetic of the "real" parts of the shader (see the module docstring).
PRECISION = "float"
PRECISIONS = ("float", "double")
#: Default texture filtering: "shader" (bilinear/trilinear from the texels, as refnpr) or
#: "hardware" (textureLod on the kit's mip levels: what a plain GPU shader would do).
SAMPLING = "shader"
SAMPLINGS = ("shader", "hardware")

#: The GLSL sources of this style.
SHADER_DIR = Path(__file__).resolve().parent.parent / "shaders" / "threshold"
_FILES = ("common.glsl", "lines.glsl", "coverage.glsl", "stipple.glsl", "image.glsl", "main.glsl")
_SOURCES = {"constant": 0, "image": 1, "lines": 2, "stipple": 3}
_FILTERS = {"none": 0, "pcf": 1, "analytic": 2}


def _f(x: float) -> str:
    """A float32 GLSL literal that round-trips."""
    v = float(np.float32(x))
    if math.isinf(v):
        return "(1.0 / 0.0)" if v > 0 else "(-1.0 / 0.0)"
    return repr(v) if "e" in repr(v) or "." in repr(v) else repr(v) + ".0"


def _d(x: float) -> str:
    """A double GLSL literal (exact)."""
    return f"{float(x)!r}lf" if ("." in repr(float(x)) or "e" in repr(float(x))) else f"{x}.0lf"


def _arr(kind: str, name: str, values: list[str]) -> str:
    if not values:
        values = ["0" if kind == "int" else _f(0.0) if kind == "float" else f"{kind}(0)"]
    return f"const {kind} {name}[{len(values)}] = {kind}[]({', '.join(values)});\n"


def _vec3(v: Any) -> str:
    a = [float(x) for x in v]
    return f"vec3({_f(a[0])}, {_f(a[1])}, {_f(a[2])})"


def fragment_source(
    case: Any, *, precision: str | None = None, sampling: str | None = None
) -> tuple[str, np.ndarray, dict[str, list[np.ndarray]]]:
    """The case's fragment shader source, its storage-buffer contents and, with hardware
    sampling, the mip pyramids to bind as sampler uniforms.

    Parameters
    ----------
    case : refnpr_glsl.kit_io.Case
        ``case.data`` (case.json) and ``case.texture(role) -> list of levels``.
    precision : {"float", "double"}, optional
        Arithmetic of the shader's "real" parts; default :data:`PRECISION`.
    sampling : {"shader", "hardware"}, optional
        Texture filtering of the pyramids; default :data:`SAMPLING`.

    Returns
    -------
    (str, (N,) float32 ndarray, dict sampler name -> levels (level 0 first))
    """
    precision = PRECISION if precision is None else precision
    if precision not in PRECISIONS:
        raise ValueError(f"precision: expected one of {list(PRECISIONS)}, got {precision!r}")
    sampling = SAMPLING if sampling is None else sampling
    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling: expected one of {list(SAMPLINGS)}, got {sampling!r}")
    data = case.data
    style = data.get("style") or {}
    if style.get("name") != "threshold":
        raise ValueError(
            f"case {data.get('name')!r}: style is {style.get('name')!r}, not 'threshold'"
        )
    p = style["params"]
    channels = set(data.get("channels") or [])
    objects = data["objects"]
    mats = [o["material"] for o in objects]
    uvs = p["uv_scales"]
    if len(uvs) != len(objects):
        raise ValueError(
            f"case {data.get('name')!r}: params.uv_scales has {len(uvs)} entries for "
            f"{len(objects)} objects"
        )
    buf = TexelBuffer()
    src = p["source"]
    filt = p["filter"]
    k = int(round(math.sqrt(p["samples"]))) if filt == "pcf" else 1
    spp_n = int(round(math.sqrt(int(data["spp"]))))
    d: dict[str, Any] = {
        "REAL_DOUBLE": int(precision == "double"),
        "HW_SAMPLING": int(sampling == "hardware"),
        "SOURCE": _SOURCES[src],
        "FILTER": _FILTERS[filt],
        "KGRID": k,
        "SPP_N": spp_n,
        "N_STEPS": int(p["n"]),
        "UNIFORM": int(bool(p["uniform"])),
        "MULTISCALE": int(bool(p["multiscale"])),
        "HAS_NOISE": int(src == "lines" and float(p["noise"]) != 0.0),
        "CHANNEL_SCALE": int(bool(p.get("channel_scale")) and "dyadic_scale" in channels),
        "MIP_PER_LEVEL": int(filt == "pcf" and p["mip"] == "per_level"),
        "TONE_CORRECT": 0,
        "SPECULAR": int(bool(p["specular"])),
        "SPEC_CONST": int(not isinstance(p["specular_threshold"], str)),
        "FACING": int(float(p["facing_fade"]) > 0.0),
        "BUMP": int(p.get("bump") is not None),
        "STIPPLE_TONE": 0,
        "HAS_POSITION": int("position" in channels),
        "HAS_UV": int("uv" in channels),
        "HAS_DUV": int("duv_dx" in channels and "duv_dy" in channels),
        "HAS_DYADIC": int("dyadic_scale" in channels),
        "N_LAYERS": len(p["directions"]) if src == "lines" else 1,
        "N_OBJ": len(objects),
    }
    consts = [
        f"const float T_CONST = {_f(p['t'])};\n",
        f"const float SPEC_T = {_f(0.0 if isinstance(p['specular_threshold'], str) else p['specular_threshold'])};\n",
        f"const float STRENGTH = {_f(p['strength'])};\n",
        f"const float FACING_FADE = {_f(p['facing_fade'])};\n",
        f"const float FACING_POWER = {_f(p['facing_power'])};\n",
        f"const float TONE_DARK = {_f(p['tone_fade'][0])};\n",
        f"const float TONE_BRIGHT = {_f(p['tone_fade'][1])};\n",
        f"const float PERIOD = {_f(p['period'])};\n",
        f"const float NOISE_AMP = {_f(p['noise'])};\n",
        f"const float NOISE_SCALE = {_f(p['noise_scale'])};\n",
        f"const uint NOISE_SEED = {int(p['noise_seed']) & 0xFFFFFFFF}u;\n",
        f"const float JITTER = {_f(p['jitter'])};\n",
        f"const float LOD_BIAS = {_f(p['lod_bias'])};\n",
        f"const float BUMP_HEIGHT = {_f(p['bump_height'])};\n",
        f"const vec3 AMBIENT = {_vec3(data['ambient'])};\n",
        f"const vec3 EYE = {_vec3(data['camera']['eye'])};\n",
    ]
    consts.append(_arr("vec3", "MAT_A", [_vec3(m["ambient"]) for m in mats]))
    consts.append(_arr("vec3", "MAT_D", [_vec3(m["diffuse"]) for m in mats]))
    consts.append(_arr("vec3", "MAT_S", [_vec3(m["specular"]) for m in mats]))
    consts.append(_arr("float", "SHININESS", [_f(m["shininess"]) for m in mats]))
    rl = _d if precision == "double" else _f
    consts.append(_arr("rvec2", "UVS", [f"rvec2({rl(u)}, {rl(v)})" for u, v in uvs]))
    consts.append(_arr("float", "LOG2_SV", [_f(math.log2(v)) for _, v in uvs]))
    lights = data.get("lights") or []
    kinds, vecs, colors = [], [], []
    for i, li in enumerate(lights):
        if li["kind"] == "point":
            kinds.append("1")
            vecs.append(_vec3(li["position"]))
        elif li["kind"] == "directional":
            v = np.asarray(li["direction"], dtype=np.float64)
            kinds.append("0")
            vecs.append(_vec3(v / np.linalg.norm(v)))
        else:
            raise ValueError(
                f"lights[{i}].kind: expected 'directional' or 'point', got {li['kind']!r}"
            )
        colors.append(_vec3(li["color"]))
    d["N_LIGHTS"] = len(lights)
    if lights:
        consts.append(_arr("int", "LIGHT_KIND", kinds))
        consts.append(_arr("vec3", "LIGHT_VEC", vecs))
        consts.append(_arr("vec3", "LIGHT_COLOR", colors))
    # textures -> buffer
    groups = [-1] * len(objects)
    tm_off: list[int] = []
    if src == "image":
        role_group: dict[str, int] = {}
        tone_roles = p.get("tone_maps") or [None] * len(objects)
        for i, role in enumerate(p["object_textures"]):
            if role is None:
                continue
            if role not in role_group:
                g = buf.add_pyramid(case.texture(role), role)
                role_group[role] = g
                tm_role = tone_roles[i]
                if p["tone_correct"]:
                    if tm_role is None:
                        raise ValueError(
                            f"params.tone_maps[{i}]: tone_correct needs a tone map role"
                        )
                    q = np.asarray(case.texture(tm_role)[0], dtype=np.float32)
                    q = q.reshape(q.shape[0], -1)
                    if q.shape != (buf.nlev[g], 1025):
                        raise ValueError(
                            f"texture {tm_role!r}: expected ({buf.nlev[g]}, 1025) quantiles, got {q.shape}"
                        )
                    tm_off.append(buf.add(q))
                else:
                    tm_off.append(-1)
            groups[i] = role_group[role]
        d["TONE_CORRECT"] = int(bool(p["tone_correct"]))
    if p.get("bump") is not None:
        d["BUMP_G"] = buf.add_pyramid(case.texture(p["bump"]), "bump")
    if src == "stipple" and p["uniform"]:
        nt, _, ny = p["stipple_tone_shape"]
        table = np.asarray(case.texture(p["stipple_tone"])[0], dtype=np.float32)
        d.update(STIPPLE_TONE=1, STIPPLE_NT=nt, STIPPLE_NY=ny, STIPPLE_OFF=buf.add(table))
    consts.append(_arr("int", "GROUP", [str(g) for g in groups]))
    consts.append(_arr("int", "TM_OFF", [str(o) for o in tm_off]))
    consts.append(buf.tables())
    if src == "lines":
        rad = [math.radians(a) for a in p["directions"]]
        consts.append(_arr("real", "SIN_A", [rl(math.sin(a)) for a in rad]))
        consts.append(_arr("real", "COS_A", [rl(math.cos(a)) for a in rad]))
        sched = p["layer_schedule"]
        lam = [float(x) for x in sched["lam"]]
        lev = [float(x) for row in sched["levels"] for x in row]
        d["N_BP"] = len(lam)
        consts.append(_arr("float", "LAM", [_f(x) for x in lam]))
        consts.append(_arr("float", "LEV", [_f(x) for x in lev]))
    kk = k * k
    d["NT_MAX"] = 2 * kk if d["MIP_PER_LEVEL"] else kk
    head = "#version 450 core\n#extension GL_ARB_gpu_shader_int64 : require\n"
    head += "".join(f"#define {key} {val}\n" for key, val in d.items())
    head += (SHADER_DIR / "precision.glsl").read_text()
    samplers = (
        {f"pyr_{g}": lv for g, lv in enumerate(buf.pyramids)} if sampling == "hardware" else {}
    )
    if samplers:
        cases = "".join(
            f"        case {g}: return textureLod(pyr_{g}, uv, lod).r;\n"
            for g in range(len(samplers))
        )
        consts.append("".join(f"uniform sampler2D {name};\n" for name in samplers))
        consts.append(
            "float hw_sample(int g, vec2 uv, float lod) {\n    switch (g) {\n"
            + cases
            + "    }\n    return 0.0;\n}\n"
        )
    body = PYRAMID_GLSL.read_text() + "".join((SHADER_DIR / f).read_text() for f in _FILES)
    return head + "".join(consts) + body, buf.array(), samplers


def shade(
    gl: Any,
    case: Any,
    gbuffer: dict[str, Any],
    size: tuple[int, int],
    *,
    precision: str | None = None,
    sampling: str | None = None,
) -> Any:
    """Per-sample straight-alpha linear RGBA of the ``threshold`` style (interface B).

    Parameters
    ----------
    gl : refnpr_glsl.context.GL
    case : refnpr_glsl.kit_io.Case
    gbuffer : dict channel -> moderngl.Texture
        The channels of ``case.data["channels"]`` at the sample grid (n W, n H), array layout:
        ``mesh_id`` (R32I), ``normal``, and as the case needs ``position``, ``uv``,
        ``duv_dx``, ``duv_dy``, ``dyadic_scale``, ``dposition_dx``, ``dposition_dy``.
    size : (int, int)
        (n W, n H).
    precision, sampling : str, optional
        See :func:`fragment_source`.

    Returns
    -------
    moderngl.Texture
        RGBA32F, ``size``; alpha 1 where ``mesh_id >= 0``, 0 (and rgb 0) elsewhere.
    """
    source, data, samplers = fragment_source(case, precision=precision, sampling=sampling)
    for ch in ("mesh_id", "normal"):
        if ch not in gbuffer:
            raise ValueError(
                f"gbuffer: the threshold style needs channel {ch!r}, got {sorted(gbuffer)}"
            )
    ssbo = gl.ctx.buffer(data.tobytes())
    pyramids = {
        name: gl.texture_from_array(
            levels[0], dtype="f4", mip_levels=levels, wrap="repeat", filter="linear_mipmap_linear"
        )
        for name, levels in samplers.items()
    }
    try:
        ssbo.bind_to_storage_buffer(0)
        out = gl.empty(size, 4, "f4")
        textures = {f"g_{name}": tex for name, tex in gbuffer.items()} | pyramids
        gl.fullscreen(source, out, textures, {})
    finally:
        ssbo.release()
        for tex in pyramids.values():
            tex.release()
    return out
