"""The ``halftone`` style on the GPU (Freudenberg, Masuch, Strothotte 2002, *Real-Time Halftoning*).

One full-screen fragment pass per scene object (``shaders/halftone/shade_frag.glsl``) computes,
per sample, the target intensity (Veryovka eq. 1 as luminance, DOT3 stroke lighting from the
stroke normal map, the indication map) and thresholds it against the object's screen (binary,
smooth, centred or with c = 1 / fwidth), sampled by hand from the kit's own mip levels (trilinear,
anisotropic probes, or per level with the tone LUTs), or outputs the raw screen, normal map or
intensity (``show``). Everything comes from the kit's ``style.params`` and textures (see
refnpr's ``refnpr/kit/styles/halftone.py`` for the params layout); nothing from refnpr.

Arithmetic: float32 by default (what a shader engineer writes); the environment variable
``REFNPR_GLSL_HALFTONE_PRECISION=double`` compiles the same shader with float64 arithmetic
(GLSL 4.0 ``double``; log2 and pow stay float32, as GLSL has no double versions).

Filtering: by default ("exact") the shader filters the screens itself from the kit's levels
(texelFetch), exactly as refnpr does; ``REFNPR_GLSL_HALFTONE_FILTER=hardware`` uses the texture
unit instead (``textureLod`` on LINEAR_MIPMAP_LINEAR / REPEAT samplers), as most shaders would.
Mesa llvmpipe filters float textures with float weights: it then agrees with "exact" on every
halftone golden case up to a few pixels on 8-bit rounding ties. GPUs that quantize sub-texel and
mip weights (commonly to 8 bits) move binary-threshold edges and smooth-ramp greys by up to a
1/256 texel step. Anisotropic probes and per-level lookups are placed by the shader in both
modes.
"""

from __future__ import annotations

import os
import weakref
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from ..context import FULLSCREEN_VERTEX

__all__ = ["shade", "PRECISIONS", "FILTERINGS"]

_SHADER = Path(__file__).resolve().parent.parent / "shaders" / "halftone" / "shade_frag.glsl"
PRECISIONS = ("float", "double")
FILTERINGS = ("exact", "hardware")
_SHOW = {"color": 0, "screen": 1, "normals": 2, "intensity": 3}
_GBUFFER = (
    "mesh_id",
    "normal",
    "uv",
    "duv_dx",
    "duv_dy",
    "position",
    "dposition_dx",
    "dposition_dy",
)


@cache
def _source(n_lights: int, precision: str, filtering: str) -> str:
    text = _SHADER.read_text()
    head, rest = text.split("\n", 1)  # the #version line stays first
    defines = f"#define MAX_LIGHTS {max(1, n_lights)}\n"
    if precision == "double":
        defines += "#define REAL_DOUBLE\n"
    if filtering == "hardware":
        defines += "#define HW_FILTER\n"
    return f"{head}\n{defines}{rest}"


def _option(var: str, default: str, choices: tuple[str, ...]) -> str:
    value = os.environ.get(var, default)
    if value not in choices:
        raise ValueError(f"{var}: expected one of {list(choices)}, got {value!r}")
    return value


def _levels(case: Any, role: str) -> list[np.ndarray]:
    """The texture's mip levels as float32 arrays (H, W) or (H, W, C)."""
    out = []
    for lv in case.texture(role):
        a = np.asarray(lv)
        a = a.astype(np.float32) / 255.0 if a.dtype == np.uint8 else a.astype(np.float32)
        if a.ndim == 3 and a.shape[2] == 1:
            a = a[..., 0]
        out.append(a)
    return out


#: Most mip levels of a screen (a 32768-texel level 0); the shader's level-size arrays.
MAX_LEVELS = 16


#: Uploaded textures per case object: {case: {(id(ctx), role, hardware): (texture, ...)}}.
_UPLOADS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _release(entries: dict) -> None:
    for tex, _, _ in entries.values():
        try:
            tex.release()
        except Exception:  # noqa: BLE001 -- the context may be gone already
            pass
    entries.clear()


def _case_cache(case: Any) -> dict:
    """The textures uploaded for ``case``, kept while the case object lives, so that shading
    the same case again (a benchmark's repeats) uploads nothing; per call for objects that
    cannot be weakly referenced."""
    try:
        entries = _UPLOADS.get(case)
    except TypeError:
        return {}
    if entries is None:
        entries = _UPLOADS[case] = {}
        weakref.finalize(case, _release, entries)
    return entries


def _upload(
    gl: Any, cache: dict, case: Any, role: str, hardware: bool = False
) -> tuple[Any, int, np.ndarray]:
    """(texture with every level, level count, (MAX_LEVELS, 2) int32 (cols, rows) per level).

    ``hardware``: a LINEAR_MIPMAP_LINEAR / REPEAT sampler (``textureLod``); else NEAREST (the
    shader fetches texels itself)."""
    key = (id(gl.ctx), role, hardware)
    if key not in cache:
        levels = _levels(case, role)
        if len(levels) > MAX_LEVELS:
            raise ValueError(
                f"case {case.name!r}: texture {role!r} has {len(levels)} mip levels; the halftone "
                f"shader takes at most {MAX_LEVELS}"
            )
        tex = gl.texture_from_array(
            levels[0],
            dtype="f4",
            mip_levels=levels,
            filter="linear_mipmap_linear" if hardware else "per_level",
        )
        sizes = np.zeros((MAX_LEVELS, 2), dtype=np.int32)
        sizes[: len(levels)] = [(a.shape[1], a.shape[0]) for a in levels]
        cache[key] = (tex, len(levels), sizes)
    return cache[key]


def _vec(value: Any, n: int, name: str) -> tuple[float, ...]:
    a = np.asarray(value, dtype=np.float64).reshape(-1)
    if a.size == 1 and n > 1:
        a = np.repeat(a, n)
    if a.size != n or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected {n} finite numbers, got {value!r}")
    return tuple(float(x) for x in a)


def _fit_arrays(gl: Any, source: str, uniforms: dict[str, Any]) -> dict[str, Any]:
    """Uniform arrays cut to the length the compiled program keeps (a compiler may shorten an
    array whose tail is never read, e.g. the level sizes with hardware filtering)."""
    prog = gl.program(FULLSCREEN_VERTEX, source)
    out = {}
    for name, value in uniforms.items():
        if isinstance(value, np.ndarray) and value.ndim >= 1 and name in prog:
            value = value[: max(1, int(prog[name].array_length))]
        out[name] = value
    return out


def _light_uniforms(case: Any) -> dict[str, Any]:
    kinds, vecs, colors = [], [], []
    for i, light in enumerate(case.lights):
        kind = light.get("kind", "directional")
        if kind == "point":
            kinds.append(1)
            vecs.append(_vec(light["position"], 3, f"lights[{i}].position"))
        elif kind == "directional":
            d = np.asarray(_vec(light["direction"], 3, f"lights[{i}].direction"))
            kinds.append(0)
            vecs.append(tuple(float(x) for x in d / np.linalg.norm(d)))
        else:
            raise ValueError(f"lights[{i}].kind: expected 'directional' or 'point', got {kind!r}")
        colors.append(_vec(light.get("color", (1.0, 1.0, 1.0)), 3, f"lights[{i}].color"))
    n = len(kinds)
    if n == 0:  # uniform arrays need one element; n_lights = 0 keeps it unused
        kinds, vecs, colors = [0], [(0.0, 0.0, 1.0)], [(0.0, 0.0, 0.0)]
    return {
        "n_lights": n,
        "light_point": np.asarray(kinds, dtype=np.int32),
        "light_vec": np.asarray(vecs, dtype=np.float32),
        "light_color": np.asarray(colors, dtype=np.float32),
        "need_position": int(any(k == 1 for k in kinds[:n])),
    }


def shade(gl: Any, case: Any, gbuffer: dict[str, Any], size: tuple[int, int]) -> Any:
    """Per-sample straight-alpha linear RGBA of the ``halftone`` style.

    Parameters
    ----------
    gl : refnpr_glsl.context.GL
    case : refnpr_glsl.kit_io.Case
        Its ``style.params`` as exported by refnpr's kit (every parameter resolved) and the
        texture roles they name.
    gbuffer : dict name -> moderngl.Texture
        ``mesh_id`` (R32I), ``normal`` (RGB32F), ``uv``, ``duv_dx``, ``duv_dy`` (RG32F), and
        ``position`` (RGB32F) when specular or point lights, ``dposition_dx/dy`` (RGB32F) when a
        screen has a stroke normal map; size (n W, n H), array layout.
    size : (n W, n H)

    Returns
    -------
    moderngl.Texture
        RGBA32F of ``size``, array layout; alpha 0 where no surface.
    """
    params = case.params
    objects = params.get("objects")
    if not isinstance(objects, list) or len(objects) != len(case.objects):
        raise ValueError(
            f"case {case.name!r}: style.params.objects: expected one entry per scene object "
            f"({len(case.objects)}), got {objects!r:.200}"
        )
    if "mesh_id" not in gbuffer:
        raise ValueError(f"case {case.name!r}: gbuffer: the halftone style needs 'mesh_id'")
    show = params.get("show", "color")
    if show not in _SHOW:
        raise ValueError(f"case {case.name!r}: style.params.show: unknown value {show!r}")
    specular = bool(params["specular"])
    lights = _light_uniforms(case)
    need_position = specular or lights["need_position"]
    for ch in ("mesh_id", "normal", "uv", "duv_dx", "duv_dy") + (
        ("position",) if need_position else ()
    ):
        if ch not in gbuffer:
            raise ValueError(f"case {case.name!r}: gbuffer: channel {ch!r} is missing")
    dummy = gl.texture_from_array(np.zeros((1, 1, 4), np.float32), dtype="f4")
    idummy = gl.texture_from_array(np.zeros((1, 1), np.int32), dtype="i4")
    target = gl.empty(size, 4, "f4")
    filtering = _option("REFNPR_GLSL_HALFTONE_FILTER", "exact", FILTERINGS)
    hw = filtering == "hardware"
    source = _source(
        len(case.lights),
        _option("REFNPR_GLSL_HALFTONE_PRECISION", "float", PRECISIONS),
        filtering,
    )
    cache = _case_cache(case)
    common = {
        "threshold_binary": int(params["threshold"] == "binary"),
        "c_const": float(params["c"]) if params.get("c") is not None else 4.0,
        "c_fwidth": int(params.get("c_mode") == "fwidth"),
        "centred": int(bool(params.get("centred"))),
        "n_axis": float(params.get("samples_per_axis", case.n)),
        "lod_offset": float(params.get("lod_offset", 0.0)),
        "show": _SHOW[show],
        "ink": _vec(params["ink"], 3, "ink"),
        "paper": _vec(params["paper"], 3, "paper"),
        "luma": _vec(params.get("luma", (0.2126, 0.7152, 0.0722)), 3, "luma"),
        "l_a": _vec(case.ambient, 3, "ambient"),
        "use_specular": int(specular),
        "eye": _vec(case.eye, 3, "camera.eye"),
        **{k: v for k, v in lights.items() if k != "need_position"},
        "need_position": int(need_position),
    }
    try:
        for k, (entry, obj) in enumerate(zip(objects, case.objects, strict=True)):
            scr = entry["screen"]
            screen_tex, screen_levels, screen_size = _upload(gl, cache, case, scr["role"], hw)
            textures = {
                f"g_{ch}": gbuffer.get(ch, idummy if ch == "mesh_id" else dummy) for ch in _GBUFFER
            }
            textures["t_screen"] = screen_tex
            normals_levels, normals_size = 0, np.zeros((MAX_LEVELS, 2), dtype=np.int32)
            textures["t_normals"] = dummy
            if scr.get("normals_role"):
                textures["t_normals"], normals_levels, normals_size = _upload(
                    gl, cache, case, scr["normals_role"], hw
                )
                for ch in ("dposition_dx", "dposition_dy"):
                    if ch not in gbuffer:
                        raise ValueError(
                            f"case {case.name!r}: gbuffer: {ch!r} is missing (object "
                            f"{entry['name']!r} lights its strokes from a normal map)"
                        )
            textures["t_indication"] = dummy
            if entry.get("indication_role"):
                textures["t_indication"], _, _ = _upload(gl, cache, case, entry["indication_role"])
            textures["t_lut"] = dummy
            if entry.get("equalize"):
                textures["t_lut"], _, _ = _upload(gl, cache, case, entry["tone_lut_role"])
            direction = scr.get("direction")
            mat = obj["material"]
            uniforms = {
                **common,
                "obj": k,
                "screen_levels": screen_levels,
                "normals_levels": normals_levels,
                "screen_size": screen_size,
                "normals_size": normals_size,
                "has_indication": int(bool(entry.get("indication_role"))),
                "equalize": int(bool(entry.get("equalize"))),
                "engraving": int(direction is not None),
                "direction": _vec(direction or (1.0, 0.0), 2, "screen.direction"),
                "uv_scale": _vec(entry["uv_scale"], 2, "uv_scale"),
                "indication_scale": _vec(entry.get("indication_scale", (1, 1)), 2, "iscale"),
                "anisotropy": int(entry.get("anisotropy", 1)),
                "per_level": int(bool(entry.get("per_level"))),
                "m_a": _vec(mat["ambient"], 3, "material.ambient"),
                "m_d": _vec(mat["diffuse"], 3, "material.diffuse"),
                "m_s": _vec(mat["specular"], 3, "material.specular"),
                "shininess": float(mat["shininess"]),
            }
            gl.fullscreen(source, target, textures, _fit_arrays(gl, source, uniforms))
    finally:
        dummy.release()
        idummy.release()
    return target
