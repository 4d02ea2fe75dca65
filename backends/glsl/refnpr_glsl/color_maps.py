"""Material colour maps (glTF baseColorTexture) for the ``smooth`` and ``toon`` passes.

A case whose scene has colour maps carries ``style.params.color_texture``: one entry per object
(in the order of ``case.objects``), a texture role (``color_<k>``, RGB float mip levels,
GL_REPEAT, ``linear_mipmap_linear``) or null. Per covered sample the shading multiplies m_a and
m_d by ``a``, the object's map sampled as the case's derived text ``color_texture`` says: the
GL_LINEAR_MIPMAP_LINEAR sample at ``uv * m.uv_scale``, at the GL isotropic LOD of the scaled
per-pixel derivatives ``duv_dx * m.uv_scale``, ``duv_dy * m.uv_scale`` against level 0's size;
``a = (1, 1, 1)`` for an object without a map.

The filtering runs in the shader from the texels (:mod:`refnpr_glsl.pyramids`, shared with the
``threshold`` style), in double like refnpr's float64, except ``log2`` of the LOD (GLSL has only
a float ``log2``: lambda off by ~1e-7, the level weight by as much).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .kit_io import Case
from .lighting import dlit
from .pyramids import PYRAMID_GLSL, TexelBuffer, glsl_int_array

__all__ = ["ColorMaps", "color_maps", "bind", "CHANNELS"]

#: G-buffer channels the colour maps read (besides mesh_id).
CHANNELS = ("uv", "duv_dx", "duv_dy")

_SAMPLE = """
layout(std430, binding = 0) readonly buffer ColorMapData { float DATA[]; };
uniform sampler2D uv;
uniform sampler2D duv_dx;
uniform sampler2D duv_dy;
dvec3 color_texel(int i) { return dvec3(DATA[i], DATA[i + 1], DATA[i + 2]); }
// GL_LINEAR / GL_REPEAT sample of level lv, three channels (taps: common/pyramid.glsl)
dvec3 color_level(int lv, dvec2 st) {
    ivec4 t;
    double fx, fy;
    bilinear_taps(lv, st, t, fx, fy);
    int o = LV_OFF[lv];
    precise dvec3 b = (1.0LF - fx) * (1.0LF - fy) * color_texel(o + 3 * t.x);
    b += fx * (1.0LF - fy) * color_texel(o + 3 * t.y);
    b += (1.0LF - fx) * fy * color_texel(o + 3 * t.z);
    b += fx * fy * color_texel(o + 3 * t.w);
    return b;
}
// a of the derived text color_texture: the object's colour map at the sample, else (1, 1, 1)
dvec3 color_factor(int mid) {
    int g = COLOR_MAP[mid];
    if (g < 0) return dvec3(1.0LF);
    ivec2 p = ivec2(gl_FragCoord.xy);
    dvec2 s = UV_SCALE[mid];
    dvec2 st = dvec2(texelFetch(uv, p, 0).xy) * s;
    int lv = LV0[g];
    dvec2 size = dvec2(double(LV_COLS[lv]), double(LV_ROWS[lv]));
    precise dvec2 gx = dvec2(texelFetch(duv_dx, p, 0).xy) * s * size;
    precise dvec2 gy = dvec2(texelFetch(duv_dy, p, 0).xy) * s * size;
    precise double rho = max(sqrt(gx.x * gx.x + gx.y * gx.y), sqrt(gy.x * gy.x + gy.y * gy.y));
    float lod = log2(float(max(rho, 5.421010862427522e-20LF)));  // 2^-64
    if (isnan(lod)) lod = 0.0;  // non-finite derivatives: level 0, never an index out of range
    int k0, k1;
    float f;
    level_weights(g, lod, k0, k1, f);
    precise dvec3 a = (1.0LF - double(f)) * color_level(lv + k0, st);
    if (f > 0.0) a += double(f) * color_level(lv + k1, st);
    return a;
}
"""


@dataclass
class ColorMaps:
    """The colour maps of a case, ready for a shader.

    Attributes
    ----------
    source : str
        GLSL to put after :func:`refnpr_glsl.lighting.preamble`: the storage buffer (binding
        0), the ``uv``/``duv_dx``/``duv_dy`` samplers and ``dvec3 color_factor(int mid)``.
    data : (N,) float32 ndarray
        The storage buffer's contents (every level of every role, RGB interleaved).
    """

    source: str
    data: np.ndarray


def _roles(case: Case) -> list[str | None] | None:
    """``params.color_texture`` validated: one role or None per object; None when absent."""
    roles = case.params.get("color_texture")
    if roles is None:
        return None
    n = len(case.objects)
    if not isinstance(roles, list) or len(roles) != n:
        got = len(roles) if isinstance(roles, list) else type(roles).__name__
        raise ValueError(
            f"case {case.name!r}: style.params.color_texture: expected a list of {n} entries "
            f"(one per object: a texture role or null), got {got}; re-export the case"
        )
    textures = case.data.get("textures") or {}
    for i, role in enumerate(roles):
        if role is None:
            continue
        if not isinstance(role, str) or role not in textures:
            raise ValueError(
                f"case {case.name!r}: style.params.color_texture[{i}] = {role!r}: expected null "
                f"or a texture role of the case ({sorted(textures)}); re-export the case"
            )
    return roles


def _uv_scale(case: Case, i: int) -> tuple[float, float]:
    raw = case.objects[i].get("material", {}).get("uv_scale", [1.0, 1.0])
    try:
        s = np.asarray(raw, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        s = np.zeros(0)
    if s.size == 1:
        s = np.repeat(s, 2)
    if s.size != 2 or not np.isfinite(s).all():
        raise ValueError(
            f"case {case.name!r}: objects[{i}].material.uv_scale = {raw!r}: expected two finite "
            "numbers [su, sv]"
        )
    return float(s[0]), float(s[1])


def color_maps(case: Case) -> ColorMaps | None:
    """The case's colour maps (None when ``style.params.color_texture`` is absent or all null).

    Raises
    ------
    ValueError
        ``params.color_texture`` is not one role or null per object, a role's levels are not
        (H, W, 3) finite images, a ``uv_scale`` is not two numbers, or the case's channels lack
        one of :data:`CHANNELS`.
    """
    roles = _roles(case)
    if roles is None or all(r is None for r in roles):
        return None
    missing = [c for c in CHANNELS if c not in case.channels]
    if missing:
        raise ValueError(
            f"case {case.name!r}: colour maps need the channels {list(CHANNELS)}; the case's "
            f"channels lack {missing}"
        )
    buf = TexelBuffer()
    group: dict[str, int] = {}
    per_object = []
    for role in roles:
        if role is not None and role not in group:
            group[role] = buf.add_pyramid(case.texture(role), role, channels=3)
        per_object.append(-1 if role is None else group[role])
    scales = [_uv_scale(case, i) for i in range(len(roles))]
    uvs = ", ".join(f"dvec2({dlit(u)}, {dlit(v)})" for u, v in scales)
    head = [
        "\n#define real double\n#define rvec2 dvec2\n",
        buf.tables(),
        glsl_int_array("COLOR_MAP", per_object),
        f"const dvec2 UV_SCALE[{len(scales)}] = dvec2[]({uvs});\n",
        PYRAMID_GLSL.read_text(),
    ]
    return ColorMaps(source="".join(head) + _SAMPLE, data=buf.array())


def bind(gl: Any, maps: ColorMaps | None) -> Any:
    """Upload ``maps.data`` as the storage buffer at binding 0; returns the buffer to release
    after the pass (None without maps)."""
    if maps is None:
        return None
    ssbo = gl.ctx.buffer(maps.data.tobytes())
    ssbo.bind_to_storage_buffer(0)
    return ssbo


def shading_terms(maps: ColorMaps | None) -> tuple[str, str, str]:
    """GLSL pieces of the lit passes' ``main()``: (a statement that sets ``dvec3 a`` followed by
    the next line's indentation, or ""; the ambient term; the diffuse material colour). Without
    maps they are the plain ``M_ambient[mid] * AMBIENT`` and ``M_diffuse[mid]``, so the shader
    is the one of a case without colour maps."""
    if maps is None:
        return "", "M_ambient[mid] * AMBIENT", "M_diffuse[mid]"
    return (
        "dvec3 a = color_factor(mid);  // colour map\n    ",
        "(M_ambient[mid] * AMBIENT) * a",
        "(M_diffuse[mid] * a)",
    )
