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
from ._export import StyleExport

__all__ = ["export", "unresolved", "DERIVED"]

#: How a backend shades a sample (collected into docs/kit.md).
DERIVED = {
    "smooth_shading": (
        "Per covered sample (mesh_id >= 0; m = objects[mesh_id].material): rgb = m.ambient * "
        "ambient + sum over lights of m.diffuse * f_d * light.color + (params.specular) "
        "m.specular * f_s * light.color (Veryovka eq. 1), clipped to [0, 1], alpha 1; empty "
        "samples (0, 0, 0, 0). N = the normal channel as stored (already unit length; not "
        "renormalized), L = the light's unit direction (directional: direction / |direction|; "
        "point: normalize(position_light - position)), V = normalize(camera.eye - position). "
        "f_d = max(N.L, 0) (not clamped above). f_s = 0 where N.L <= 0 or shininess <= 0, else "
        "max(B, 0)^shininess with B = N.normalize(L + V) (params.model 'blinn-phong') or B = "
        "(2 (N.L) N - L).V ('phong'). refnpr computes in float64 (refnpr/styles/lit/_kernels.py "
        "shade_smooth, refnpr/formulas/lighting.py)."
    )
}


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Every parameter of the declaration as used (``specular``, ``model``); no textures."""
    params = jsonable(SMOOTH.resolved(style.p), where="smooth params")
    return StyleExport(params=params, derived=dict(DERIVED))


def unresolved(params: dict[str, Any]) -> list[str]:
    """Declared parameters missing from ``params`` (none can hold "auto")."""
    return [k for k in SMOOTH.names if k not in params]
