"""Kit export of the ``tam`` style (the texture-space RPTAM baseline of TAMISS, Szécsi et al.).

The parameters are the style's resolved declaration (``TAM_PARAMS.resolved``: directions as
angles in degrees, layer tones resolved to k / layers when not given); the constants the field
is defined by (seed columns, id bit layout, SplitMix64 hash salts) are exported as numbers (the
64-bit ones as hex strings: JSON numbers hold 53 bits). What the style derives from the meshes
is exported per vertex, computed by the style's own code (:mod:`refnpr.styles.tamiss.charts`,
:mod:`refnpr.styles.tamiss.gather`), so a backend reproduces it exactly:

* ``_TAM_FRAME_U``, ``_TAM_FRAME_V`` (VEC3): the area-weighted vertex tangent frame dP/du, dP/dv
  (``vertex_frames``) of the smooth derivatives;
* ``_TAM_CHART`` (SCALAR): the chart number the stroke ids use (the layout group over the scene
  when ``orient_charts``, else the connected component), constant over a chart;
* ``_TAM_SYMMETRY`` (VEC4, row-major 2 x 2 M of u' = M u + offset) and ``_TAM_OFFSET`` (VEC2):
  the chart orientation (identity and 0 when ``orient_charts`` is false).

Params layout (``case.json`` ``style.params``)::

    directions (degrees), cos_a, sin_a (float64 of each direction, as refnpr computes them),
    layer_tones, period, length, length_jitter, width_jitter, density, max_level, width,
    density_mode, fade, constant_tone, derivatives, orient_charts, ink, paper, base,
    luma, kx, n_rows, cell_bits, splitmix ({m1, m2, m3}), salts ({tone, length, width}: the
    offsets added to an id before hashing), cap (candidates kept per sample and layer)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .._json import jsonable
from ._export import StyleExport

__all__ = ["export", "DERIVED"]

#: splitmix64 and hash01 as the TAM and TAMISS texts define them.
HASH01 = (
    "hash01(id, salt) = (splitmix64((uint64(id) + salt) mod 2^64) >> 11) / 2^53, splitmix64(z): "
    "z = z + m1; z = (z ^ (z >> 30)) * m2; z = (z ^ (z >> 27)) * m3; return z ^ (z >> 31), all "
    "uint64 modulo 2^64 (uint64(id): the two's-complement bits of the int64 id)"
)
#: The stroke id of a seed, as the TAM and TAMISS texts define it.
PACK_ID = (
    "id = ((((chart * 4 + k) * 16 + lev) * 2^22 + (gx + 2^21)) * 2^22 + (gy + 2^21)) * 8 + r "
    "as int64 (bits: chart 10 | layer 2 | level 4 | gx + 2^21 22 | gy + 2^21 22 | row 3)"
)
#: The level rule of the dyadic scale S.
LEVELS = (
    "L = floor(S), f = S - L, thin = 1; if L < 0: thin = 2^S, L = 0, f = 0; if L >= "
    "params.max_level: L = params.max_level, f = 0. Levels lev = 0 .. L, plus L + 1 when f > "
    "0; gain = thin for lev <= L, 2^f - 1 for lev = L + 1"
)
#: The skip rule of inherited seeds.
BORN = (
    "a seed of level lev > 0 is inherited (skipped: it was enumerated at its birth level) when "
    "((gx & 1) == (kx & 1)) and ((gy & 1) == (r & 1)), & the bitwise AND of two's-complement "
    "integers, evaluated before =="
)

DERIVED = {
    "tam-inputs": (
        "Per covered sample (tri_id >= 0; o = mesh_id; V_0, V_1, V_2 the triangle's vertices in "
        "index-buffer order, per tri_id and objects[o].first_tri_id), in float64 (the G-buffer "
        "is float64: raster_options.dtype): uv, duv_dx, duv_dy from the channels (per image "
        "pixel) and (su, sv) = objects[o].material.uv_scale. params.derivatives 'smooth': g_u = "
        "sum_c bary_c _TAM_FRAME_U(V_c), g_v = sum_c bary_c _TAM_FRAME_V(V_c) (c = 0, 1, 2 in "
        "order), a00 = g_u . g_u, a01 = g_u . g_v, a11 = g_v . g_v, det = a00 a11 - a01^2; D = "
        "position - camera.eye, n = the normal channel; where det > 1e-12 (a00 a11) and det > 0 "
        "and |n . D| >= 0.05 |D| |n| and |D| > 0, for each of dP = dposition_dx, dposition_dy: "
        "lam = (n . dP) / (n . D), dP_n = dP - lam D, r0 = g_u . dP_n, r1 = g_v . dP_n, du = "
        "(a11 r0 - a01 r1) / det, dv = (a00 r1 - a01 r0) / det (these replace duv_dx, duv_dy); "
        "elsewhere the channels' values stay. Charts: _TAM_SYMMETRY (M00, M01, M10, M11, "
        "row-major), _TAM_OFFSET (o_0, o_1) and _TAM_CHART are equal on the three vertices of a "
        "triangle (read them at V_0); params.orient_charts: uv = (M00 u + M01 v + o_0, M10 u + "
        "M11 v + o_1), each derivative d = (M00 d_u + M01 d_v, M10 d_u + M11 d_v), (su, sv) = "
        "(|M00| su + |M01| sv, |M10| su + |M11| sv); with orient_charts false they are left as "
        "they are (the attributes hold the identity and 0). chart = _TAM_CHART(V_0) as an "
        "integer. The darkness to reproduce: params.constant_tone when not null, else "
        "tam-darkness."
    ),
    "tam-darkness": (
        "darkness = 1 - clip(Y, 0, 1), Y = (r 0.2126 + g 0.7152) + b 0.0722 (params.luma) of "
        "rgb = m.ambient * ambient + sum over the lights i in order of m.diffuse * f_d,i * "
        "lights[i].color (m = objects[mesh_id].material), f_d,i = min(max(normalize(n) . L_i, "
        "0), 1), n the normal channel, L_i = lights[i].direction (directional) or "
        "normalize(lights[i].position - P) (point, P the position channel), normalize(v) = v / "
        "|v|; or params.constant_tone when not null."
    ),
    "tam-field": (
        "Per covered sample, ink = 0; for each layer k in order (params.directions[k], c = "
        "params.cos_a[k], s = params.sin_a[k] as given): rho = clip((darkness - "
        "params.layer_tones[k]) / (1 - params.layer_tones[k]) * params.density, 0, 1), the "
        "layer skipped when rho <= 0. With u = uv_0 su, v = uv_1 sv and their derivatives "
        "scaled alike: p = c u + s v, q = -s u + c v, gp = hypot(c du/dx + s dv/dx, c du/dy + s "
        "dv/dy), gq = hypot(-s du/dx + c dv/dx, -s du/dy + c dv/dy); the layer is skipped unless "
        "0 < gp < 1e30 and 0 < gq < 1e30; d_p = 1 / gp, d_q = 1 / gq (pixels per unit of p, q); S "
        "= log2(d_q / (7 params.period)). " + LEVELS + "; limit = rho gain, a level skipped when "
        "limit <= 0. Constants: hw = params.width (1 + params.width_jitter) / 2 + 0.5 px across, "
        "e = 0.5 px past the ends, hw_q = hw / d_q, KX = params.kx. Each level in order: R = 7 "
        "2^lev rows per unit of q; rows ry = floor((q - hw_q) R) .. floor((q + hw_q) R) + 1 "
        "(inclusive, in order); dist = |q - ry / R| d_q, the row skipped when dist > hw; gy = "
        "floor(ry / 7), r = ry - 7 gy, kx = KX[r]; ps = p 2^lev - kx / 7, hc = params.length (1 + "
        "params.length_jitter) / 2 + (e / d_p) 2^lev; cells gx = floor(ps - hc) .. floor(ps + hc) "
        "+ 1 (inclusive, in order); " + BORN + ". " + PACK_ID + ". " + HASH01 + "; m1, m2, m3 = "
        "params.splitmix, the salts params.salts (64-bit numbers as hex strings). Stroke: lam = "
        "params.length (1 + params.length_jitter (2 hash01(id, salts.length) - 1)) / 2^lev, "
        "p_start = (gx + kx / 7) / 2^lev - lam / 2, t = (p - p_start) / lam, beyond = max(-t, t "
        "- 1) lam d_p; skipped when beyond > e. Cap: the strokes that pass the beyond test are "
        "counted; at the (params.cap + 1)-th the sample's layer ends (its later cells, rows and "
        "levels are not visited). Each counted stroke: tau = hash01(id, salts.tone); opacity = "
        "1 if tau < limit else 0 (params.density_mode 'clip') or clip((limit - tau) / "
        "params.fade, 0, 1) ('fade'), skipped when <= 0; wf = 1 + params.width_jitter (2 "
        "hash01(id, salts.width) - 1); a = clip(params.width wf / 2 - dist + 0.5, 0, 1) * "
        "clip(0.5 - beyond, 0, 1) * opacity; ink = ink + a (1 - ink). The layers ink the same "
        "value, layer after layer."
    ),
    "tam-composite": (
        "Output straight-alpha RGBA per sample, in float64 (stored as float32): a = clip(ink, 0, "
        "1); under = (paper, 1) on covered samples (tri_id >= 0) when params.paper is not null "
        "(paper clipped to [0, 1] and rounded to float32), else (0, 0, 0, 0); k = a_under (1 - "
        "a), alpha = a + k, rgb = clip((params.ink a + under_rgb k) / alpha, 0, 1) where alpha > "
        "0, else 0: samples without ink show the paper (covered samples) or nothing."
    ),
}


def _unwrap(style: Any) -> Any:
    if style.name == "contoured":
        style = style.base
    if style.name != "tam":
        raise TypeError(f"style: expected a tam style, got {style.name!r}")
    return style


def _hex(v: int | np.integer) -> str:
    return f"0x{int(v) & 0xFFFFFFFFFFFFFFFF:016x}"


def _vertex_attributes(scene: Any, orient: bool) -> dict[int, dict[str, np.ndarray]]:
    from refnpr.styles.tamiss.charts import SYMMETRIES
    from refnpr.styles.tamiss.gather import scene_charts

    from .tamiss import chart_vertices

    scene_charts(scene)  # validates the chart count (ids hold MAX_CHARTS charts)
    out: dict[int, dict[str, np.ndarray]] = {}
    for k, frames, v_chart, layout, c_off in chart_vertices(scene, "tam"):
        n_v = v_chart.shape[0]
        sym = layout.symmetry[v_chart] if orient else np.zeros(n_v, dtype=np.int64)  # identity
        attrs = {
            "tam_frame_u": frames[:, :, 0],
            "tam_frame_v": frames[:, :, 1],
            "tam_chart": (layout.group[v_chart] if orient else v_chart) + c_off,
            "tam_symmetry": SYMMETRIES[sym].reshape(n_v, 4),
            "tam_offset": layout.offset[v_chart] if orient else np.zeros((n_v, 2)),
        }
        out[k] = {name: a.astype(np.float32) for name, a in attrs.items()}
    return out


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Export a tam style for one case (see the module docstring for the params layout).

    Parameters
    ----------
    style : refnpr.styles.tamiss.TamStyle (or a ``contoured`` wrapper of one)
    scene : refnpr.scenes.Scene
    case_dir : Path
        ``DIR/<case>`` (the style samples no texture files).
    width, height, spp : int
        Image size and samples per pixel (unused: the field is per sample).

    Returns
    -------
    StyleExport
        params, derived texts and the per-vertex chart data of every object.
    """
    from refnpr.formulas.lighting import LUMA_709
    from refnpr.formulas.tamiss.field import CELL_BITS, KX, N_ROWS, SPLITMIX64, salt_offset
    from refnpr.styles.tamiss.gather import CANDIDATE_CAP
    from refnpr.styles.tamiss.params import SALTS, TAM_PARAMS

    style = _unwrap(style)
    a = np.radians(np.asarray(style.field.directions, dtype=np.float64))
    params = TAM_PARAMS.resolved(
        style.values,
        cos_a=np.cos(a).tolist(),
        sin_a=np.sin(a).tolist(),
        luma=list(LUMA_709),
        kx=[int(x) for x in KX],
        n_rows=int(N_ROWS),
        cell_bits=CELL_BITS,
        splitmix={k: _hex(m) for k, m in zip(("m1", "m2", "m3"), SPLITMIX64, strict=True)},
        salts={k: _hex(salt_offset(v)) for k, v in SALTS.items()},
        cap=CANDIDATE_CAP,
    )
    return StyleExport(
        params=jsonable(params, where="style 'tam' params"),
        derived=dict(DERIVED),
        vertex_attributes=_vertex_attributes(scene, style.values.orient_charts),
    )
