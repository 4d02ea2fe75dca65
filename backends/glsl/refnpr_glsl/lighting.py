"""GLSL building blocks for Veryovka eq. 1 lighting (ambient, Lambert f_d, specular f_s), shared
by the smooth and toon passes (and usable by any style pass).

Scene constants (materials per object, lights, ambient, eye) are inlined into the generated
source as double literals, as specialization constants would be; the per-sample arithmetic runs
in double precision where refnpr uses float64 (dot products, normalizations, sums), except
``pow``, which GLSL only has in float (relative error ~ shininess * 6e-8).

The generated function ``shade_inputs()`` reads the G-buffer at ``ivec2(gl_FragCoord.xy)`` and
defines, for the sample: ``covered`` (mesh_id >= 0), ``mid`` (the mesh id), ``N`` (dvec3 normal
as stored, not renormalized: refnpr passes unit inputs with normalize=False), ``P`` (position,
when available), ``V`` (unit eye direction, when available).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .kit_io import Case

__all__ = ["dlit", "dvec3_lit", "material_table", "lights_glsl", "LIGHTING_FUNCS", "preamble"]


def dlit(x: float) -> str:
    """A double literal that round-trips ``x`` exactly."""
    return f"{float(x)!r}LF"


def dvec3_lit(v: Any) -> str:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    return f"dvec3({dlit(a[0])}, {dlit(a[1])}, {dlit(a[2])})"


def material_table(case: Case, key: str, default: Any = 0.0) -> str:
    """``const dvec3 M_<key>[K]`` (colours) or ``const double M_<key>[K]`` (scalars)."""
    vals = [np.asarray(o.get("material", {}).get(key, default), np.float64) for o in case.objects]
    k = max(1, len(vals))
    if not vals:
        vals = [np.zeros(3)]
    if all(v.ndim == 0 for v in vals):
        body = ", ".join(dlit(v) for v in vals)
        return f"const double M_{key}[{k}] = double[{k}]({body});"
    body = ", ".join(dvec3_lit(v) for v in vals)
    return f"const dvec3 M_{key}[{k}] = dvec3[{k}]({body});"


LIGHTING_FUNCS = """
// f_d of Veryovka eq. 1 with unit inputs (normalize=False): max(N.L, 0)
double f_diffuse(dvec3 n, dvec3 l) {
    precise double d = n.x * l.x + n.y * l.y + n.z * l.z;
    return max(d, 0.0LF);
}
dvec3 unit_or_zero(dvec3 v) {
    precise double len = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return len > 0.0LF ? v / len : dvec3(0.0LF);
}
// f_s of Veryovka eq. 1 (refnpr lighting.specular, normalize=False): 0 where N.L <= 0
double f_specular(dvec3 n, dvec3 l, dvec3 v, double p, bool phong) {
    if (p <= 0.0LF) return 0.0LF;  // refnpr: objects with shininess <= 0 get no specular
    precise double ndl = n.x * l.x + n.y * l.y + n.z * l.z;
    precise double base;
    if (phong) {
        dvec3 r = 2.0LF * ndl * n - l;
        base = r.x * v.x + r.y * v.y + r.z * v.z;
    } else {
        dvec3 h = unit_or_zero(l + v);
        base = n.x * h.x + n.y * h.y + n.z * h.z;
    }
    base = max(base, 0.0LF);
    return ndl > 0.0LF ? double(pow(float(base), float(p))) : 0.0LF;
}
"""


def lights_glsl(case: Case) -> tuple[str, int]:
    """``light_dir(i, P)`` and ``light_color(i)`` for the case's lights; returns (source, count).

    Directional lights: the unit direction towards the light (normalized here in float64, as
    refnpr's ShadeContext.light_dirs); point lights: unit (position - P), zero when P is there.
    """
    lights = case.lights
    dirs, cols = [], []
    for i, light in enumerate(lights):
        cols.append(f"    if (i == {i}) return {dvec3_lit(light['color'])};")
        if light.get("kind", "directional") == "point":
            dirs.append(
                f"    if (i == {i}) return unit_or_zero({dvec3_lit(light['position'])} - P);"
            )
        else:
            d = np.asarray(light["direction"], dtype=np.float64)
            d = d / np.linalg.norm(d)
            dirs.append(f"    if (i == {i}) return {dvec3_lit(d)};")
    src = "\n".join(
        [
            "dvec3 light_dir(int i, dvec3 P) {",
            *dirs,
            "    return dvec3(0.0LF);",
            "}",
            "dvec3 light_color(int i) {",
            *cols,
            "    return dvec3(0.0LF);",
            "}",
        ]
    )
    return src, len(lights)


def preamble(case: Case, gbuffer: dict[str, Any]) -> str:
    """Declarations for a full-screen style pass: G-buffer samplers (those present), material
    tables (ambient, diffuse, specular, shininess), ambient light, eye, lights and the functions
    above, and ``shade_inputs()``.
    """
    has_pos = "position" in gbuffer
    ident = "mesh_id" if "mesh_id" in gbuffer else "tri_id"
    lines = ["#version 450 core"]
    lines.append(f"uniform isampler2D {ident};")
    if "mesh_id" in gbuffer and ident != "mesh_id":
        lines.append("uniform isampler2D mesh_id;")
    if "normal" in gbuffer:
        lines.append("uniform sampler2D normal;")
    if has_pos:
        lines.append("uniform sampler2D position;")
    for key in ("ambient", "diffuse", "specular"):
        lines.append(material_table(case, key, [0.0, 0.0, 0.0]))
    lines.append(material_table(case, "shininess", 0.0))
    lines.append(f"const dvec3 AMBIENT = {dvec3_lit(case.ambient)};")
    lines.append(f"const dvec3 EYE = {dvec3_lit(case.eye)};")
    lights, count = lights_glsl(case)
    lines.append(f"const int N_LIGHTS = {count};")
    lines.append(LIGHTING_FUNCS)
    lines.append(lights)
    body = [
        "bool covered; int mid; dvec3 N; dvec3 P; dvec3 V;",
        "void shade_inputs() {",
        "    ivec2 p = ivec2(gl_FragCoord.xy);",
        f"    int id = texelFetch({ident}, p, 0).r;",
        "    covered = id >= 0;",
        "    mid = max(texelFetch(mesh_id, p, 0).r, 0);"
        if "mesh_id" in gbuffer
        else "    mid = 0;",
        "    N = dvec3(texelFetch(normal, p, 0).xyz);"
        if "normal" in gbuffer
        else "    N = dvec3(0);",
        "    P = dvec3(texelFetch(position, p, 0).xyz);" if has_pos else "    P = dvec3(0);",
        "    V = unit_or_zero(EYE - P);" if has_pos else "    V = dvec3(0);",
        "}",
    ]
    return "\n".join(lines + body)
