"""Kit export of the ``threshold`` style (Veryovka 2002): every parameter resolved, every table
and texture the style samples written as files (interface A of the conformance kit).

What a backend receives, beyond every parameter of the style's declaration
(:data:`refnpr.styles.threshold.params.PARAMS`, in its order, None as null; ``pyramid``, a
Python object, left out; the deprecated ``scale`` after ``tone_fade``):

- ``uv_scales``: per object index ``[su, sv]`` multiplying uv (the style's ``uv_scale`` or the
  material's, times the deprecated ``scale``), as :meth:`ThresholdStyle.uv_scales` resolves it.
- ``channel_scale``: whether single unfiltered lines read eq. 5 from the G-buffer's
  ``dyadic_scale`` channel (rasterized with ``raster_options.line_period``) minus log2(sv).
- source "image": ``object_textures`` (per object index the role of its threshold pyramid, or
  null for the constant ``t``) and, per role ``threshold_<g>``, every mip level of the pyramid
  the style built (CLAHE per level, rank-equalized, as :class:`PyramidCache` makes it); with
  ``tone_correct`` the role ``tone_map_<g>``: one row per level of 1025 interpolant quantiles
  (``ToneMaps``), applied as ``np.interp(t, q, linspace(0, 1, 1025))``.
- several line directions: ``layer_schedule`` (``lam`` and ``levels`` of
  :func:`refnpr.formulas.threshold.layer_schedule`, the water-filling breakpoints).
- source "stipple" with ``uniform``: the role ``stipple_tone``, the (n_t * n_t, n_y) CDF table of
  :func:`stipple_tone_table` (row ``a * n_t + b`` for (t_u, t_v) = (a, b) / (n_t - 1)).
- ``bump``: the role ``bump`` with the box-filtered height pyramid.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from refnpr.formulas import threshold as thr
from refnpr.kit.textures import write_pyramid, write_table
from refnpr.styles.threshold.shading import uv_scale_table

from ._export import StyleExport

__all__ = ["export", "unresolved", "DERIVED"]

#: The backend's own computations, as text (collected into docs/kit.md).
DERIVED = {
    "threshold_shading": (
        "Per covered sample (mask: mesh_id >= 0): I = m_a l_a + sum_i m_d B(f_d) l_i + sum_i "
        "m_s B(f_s) l_i (Veryovka eqs. 1-2), f_d = clamp(dot(normalize(n), L), 0, 1), f_s = "
        "Blinn-Phong max(n.h, 0)^shininess where n.L > 0 and shininess > 0 (n not renormalized, "
        "h = normalize(L + V), V = normalize(eye - position)), B(x) = x + strength * s_o * s_i * "
        "(T_n(x) - x) with s_o = 1 - facing_fade |n.v|^facing_power and s_i the smoothstep "
        "tone fades (refnpr/formulas/threshold/strength.py); T_n filtered as params.filter says "
        "(refnpr/styles/threshold/_kernels.py, images.py); the colour is clipped to [0, 1], "
        "alpha 1. uv is multiplied by params.uv_scales[mesh_id] before any lookup, and so are "
        "duv_dx / duv_dy (per-pixel derivatives; a sample's footprint is 1/n of them, n = "
        "sqrt(spp))."
    ),
    "threshold_lines": (
        "Hatching layer at angle a (degrees in params.directions): v_a = -u sin a + v cos a "
        "(and its derivatives), s = -log2(period |grad v_a|) (eq. 5; or the dyadic_scale "
        "channel minus log2(sv) when params.channel_scale), floored when multiscale is false; "
        "F = multiscale_line(Frac(v_a 2^floor(s)), Frac(s), uniform) (eqs. 6-8, "
        "refnpr/formulas/threshold/lines.py), Frac(F + noise) with noise = params.noise * "
        "value_noise(uv * noise_scale, noise_seed) (refnpr/styles/threshold/noise.py: "
        "splitmix64 lattice hash, quintic fade, two octaves). Several layers combine by "
        "combine_thresholds (compose.py) with params.layer_schedule; filter 'analytic' is "
        "line_coverage (filtering.py) per layer over the footprint dv/n, the layers' coverages "
        "multiplied at the whites layer_whites(Frac(x n))."
    ),
    "threshold_stipple": (
        "refnpr/formulas/threshold/stipple.py: per-axis dyadic scales, four-term tensor blend "
        "of exactly uniform round dots with rows at splitmix64-hashed phases (hash of the "
        "float64 bits of the row's exact v and noise_seed), dot offsets up to params.jitter "
        "tiles; with uniform the trilinear lookup in textures.stipple_tone."
    ),
}


def _params(style: Any) -> dict[str, Any]:
    """Every declared parameter (None as null) but the Python-only ``pyramid``, the deprecated
    ``scale`` after ``uv_scale`` (both shown, as params() shows them)."""
    out = {}
    for name, value in style.p.as_dict(keep_none=True).items():
        if name != "pyramid":
            out[name] = value
        if name == "uv_scale":
            out["scale"] = style.scale
    return out


def _image_textures(style: Any, scene: Any, case_dir: Path, params: dict, textures: dict) -> None:
    """Threshold pyramids (and tone maps) per distinct texture, as the style groups objects
    (refnpr/styles/threshold/style.py ``image_thresholds``)."""
    p = style.p
    roles: dict[Any, str | None] = {}
    per_object = []
    for obj in scene.objects:
        tex = p.texture if p.texture is not None else obj.material.texture
        key = "<prebuilt>" if style.pyramid is not None else tex
        if key not in roles and key is None:
            roles[key] = None
        elif key not in roles:
            pyr = style.pyramid
            if pyr is None:
                pyr = style.pyramids.get(tex, p, tiling=p.tiling)
            g = sum(r is not None for r in roles.values())
            role = roles[key] = f"threshold_{g}"
            textures[role] = write_pyramid(
                case_dir,
                role,
                pyr.levels,
                filter=(
                    "per_level"
                    if (p.filter == "pcf" and p.mip == "per_level") or p.tone_correct
                    else "linear_mipmap_linear"
                ),
                used_for=(
                    f"threshold pyramid of {key!r} (clahe_levels={p.clahe_levels!r}), "
                    "sampled bilinearly at levels floor/ceil of the GL LOD"
                ),
            )
            if p.tone_correct:
                textures[f"tone_map_{g}"] = write_table(
                    case_dir,
                    f"tone_map_{g}",
                    np.stack(style.pyramids.tone_maps(pyr).quantiles),
                    orientation="row k = mip level k; column i = quantile i / 1024",
                    used_for=(
                        "tone_correct: per level, bilinear threshold t -> "
                        "interp(t, row k, linspace(0, 1, 1025)); a row with "
                        "q[-1] <= q[0] maps to 0.5"
                    ),
                )
        per_object.append(roles[key])
    params["object_textures"] = per_object
    params["tone_maps"] = [
        None if r is None or not p.tone_correct else r.replace("threshold_", "tone_map_")
        for r in per_object
    ]


def export(style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int):
    """Resolved parameters, textures and derivation notes of a ``threshold`` style for
    ``scene`` (what the module docstring lists)."""
    if getattr(style, "name", "") != "threshold":
        raise TypeError(
            f"style: expected a 'threshold' style, got {getattr(style, 'name', style)!r}"
        )
    case_dir = Path(case_dir)
    p = style.p
    params = _params(style)
    params["uv_scales"] = uv_scale_table(style, scene).tolist()  # as the kernel reads them
    params["channel_scale"] = bool(style._channel_scale())
    params["spp_n"] = int(round(math.sqrt(spp)))
    textures: dict[str, Any] = {}
    if p.source == "image":
        _image_textures(style, scene, case_dir, params, textures)
    if p.source == "lines":
        onsets = p.onsets if p.onsets is not None else (1.0,) * len(p.directions)
        params["onsets_resolved"] = [float(o) for o in onsets]
        lam, levels = thr.layer_schedule(onsets)
        params["layer_schedule"] = {"lam": lam.tolist(), "levels": levels.tolist()}
    if p.source == "stipple" and p.uniform:
        c = style.stipple_tone_table().cdf  # the style's own table
        textures["stipple_tone"] = write_table(
            case_dir,
            "stipple_tone",
            c.reshape(c.shape[0] * c.shape[1], c.shape[2]),
            orientation=(
                f"row a * {c.shape[0]} + b = (t_u, t_v) = (a, b) / {c.shape[0] - 1}; column i = "
                f"y = i / {c.shape[2] - 1}"
            ),
            used_for="uniform stipple: trilinear lookup of the tone CDF G(F | t_u, t_v)",
        )
        params["stipple_tone_shape"] = [int(s) for s in c.shape]
        params["stipple_tone"] = "stipple_tone"  # the texture role of the table
    if style._bump is not None:
        params["bump_source"] = params["bump"]  # the texture refnpr built the pyramid from
        params["bump"] = "bump"  # the texture role of the height pyramid
        textures["bump"] = write_pyramid(
            case_dir,
            "bump",
            style._bump.pyramid.levels,
            filter="linear_mipmap_linear",
            used_for=(
                "bump height pyramid (times bump_height), trilinear at the footprint's GL LOD, "
                "central differences over the pixel (refnpr/styles/threshold/bump.py)"
            ),
        )
    return StyleExport(params=params, textures=textures, derived=dict(DERIVED))


def unresolved(params: dict[str, Any]) -> list[str]:
    """Key paths of exported params a backend could not use without refnpr: an image source
    whose textured objects lack a pyramid role, or missing resolved tables."""
    out = []
    if params.get("source") == "image" and "object_textures" not in params:
        out.append("object_textures")
    if params.get("source") == "lines" and "layer_schedule" not in params:
        out.append("layer_schedule")
    if "uv_scales" not in params:
        out.append("uv_scales")
    return out
