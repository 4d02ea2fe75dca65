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
from ._export import StyleExport

__all__ = ["export", "unresolved", "DERIVED"]

DERIVED = {
    "toon_shading": (
        "Per covered sample (mesh_id >= 0; m = objects[mesh_id].material): rgb = m.ambient * "
        "ambient + sum over lights of m.diffuse * tone * light.color (+ in step mode with "
        "params.specular: m.specular * T_n(f_s, t) * light.color), clipped to [0, 1], alpha 1. "
        "f_d = max(N.L, 0) with N the normal channel as stored and L the light's unit "
        "direction; f_s as in the smooth style (Blinn-Phong, per-object shininess). Step mode: "
        "tone = T_n(f_d, t) with T_n(x, t) = min(floor(x n) + [x n - floor(x n) >= t], "
        "ceil(x n)) / n (Veryovka eq. 4, bounded by ceil(x n) / n: refnpr step_n). Lake mode: "
        "tone = ramp[min(floor(clamp(f_d, 0, 1) K), K - 1)] from the texture role 'ramp' "
        "(equivalently: the count of j in 0..n-1 with (j + t) / n <= (i + 0.5) / K, divided "
        "by n, for texel i). refnpr computes in float64 (refnpr/styles/lit/_kernels.py "
        "shade_toon; the ramp: refnpr/styles/lit/shading.py lake_ramp)."
    )
}


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """n, t, mode, specular; in lake mode also the ramp texture ``textures/ramp/level_0.exr``."""
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
    return StyleExport(
        params=jsonable(params, where="toon params"), textures=textures, derived=dict(DERIVED)
    )


def unresolved(params: dict[str, Any]) -> list[str]:
    """Missing keys (lake mode needs the ramp role and its size)."""
    need = TOON.names + (("ramp", "ramp_size") if params.get("mode") == "lake" else ())
    return [k for k in need if k not in params]
