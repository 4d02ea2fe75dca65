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

DERIVED = {
    "tam-inputs": (
        "Per covered sample (tri_id >= 0): uv, duv_dx, duv_dy from the G-buffer (the "
        "rasterizer's flat per-triangle derivatives) and uv_scale = the object's material "
        "uv_scale. derivatives 'smooth': F = sum_k bary_k [_TAM_FRAME_U, _TAM_FRAME_V]_k over "
        "the triangle's vertices (a 3 x 2 frame), A = F^T F, det = a00 a11 - a01^2; where det > "
        "1e-12 a00 a11 and det > 0, and with D = position - eye, n = the G-buffer normal, "
        "|n.D| >= 0.05 |D| |n| and |D| > 0: for each of dP = dposition_dx, dposition_dy: dP_n = "
        "dP - (n.dP / n.D) D, r = F^T dP_n, duv = A^-1 r (replaces duv_dx / duv_dy); elsewhere "
        "the flat values stay. orient_charts: with the triangle's chart symmetry M "
        "(_TAM_SYMMETRY of its vertices, row-major) and offset o (_TAM_OFFSET): uv = M uv + o, "
        "duv = M duv, uv_scale = |M| uv_scale; chart = _TAM_CHART (refnpr/styles/tamiss/"
        "gather.py field_inputs, _kernels._smooth_duv)."
    ),
    "tam-darkness": (
        "darkness = 1 - clip(luma . (m_a * ambient + sum_i m_d * f_d_i * color_i), 0, 1) with "
        "m_a, m_d the object's material ambient and diffuse, f_d = min(max(normalize(N) . "
        "normalize(L), 0), 1), N the G-buffer normal, L towards light i (point: position_i - P); "
        "or params.constant_tone when not null."
    ),
    "tam-field": (
        "Per layer k (angle directions[k], cos_a/sin_a as given): rho = clip((darkness - "
        "layer_tones[k]) / (1 - layer_tones[k]) density, 0, 1), skip when rho <= 0; u = uv_u "
        "scale_u, v = uv_v scale_v (derivatives likewise), p = c u + s v, q = -s u + c v, gp = "
        "|grad p|, gq = |grad q| (skip unless both in (0, 1e30)), d_p = 1 / gp, d_q = 1 / gq, "
        "s = log2(d_q / (7 period)). Enumerate strokes exactly as refnpr/styles/tamiss/"
        "_kernels.py _enumerate (hw_px = width (1 + width_jitter) / 2 + 0.5, end_px = 0.5): "
        "L = floor(s), f = s - L; s < 0: thin = 2^s, L = 0, f = 0; L >= max_level: L = "
        "max_level, f = 0; levels 0 .. L (+1 when f > 0), gain = thin for lev <= L else 2^f - "
        "1; rows = 7 2^lev; rows ry from floor((q - hw_px / d_q) rows) to floor((q + hw_px / "
        "d_q) rows) + 1, dist = |q - ry / rows| d_q <= hw_px; gy = floor(ry / 7), r = ry - 7 gy, "
        "kx = kx[r]; cells gx from floor(ps - h) to floor(ps + h) + 1 with ps = p 2^lev - kx / 7, "
        "h = length (1 + length_jitter) / 2 + end_px / d_p 2^lev; skip inherited seeds (lev > 0 "
        "and gx & 1 == kx & 1 and gy & 1 == r & 1); id = pack(chart, k, lev, gx, gy, r) = "
        "((((chart 4 + k) 16 + lev) << 22 + gx + 2^21) << 22 + gy + 2^21) 8 + r (int64); hash01"
        "(id, salt) = (splitmix64(uint64(id) + salt) >> 11) 2^-53 with splitmix64(z): z += m1; "
        "z = (z ^ z >> 30) m2; z = (z ^ z >> 27) m3; z ^ z >> 31 (wrapping uint64); stroke "
        "length lam = length (1 + length_jitter (2 hash01(id, salts.length) - 1)) / 2^lev, "
        "p_start = (gx + kx / 7) / 2^lev - lam / 2, t = (p - p_start) / lam, beyond = max(-t, t"
        " - 1) lam d_p, skip when beyond > end_px; at most `cap` candidates per sample and "
        "layer (in this order). Each candidate: tau = hash01(id, salts.tone), limit = rho gain, "
        "opacity = 1 if tau < limit else 0 (density_mode clip) or clip((limit - tau) / fade, 0,"
        " 1) (fade), skipped when <= 0; wf = 1 + width_jitter (2 hash01(id, salts.width) - 1); "
        "a = clip(width wf / 2 - dist + 0.5, 0, 1) clip(0.5 - beyond, 0, 1) opacity; ink = ink "
        "+ a (1 - ink)."
    ),
    "tam-composite": (
        "Output straight-alpha RGBA per sample: a = clip(ink, 0, 1); under = (paper, 1) on "
        "covered samples when paper is not null, else (0, 0, 0, 0); alpha = a + a_u (1 - a); "
        "rgb = clip((ink_color a + under_rgb a_u (1 - a)) / alpha, 0, 1) where alpha > 0, else "
        "0 (refnpr/styles/tamiss/compose.py composite_ink)."
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
