"""Kit export of the ``tamiss`` style (Szécsi, Szirányi, Kacsó: TAMISS).

Every parameter is resolved by the style's own code: its declaration's resolved values
(``PARAMS.resolved``: ``directions`` as angles in degrees, ``layer_tones`` as numbers),
``visibility_threshold`` from the formula's default 1 / (2 (1 + prior_weight)), and the brush
as a texture file. What TAMISS derives from the
mesh topology (uv charts, their orientation, offset and id group, the smooth per-vertex tangent
frames) is exported per vertex, computed by refnpr's own functions
(:func:`refnpr.styles.tamiss.charts.chart_layout`, :func:`~refnpr.styles.tamiss.charts
.vertex_frames`), so that a backend needs no mesh analysis.

Params layout (``case.json`` ``style.params``): the declared parameters in their order
(directions, layer_tones, period, length, length_jitter, width_jitter, density, max_level,
gather_width, aggregation, ..., smooth, ``ink``, ``paper``, ``base``), with

* ``brush``: ``{"name": <refnpr's brush name or "solid">, "role": "brush", "wrap_t": bool}``
  (texture ``brush``: (Hb, Wb) float32 alpha, rows across the stroke, columns along t);
* ``visibility_threshold``: the number used;
* ``constants``: the integers of the stroke field and its hashes (KX, salts, bit layout), so that
  the backend does not hard-code refnpr's values.

Per-vertex attributes (.glb, float32): ``_TAMISS_FRAME_U``, ``_TAMISS_FRAME_V`` (VEC3, dP/du
and dP/dv) and ``_TAMISS_FRAME_U_LO``, ``_TAMISS_FRAME_V_LO`` (the float64 residual, so hi + lo
is the float64 frame to ~1e-14), ``_TAMISS_CHART`` (SCALAR, the chart number over the scene),
``_TAMISS_CHART_MAP`` (VEC4: M00, M01, M10, M11 of the chart's signed permutation u' = M u +
offset), ``_TAMISS_CHART_OFFSET`` (VEC2), ``_TAMISS_CHART_GROUP`` (SCALAR, the chart number
stroke ids use when ``orient_charts``).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from refnpr.styles.tamiss import field as F
from refnpr.styles.tamiss import strokes as ST
from refnpr.styles.tamiss.charts import SYMMETRIES, chart_layout, vertex_frames
from refnpr.styles.tamiss.gather import chart_meshes
from refnpr.styles.tamiss.params import PARAMS
from refnpr.styles.tamiss.raster import brush_texture
from refnpr.styles.tamiss.show import LEVEL_COLORS

from .._json import jsonable
from ..textures import ORIENTATION_ROW0_TOP, write_texture_levels
from ._export import StyleExport

__all__ = ["export", "vertex_data", "DERIVED"]

DERIVED = {
    "tamiss-inputs": (
        "Per covered sample (tri_id >= 0): uv, duv_dx, duv_dy from the G-buffer (float64 in refnpr: "
        "raster_options dtype float64), uv_scale = the object's material.uv_scale. Smooth "
        "derivatives (params.derivatives == 'smooth'): F = sum_c bary[c] (FRAME_U, FRAME_V)[vertex "
        "c of triangle tri_id] (hi + lo), D = position - camera eye, n = G-buffer normal; if det = "
        "a00 a11 - a01^2 > 1e-12 a00 a11 (a = F^T F) and |n.D| >= 0.05 |D| |n|, for each of "
        "dposition_dx, dposition_dy: dP_n = dP - (n.dP / n.D) D, duv = (F^T F)^-1 F^T dP_n "
        "(else keep the rasterizer's flat values; refnpr/styles/tamiss/_kernels.py _smooth_duv). "
        "Then with orient_charts: uv' = M uv + offset, duv' = M duv, uv_scale' = |M| uv_scale, "
        "chart = CHART_GROUP (else chart = CHART), all of the triangle's first vertex. Darkness = "
        "1 - clip(luminance_709(m_a l_a + sum_i m_d max(n.L_i, 0) l_i), 0, 1) (n, L normalized; "
        "point lights L = normalize(position - P)), or params.constant_tone."
    ),
    "tamiss-field": (
        "RPTAM stroke field per layer k (angle a = directions[k]): p = cos a u' su + sin a v' sv, "
        "q = -sin a u' su + cos a v' sv (su, sv = uv_scale'), |grad p|, |grad q| from the "
        "derivatives; d_p = 1/|grad p|, d_q = 1/|grad q|; s = log2(d_q / (7 period)); L = floor(s), "
        "f = s - L; if L < 0: thin = 2^s, L = 0, f = 0; if L >= max_level: L = max_level, f = 0. "
        "rho = clip(density (darkness - layer_tones[k]) / (1 - layer_tones[k]), 0, 1), skip if 0. "
        "Levels lev = 0 .. L (+1 if f > 0), gain = thin (lev <= L) or 2^f - 1. Rows ry with |q - "
        "ry / (7 2^lev)| d_q <= hw (hw = gather_width / 2), gy = floor(ry / 7), r = ry - 7 gy, "
        "kx = KX[r]; cells gx around p 2^lev - kx / 7 within 0.5 length (1 + length_jitter); skip "
        "inherited seeds (lev > 0 and gx & 1 == kx & 1 and gy & 1 == r & 1). id = pack(chart, k, "
        "lev, gx, gy, r) (63-bit: chart 10 | layer 2 | level 4 | gx + 2^21 (22) | gy + 2^21 (22) | "
        "row 3); stroke length = length (1 + length_jitter (2 hash01(id, SALT_LENGTH) - 1)) / "
        "2^lev; t = (p - ((gx + kx / 7) / 2^lev - length / 2)) / length; a fragment (x, y, t, id) "
        "is emitted when t in [0, 1] and hash01(id, SALT_TONE) < rho gain, in the order layer, "
        "level, row, cell per sample (refnpr/styles/tamiss/_kernels.py _enumerate, field_gather; "
        "docstring of refnpr/styles/tamiss/field.py). hash01(id, salt) = (splitmix64(id + salt "
        "0x9E3779B97F4A7C15 mod 2^64) >> 11) 2^-53; x, y = sample centre in PIXELS ((sx + 0.5) / "
        "n, (sy + 0.5) / n)."
    ),
    "tamiss-aggregate-fit": (
        "Per stroke id (aggregation 'exact': group by the 64-bit id; 'hashed': the paper's "
        "double-hashed table, refnpr/formulas/tamiss/hashing.py) in params.dtype: t_min, t_max "
        "(min/max of t), origin = (min + max) / 2 of (x, y), s = (2 t - t_min - t_max) / (t_max - "
        "t_min) (0 if equal), sums of s^0..s^6, s^0..s^3 (x - o_x), s^0..s^3 (y - o_y). Fit: A = "
        "Hankel(s^0..s^6), Legendre basis change A_L = L A L^T (symmetrized), Jacobi scaling, "
        "params.iterations CG steps (rtol 8 eps of the dtype), for x and y (b = moments) and for "
        "visibility ((A + D) c_v = s^0..s^3 sums, D = prior_weight count * mean of s^m over [-1, "
        "1]). Drop rule, extents (visible segments of v >= visibility_threshold by bisection, "
        "overdraw run-on by params.overdraw px at the mean speed of a 17-point polyline), tangent "
        "continuation outside [t_min, t_max], extrusion (samples vertex pairs, taper, wobble, end "
        "jitter from id hashes with salts 11-14, width factor from SALT_WIDTH): "
        "refnpr/styles/tamiss/strokes.py and refnpr/formulas/tamiss/fit.py."
    ),
    "tamiss-raster": (
        "Each drawn piece (ascending stroke id, then segment) covers a sample of the n W x n H grid "
        "with the fraction of aa x aa sub-samples (sample units, at (x + (i + 0.5) / aa, y + (j + "
        "0.5) / aa)) inside ANY of its 2 (K - 1) triangles (L_i, R_i, L_i+1), (R_i, R_i+1, L_i+1), "
        "times opacity times the brush (bilinear, texel centres (i + 0.5) / size, u = t wrapping "
        "when brush.wrap_t else clamped, v = across 0 left .. 1 right, clamped) at the barycentric "
        "(t, across) of the triangle the sample centre is most inside; ink A <- A + a (1 - A). The "
        "style's RGBA: ink colour over paper (or nothing) with alpha = ink; show views colour each "
        "piece by a hash of its id (refnpr/styles/tamiss/show.py)."
    ),
}


def chart_vertices(scene: Any, style: str) -> Iterator[tuple]:
    """Per object of ``scene``: its index, vertex tangent frames (V, 3, 2) float64, chart per
    vertex (V,) int64, :class:`~refnpr.styles.tamiss.charts.ChartLayout` and the number of its
    first chart over the scene; an object without uv is an error naming ``style``."""
    for k, mesh, labels, c_off in chart_meshes(scene):
        if mesh.uv is None:
            raise ValueError(
                f"scene: object {k} ({mesh.name!r}) has no uv; the {style} style needs uv (the "
                "hatching direction)"
            )
        v_chart = np.zeros(mesh.positions.shape[0], dtype=np.int64)
        v_chart[np.asarray(mesh.faces, dtype=np.int64).ravel()] = np.repeat(labels, 3)
        yield k, vertex_frames(mesh), v_chart, chart_layout(mesh, labels), c_off


def vertex_data(scene: Any) -> dict[int, dict[str, np.ndarray]]:
    """Per object index: the per-vertex TAMISS attributes (see the module docstring).

    Parameters
    ----------
    scene : refnpr.scenes.Scene

    Returns
    -------
    dict
        ``{object_index: {name: (V, C) float32 array}}`` with names tamiss_frame_u,
        tamiss_frame_v, tamiss_frame_u_lo, tamiss_frame_v_lo, tamiss_chart, tamiss_chart_map,
        tamiss_chart_offset, tamiss_chart_group.
    """
    out: dict[int, dict[str, np.ndarray]] = {}
    for k, frames, v_chart, layout, c_off in chart_vertices(scene, "tamiss"):
        hi_u = frames[:, :, 0].astype(np.float32)
        hi_v = frames[:, :, 1].astype(np.float32)
        out[k] = {
            "tamiss_frame_u": hi_u,
            "tamiss_frame_v": hi_v,
            "tamiss_frame_u_lo": (frames[:, :, 0] - hi_u).astype(np.float32),
            "tamiss_frame_v_lo": (frames[:, :, 1] - hi_v).astype(np.float32),
            "tamiss_chart": (v_chart + c_off).astype(np.float32),
            "tamiss_chart_map": SYMMETRIES[layout.symmetry[v_chart]]
            .reshape(-1, 4)
            .astype(np.float32),
            "tamiss_chart_offset": layout.offset[v_chart].astype(np.float32),
            "tamiss_chart_group": (layout.group[v_chart] + c_off).astype(np.float32),
        }
        if np.any(out[k]["tamiss_chart_offset"] != layout.offset[v_chart]):
            raise ValueError(
                f"scene: object {k}: chart offsets {layout.offset} are not exact in float32"
            )
    return out


def _constants() -> dict[str, Any]:
    return {
        "KX": [int(v) for v in F.KX],
        "rows_per_cell": F.N_ROWS,
        "cell_bits": 22,
        "cell_offset": 1 << 21,
        "salt_tone": F.SALT_TONE,
        "salt_length": F.SALT_LENGTH,
        "salt_width": F.SALT_WIDTH,
        "salt_wobble_amp": ST.SALT_WOBBLE_AMP,
        "salt_wobble_phase": ST.SALT_WOBBLE_PHASE,
        "salt_end_a": ST.SALT_END_A,
        "salt_end_b": ST.SALT_END_B,
        "salt_rgb": [11, 12, 13],
        "splitmix64": ["0x9E3779B97F4A7C15", "0xBF58476D1CE4E5B9", "0x94D049BB133111EB"],
        "level_colors": LEVEL_COLORS.tolist(),
    }


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Resolved params, the brush texture and per-vertex chart data of a ``tamiss`` style.

    Parameters
    ----------
    style : TamissStyle
        (a ``contoured`` wrapper is unwrapped by :func:`refnpr.kit.styles.export_style`)
    scene : refnpr.scenes.Scene
    case_dir : Path
        The case directory; the brush goes to ``case_dir/textures/brush/``.
    width, height, spp : int
        The case's image size and samples per pixel (unused: nothing depends on them).

    Returns
    -------
    StyleExport
    """
    if getattr(style, "name", None) != "tamiss":
        raise TypeError(f"style: expected a tamiss style, got {type(style).__name__}")
    if style.base is not None:
        raise ValueError(
            "style: base is set; the kit exports the tamiss style without a base style only "
            f"(got base={style.base.name!r})"
        )
    p = style.pipeline_params
    threshold = (
        p.visibility_threshold
        if p.visibility_threshold is not None
        else 0.5 / (1.0 + p.prior_weight)
    )
    tex, wrap = brush_texture(p.brush)
    resolved = PARAMS.resolved(
        p.values,
        visibility_threshold=float(threshold),
        brush={"name": p.brush or "solid", "role": "brush", "wrap_t": bool(wrap)},
        constants=_constants(),
    )
    params = jsonable(resolved, where="style 'tamiss' params")
    textures = {
        "brush": write_texture_levels(
            Path(case_dir),
            "brush",
            [np.asarray(tex, dtype=np.float32)],
            encoding="linear",
            wrap="repeat" if wrap else "clamp",
            filter="linear",
            orientation=ORIENTATION_ROW0_TOP
            + "; rows = across the stroke (row 0 at the left edge, v = 0), columns = along t "
            "(u = t); texel centres at (i + 0.5) / size",
            used_for="tamiss brush: alpha multiplier of each stroke sample (bilinear)",
        )
    }
    return StyleExport(
        params=params,
        textures=textures,
        derived=dict(DERIVED),
        vertex_attributes=vertex_data(scene),
    )
