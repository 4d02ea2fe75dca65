"""Smooth shading on the GPU: Veryovka 2002 eq. 1, as refnpr's ``smooth`` style.

``I = m_a l_a + sum_i m_d f_d(N, L_i) l_i + sum_i m_s f_s(N, L_i, V) l_i``, clipped to [0, 1],
alpha 1 on covered samples, 0 elsewhere (straight alpha). With colour maps
(``params.color_texture``, :mod:`refnpr_glsl.color_maps`) m_a and m_d are multiplied by the
map's linear RGB ``a`` at the sample: ``(m_a l_a) a`` and ``(m_d a) f_d l_i``.
"""

from __future__ import annotations

from typing import Any

import moderngl

from ..color_maps import ColorMaps, bind, color_maps, shading_terms
from ..context import GL
from ..kit_io import Case
from ..lighting import preamble

__all__ = ["shade", "fragment_source"]


def fragment_source(
    case: Case, gbuffer: dict[str, Any], *, maps: ColorMaps | None | bool = True
) -> str:
    """The full-screen fragment shader of the case (parameters inlined); ``maps``: the case's
    colour maps (:func:`refnpr_glsl.color_maps.color_maps`; True: read them from the case)."""
    p = case.params
    if maps is True:
        maps = color_maps(case)
    setup, ambient, diffuse = shading_terms(maps or None)
    specular = bool(p.get("specular", True))
    phong = p.get("model", "blinn-phong") == "phong"
    return (
        preamble(case, gbuffer)
        + (maps.source if maps else "")
        + f"""
out vec4 o_rgba;
void main() {{
    shade_inputs();
    if (!covered) {{ o_rgba = vec4(0.0); return; }}
    {setup}dvec3 rgb = {ambient};  // eq. 1
    for (int i = 0; i < N_LIGHTS; ++i) {{
        dvec3 L = light_dir(i, P);
        dvec3 c = light_color(i);
        rgb += {diffuse} * f_diffuse(N, L) * c;  // eq. 1: f_d
        {"rgb += M_specular[mid] * f_specular(N, L, V, M_shininess[mid], " + ("true" if phong else "false") + ") * c;  // eq. 1: f_s" if specular else ""}
    }}
    o_rgba = vec4(vec3(clamp(rgb, 0.0LF, 1.0LF)), 1.0);
}}
"""
    )


def shade(
    gl: GL, case: Case, gbuffer: dict[str, moderngl.Texture], size: tuple[int, int]
) -> moderngl.Texture:
    """Per-sample straight-alpha linear RGBA (RGBA32F, ``size`` = (n W, n H), array layout)."""
    maps = color_maps(case)
    out = gl.empty(size, 4, "f4")
    ssbo = bind(gl, maps)
    try:
        gl.fullscreen(fragment_source(case, gbuffer, maps=maps), out, dict(gbuffer))
    finally:
        if ssbo is not None:
            ssbo.release()
    return out
