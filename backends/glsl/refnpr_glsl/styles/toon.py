"""Toon shading on the GPU, as refnpr's ``toon`` style.

``mode="step"`` (Veryovka eq. 2): ``I = m_a l_a + sum m_d T_n(f_d, t) l_i + sum m_s T_n(f_s, t)
l_i`` with eq. 4's T_n bounded by ceil(x n) / n (refnpr's ``step_n``), computed in double.
``mode="lake"`` (Lake et al. 2000): ``I = m_a l_a + sum m_d ramp(N.L) l_i``, a nearest-texel lookup
of the kit's 1D ramp texture (role "ramp": ``K`` texels, texel ``min(floor(clamp(N.L, 0, 1) K),
K - 1)``) with ``texelFetch``; without the texture, the ramp is evaluated from n and t.
With colour maps (``params.color_texture``, :mod:`refnpr_glsl.color_maps`) m_a and m_d are
multiplied by the map's linear RGB ``a`` at the sample: ``(m_a l_a) a`` and ``(m_d a) tone l_i``
(the specular term is not scaled).
"""

from __future__ import annotations

from typing import Any

import moderngl

from ..color_maps import ColorMaps, bind, color_maps, shading_terms
from ..context import GL
from ..kit_io import Case
from ..lighting import dlit, preamble

__all__ = ["shade", "fragment_source"]

_STEP_N = """
// T_n(x, t) of Veryovka eq. 4, bounded by ceil(x n) / n (refnpr step_n)
double step_n(double x, double t, double n) {
    precise double xn = x * n;
    double whole = floor(xn);
    double levels = whole + ((xn - whole >= t) ? 1.0LF : 0.0LF);
    return min(levels, ceil(xn)) / n;
}
"""


def fragment_source(
    case: Case,
    gbuffer: dict[str, Any],
    *,
    ramp_size: int | None,
    maps: ColorMaps | None | bool = True,
) -> str:
    """The full-screen fragment shader (parameters inlined); ``ramp_size``: texels of the ramp
    texture bound as ``ramp`` (lake mode), or None to evaluate the ramp analytically; ``maps``:
    the case's colour maps (:func:`refnpr_glsl.color_maps.color_maps`; True: read them from
    the case)."""
    p = case.params
    if maps is True:
        maps = color_maps(case)
    setup, ambient, diffuse = shading_terms(maps or None)
    n = int(p.get("n", 2))
    t = float(p.get("t", 0.5))
    mode = p.get("mode", "step")
    specular = bool(p.get("specular", True)) and mode == "step"
    if mode not in ("step", "lake"):
        raise ValueError(f"case {case.name!r}: toon mode must be 'step' or 'lake', got {mode!r}")
    if mode == "lake":
        k = int(ramp_size or p.get("ramp_size", 1024))
        if ramp_size:
            decl = "uniform sampler2D ramp;"
            tone = (
                f"double(texelFetch(ramp, ivec2(int(min(floor(clamp(fd, 0.0LF, 1.0LF) * {k}.0LF),"
                f" {k - 1}.0LF)), 0), 0).r)"
            )
        else:  # the ramp's texel i holds (number of bounds (j + t) / n <= (i + 0.5) / K) / n
            decl = ""
            tone = f"lake_tone(fd, {k})"
        decl += f"""
double lake_tone(double fd, int k) {{
    double i = min(floor(clamp(fd, 0.0LF, 1.0LF) * double(k)), double(k - 1));
    double centre = (i + 0.5LF) / double(k);
    int j = 0;
    for (int b = 0; b < {n}; ++b) j += ((double(b) + {dlit(t)}) / {dlit(n)} <= centre) ? 1 : 0;
    return double(j) / {dlit(n)};
}}"""
    else:
        decl = ""
        tone = f"step_n(fd, {dlit(t)}, {dlit(n)})"
    spec = (
        f"rgb += M_specular[mid] * step_n(f_specular(N, L, V, M_shininess[mid], false),"
        f" {dlit(t)}, {dlit(n)}) * c;"
        if specular
        else ""
    )
    return (
        preamble(case, gbuffer)
        + (maps.source if maps else "")
        + _STEP_N
        + decl
        + f"""
out vec4 o_rgba;
void main() {{
    shade_inputs();
    if (!covered) {{ o_rgba = vec4(0.0); return; }}
    {setup}dvec3 rgb = {ambient};  // eq. 2
    for (int i = 0; i < N_LIGHTS; ++i) {{
        dvec3 L = light_dir(i, P);
        dvec3 c = light_color(i);
        double fd = f_diffuse(N, L);
        rgb += {diffuse} * {tone} * c;
        {spec}
    }}
    o_rgba = vec4(vec3(clamp(rgb, 0.0LF, 1.0LF)), 1.0);
}}
"""
    )


def shade(
    gl: GL, case: Case, gbuffer: dict[str, moderngl.Texture], size: tuple[int, int]
) -> moderngl.Texture:
    """Per-sample straight-alpha linear RGBA (RGBA32F, ``size`` = (n W, n H), array layout)."""
    textures = dict(gbuffer)
    ramp_size = None
    if case.params.get("mode") == "lake" and "ramp" in (case.data.get("textures") or {}):
        level0 = case.texture("ramp")[0]
        ramp = level0.reshape(1, -1) if level0.ndim == 1 else level0
        if ramp.ndim == 3:
            ramp = ramp[..., 0]
        ramp = ramp.reshape(1, -1)
        ramp_size = ramp.shape[1]
        textures["ramp"] = gl.texture_from_array(ramp, dtype="f4", wrap="clamp", filter="nearest")
    maps = color_maps(case)
    out = gl.empty(size, 4, "f4")
    ssbo = bind(gl, maps)
    try:
        source = fragment_source(case, gbuffer, ramp_size=ramp_size, maps=maps)
        gl.fullscreen(source, out, textures)
    finally:
        if ssbo is not None:
            ssbo.release()
        if "ramp" in textures:
            textures["ramp"].release()
    return out
