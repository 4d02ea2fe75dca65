"""Kit export of the ``smooth`` style (Veryovka 2002 eq. 1): its two parameters as used.

Nothing is scene-dependent: ``specular`` and ``model`` are exported as the style holds them;
materials (ambient, diffuse, specular, shininess per object) and lights are in case.json's
``objects`` and ``lights``. The derived text says exactly what a backend computes per sample.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refnpr.styles.lit.params import SMOOTH

from .._json import jsonable
from ._albedo import color_derived, export_color_maps
from ._export import StyleExport

__all__ = ["export", "derived", "unresolved", "DERIVED"]

#: How a backend shades a sample (collected into docs/kit.md).
DERIVED = {
    "smooth_shading": (
        "Per covered sample (mesh_id >= 0; m = objects[mesh_id].material), in float64: rgb = "
        "m.ambient * ambient; then for each light i in the order of case.lights: rgb += "
        "m.diffuse * f_d * lights[i].color, then, when params.specular and m.shininess > 0 and "
        "f_d > 0, rgb += m.specular * f_s * lights[i].color; finally each channel clipped to "
        "[0, 1], alpha 1. Empty samples (mesh_id < 0) are (0, 0, 0, 0). N = the normal channel "
        "as stored (unit length; not renormalized), P = the position channel, L = the light's "
        "unit direction (directional: lights[i].direction; point: normalize(lights[i].position "
        "- P)), V = normalize(camera.eye - P), normalize(v) = v / |v| (zero stays zero). f_d = "
        "max(N.L, 0) (not clamped above). f_s = base^m.shininess with base = max(N.H, 0), H = "
        "normalize(L + V) (params.model 'blinn-phong'), or base = max(R.V, 0), R = 2 (N.L) N - "
        "L (params.model 'phong'); base is not clamped above."
    )
}


def derived(style: Any, scene: Any, *, width: int, height: int, spp: int) -> dict[str, str]:
    """The derived texts of a ``smooth`` case: the shading, and the colour maps where the scene
    has any."""
    return {**DERIVED, **color_derived(scene)}


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Every parameter of the declaration as used (``specular``, ``model``); the colour maps
    of the scene's materials (``params.color_texture``, roles ``color_<k>``) where it has any."""
    params = jsonable(SMOOTH.resolved(style.p), where="smooth params")
    roles, textures = export_color_maps(scene, case_dir)
    if roles:  # the material colour maps
        params["color_texture"] = roles
    return StyleExport(
        params=params,
        textures=textures,
        derived=derived(style, scene, width=width, height=height, spp=spp),
    )


def unresolved(params: dict[str, Any]) -> list[str]:
    """Declared parameters missing from ``params`` (none can hold "auto")."""
    return [k for k in SMOOTH.names if k not in params]
