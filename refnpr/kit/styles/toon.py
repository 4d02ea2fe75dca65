"""Kit export of the ``toon`` style (Veryovka 2002 eqs. 2-4, Lake et al. 2000's ramp).

``params``: ``n``, ``t``, ``mode`` and ``specular`` as used (``specular`` is false in lake mode,
as the style forces it). In lake mode the 1D ramp refnpr builds and samples is exported as the
texture role ``ramp`` (float32 EXR, shape (1, K), K = ``params.ramp_size`` = 1024: texel i
holds the tone of N.L in [i / K, (i + 1) / K), looked up with nearest filtering at texel
``min(floor(clamp(N.L, 0, 1) K), K - 1)``) and referenced by ``params.ramp`` = "ramp".
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refnpr.styles.lit.params import TOON
from refnpr.styles.lit.shading import lake_ramp

from .._json import jsonable
from ..textures import write_table
from ._albedo import color_derived, export_color_maps
from ._export import StyleExport

__all__ = ["export", "derived", "unresolved", "DERIVED"]

#: What every toon case computes (the step or the Lake text follows).
COMMON = (
    "Per covered sample (mesh_id >= 0; m = objects[mesh_id].material), in float64: rgb = "
    "m.ambient * ambient; then for each light i in the order of case.lights: rgb += m.diffuse "
    "* tone * lights[i].color, then, in step mode with params.specular and m.shininess > 0, rgb "
    "+= m.specular * f_s * lights[i].color; finally each channel clipped to [0, 1], alpha 1. "
    "Empty samples (mesh_id < 0) are (0, 0, 0, 0): the background shows there. N = the normal "
    "channel as stored (unit length; not renormalized), P = the position channel, L = the "
    "light's unit direction (directional: lights[i].direction; point: "
    "normalize(lights[i].position - P)), V = normalize(camera.eye - P), normalize(v) = v / |v| "
    "(zero stays zero); f_d = max(N.L, 0) (not clamped above)."
)
STEP = (
    " Step mode (params.mode 'step', Veryovka eqs. 2-4): T_n(x, t) = min(floor(x n) + (1 if x n "
    "- floor(x n) >= t else 0), ceil(x n)) / n with n = params.n, t = params.t (eq. 4, bounded by "
    "ceil(x n) / n); tone = T_n(f_d, t); the specular term is Blinn-Phong thresholded the same "
    "way: f_s = T_n(base^m.shininess, t) with base = max(N.H, 0), H = normalize(L + V) (base not "
    "clamped above) where f_d > 0, and f_s = 0 where f_d = 0."
)
LAKE = (
    " Lake mode (params.mode 'lake', Lake et al. 2000; params.specular is false): tone = "
    "ramp[min(floor(min(f_d, 1) K), K - 1)], ramp the texture role params.ramp (K = "
    "params.ramp_size texels, nearest); texel i of the ramp holds the count of j in 0 .. n - 1 "
    "with (j + t) / n <= (i + 0.5) / K, divided by n (n = params.n, t = params.t)."
)
DERIVED = {"toon_shading": COMMON + STEP}


def derived(style: Any, scene: Any, *, width: int, height: int, spp: int) -> dict[str, str]:
    """The derived texts of a ``toon`` case: the step mode's or the Lake ramp's, and the colour
    maps where the scene has any."""
    return {
        "toon_shading": COMMON + (LAKE if style.mode == "lake" else STEP),
        **color_derived(scene),
    }


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """n, t, mode, specular; in lake mode also the ramp texture ``textures/ramp/level_0.exr``;
    the colour maps of the scene's materials (``params.color_texture``) where it has any."""
    # every parameter as the style holds it (specular false in lake mode, as the style forces)
    params = {**TOON.resolved(style.p), "specular": bool(style.specular)}
    textures = {}
    if style.mode == "lake":
        ramp = lake_ramp(style.n, style.t)  # the ramp the style samples
        textures["ramp"] = write_table(
            case_dir,
            "ramp",
            ramp.reshape(1, -1),
            orientation="row 0 only; texel i (column) covers N.L in [i / K, (i + 1) / K)",
            used_for="Lake et al. 2000 toon ramp: tone indexed by clamp(N.L, 0, 1)",
        )
        params["ramp"] = "ramp"
        params["ramp_size"] = ramp.shape[-1]
    roles, maps = export_color_maps(scene, case_dir)
    if roles:  # the material colour maps
        params["color_texture"] = roles
        textures.update(maps)
    return StyleExport(
        params=jsonable(params, where="toon params"),
        textures=textures,
        derived=derived(style, scene, width=width, height=height, spp=spp),
    )


def unresolved(params: dict[str, Any]) -> list[str]:
    """Missing keys (lake mode needs the ramp role and its size)."""
    need = TOON.names + (("ramp", "ramp_size") if params.get("mode") == "lake" else ())
    return [k for k in need if k not in params]
