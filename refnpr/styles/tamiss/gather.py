"""Fragment gathering (TAMISS sec. 3.1, fig. 6) and the texture-space TAM/RPTAM baseline.

Both evaluate the stroke field of ``field`` at every covered G-buffer sample:

* :func:`gather_fragments`: every stroke whose band (``gather_width`` pixels across, t in [0, 1])
  covers the sample and that passes the tone/density test tau < rho * gain emits a fragment
  (x, y, t, id); a sample may emit several (fig. 6 is never drawn, only gathered).
* :func:`tam_ink`: the same strokes drawn per sample in texture space, anti-aliased across (pixel
  width) and at their ends, clipped (binary density test) or faded (smooth test) per sample: the
  baseline of Figure 1 (left) and Figure 3.

Per-sample inputs (:class:`FieldInputs`): uv, its screen derivatives, the material's uv_scale, the
darkness to reproduce and the chart (object and uv chart) of the triangle.
"""

from __future__ import annotations

import warnings
import weakref
from dataclasses import dataclass

import numpy as np

from refnpr.formulas import lighting

from ..base import ShadeContext
from . import _kernels as K
from .charts import SYMMETRIES, chart_layout, vertex_frames
from .field import (
    MAX_CHARTS,
    SALT_LENGTH,
    SALT_TONE,
    SALT_WIDTH,
    TILE_LIMIT,
    StrokeField,
    salt_offset,
)

__all__ = [
    "FieldInputs",
    "Fragments",
    "field_inputs",
    "scene_charts",
    "DERIVATIVES",
    "darkness",
    "gather_fragments",
    "tam_ink",
    "layer_scale",
]

_CHART_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

#: How the field takes d(uv)/d(x, y): "smooth" (continuous across triangle edges, from vertex
#: tangent frames; ``charts``) or "flat" (the rasterizer's per-triangle analytic derivatives).
DERIVATIVES = ("smooth", "flat")
_SMOOTH_CHANNELS = frozenset({"bary", "normal", "position", "dposition_dx", "dposition_dy"})


def _mesh_charts(mesh) -> np.ndarray:
    labels = _CHART_CACHE.get(mesh)
    if labels is None:
        faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
        labels = K.chart_labels(faces, mesh.positions.shape[0])
        _CHART_CACHE[mesh] = labels
    return labels


def scene_charts(scene, gb=None) -> np.ndarray:
    """(total triangles,) int64 chart per triangle, over the scene's meshes concatenated.

    A chart is a connected component of a mesh's faces through shared vertices (the teapot's 32
    patches, each with its own uv square, are 32 charts); numbering runs over objects in order.
    """
    out = []
    offset = 0
    for mesh in scene.world_meshes():
        labels = _mesh_charts(mesh)
        out.append(labels + offset)
        offset += int(labels.max()) + 1 if labels.size else 0
    charts = np.concatenate(out) if out else np.zeros(0, dtype=np.int64)
    if offset > MAX_CHARTS:
        raise ValueError(
            f"scene: {offset} uv charts (connected components of the meshes), but stroke ids "
            f"hold at most {MAX_CHARTS}; weld the meshes or split the scene"
        )
    if gb is not None and charts.size != int(gb.mesh_first_tri[-1]):
        raise ValueError(
            f"gb: rasterized {int(gb.mesh_first_tri[-1])} triangles but the scene has "
            f"{charts.size}; pass the scene the G-buffer was rendered from"
        )
    return charts


def darkness(ctx: ShadeContext, sel: np.ndarray, constant_tone: float | None) -> np.ndarray:
    """(N,) float64 darkness 1 - luminance(m_a l_a + sum_i m_d f_d l_i) at the samples ``sel``.

    The diffuse tone of Veryovka eq. 1 without the specular term (hatching conveys shading, not
    highlights); Rec. 709 luminance, clipped to [0, 1]. ``constant_tone`` overrides it.
    """
    n_sel = int(np.count_nonzero(sel))
    if constant_tone is not None:
        return np.full(n_sel, float(constant_tone))
    gb = ctx.gb
    n = gb["normal"][sel].astype(np.float64)
    mesh_id = np.maximum(gb["mesh_id"][sel], 0)
    objs = ctx.scene.objects
    m_a = np.array([o.material.ambient for o in objs], dtype=np.float64)[mesh_id]
    m_d = np.array([o.material.diffuse for o in objs], dtype=np.float64)[mesh_id]
    rgb = m_a * np.asarray(ctx.scene.ambient, dtype=np.float64)
    for light_dir, color in ctx.light_dirs():
        ld = light_dir[sel] if np.ndim(light_dir) > 1 else light_dir
        rgb = rgb + m_d * lighting.diffuse(n, ld)[..., None] * color
    lum = rgb @ np.array([0.2126, 0.7152, 0.0722])
    return 1.0 - np.clip(lum, 0.0, 1.0)


@dataclass(frozen=True, eq=False)
class FieldInputs:
    """Per-sample inputs of the stroke field, compacted to the N covered samples.

    Attributes
    ----------
    sample : (N,) int64, flat index into the (nH, nW) sample grid
    uv, duv_dx, duv_dy, uv_scale : (N, 2) float64
    darkness : (N,) float64 in [0, 1]
    chart : (N,) int64
    shape : (nH, nW); n : samples per pixel along an axis
    """

    sample: np.ndarray
    uv: np.ndarray
    duv_dx: np.ndarray
    duv_dy: np.ndarray
    uv_scale: np.ndarray
    darkness: np.ndarray
    chart: np.ndarray
    shape: tuple[int, int]
    n: int

    def pixel_xy(self, sample: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates of sample centres ((sx + 0.5) / n, (sy + 0.5) / n)."""
        idx = self.sample if sample is None else sample
        sy, sx = np.divmod(idx, self.shape[1])
        return (sx + 0.5) / self.n, (sy + 0.5) / self.n


def _scene_frames(scene) -> tuple[np.ndarray, ...]:
    """Faces (T, 3) into the scene's concatenated vertices, their frames (V, 3, 2), and per
    triangle its chart's symmetry (T,) (index into ``SYMMETRIES``), offset (T, 2) and id group
    (T,) (numbered over the scene like :func:`scene_charts`)."""
    faces, frames, sym, offset, group = [], [], [], [], []
    v_off = 0
    c_off = 0
    for mesh in scene.world_meshes():
        labels = _mesh_charts(mesh)
        layout = chart_layout(mesh, labels)
        faces.append(np.asarray(mesh.faces, dtype=np.int64) + v_off)
        frames.append(vertex_frames(mesh))
        sym.append(layout.symmetry[labels])
        offset.append(layout.offset[labels])
        group.append(layout.group[labels] + c_off)
        v_off += mesh.positions.shape[0]
        c_off += int(labels.max()) + 1 if labels.size else 0
    return tuple(np.concatenate(a) for a in (faces, frames, sym, offset, group))


def field_inputs(
    gb,
    scene,
    *,
    constant_tone: float | None = None,
    derivatives: str = "smooth",
    orient_charts: bool = True,
) -> FieldInputs:
    """Collect :class:`FieldInputs` from a G-buffer (channels: :func:`field_channels`).

    ``derivatives="smooth"`` reconstructs d(uv)/d(x, y) from interpolated vertex tangent frames
    on the plane of the shading normal (continuous across triangle edges, so levels and density
    boundaries do not follow the tessellation); ``"flat"`` takes the rasterizer's per-triangle
    ``duv_dx``, ``duv_dy``. ``orient_charts`` maps each chart's uv by the signed permutation
    and offset of :func:`~refnpr.styles.tamiss.charts.chart_layout` and gives the charts of one
    layout group one chart number, so that hatching directions agree across chart borders (the
    teapot's patches) and strokes run on across them where the uv continues."""
    ctx = ShadeContext(gb, scene)
    tri = gb["tri_id"]
    sel = tri >= 0
    charts = scene_charts(scene, gb)
    scale = np.array([o.material.uv_scale for o in scene.objects], dtype=np.float64)
    mesh_id = np.maximum(gb["mesh_id"][sel], 0)
    uv = np.ascontiguousarray(gb["uv"][sel], dtype=np.float64)
    uv_scale = np.ascontiguousarray(scale[mesh_id])
    chart = charts[tri[sel]]
    duv_dx = np.ascontiguousarray(gb["duv_dx"][sel], dtype=np.float64)
    duv_dy = np.ascontiguousarray(gb["duv_dy"][sel], dtype=np.float64)
    tri_sel = tri[sel].astype(np.int64)
    if derivatives == "smooth":
        missing = sorted(_SMOOTH_CHANNELS - set(gb.channels))
        if missing:
            warnings.warn(
                f"derivatives='smooth' needs the G-buffer channels {missing}, which were not "
                "rasterized; using the flat per-triangle derivatives. Rasterize "
                "field_channels(scene, ...) or pass derivatives='flat'",
                RuntimeWarning,
                stacklevel=2,
            )
            derivatives = "flat"
    if (derivatives == "smooth" or orient_charts) and tri_sel.size:
        faces, frames, sym, offset, group = _scene_frames(scene)
        if derivatives == "smooth":
            f64 = lambda name: np.ascontiguousarray(gb[name][sel], dtype=np.float64)  # noqa: E731
            eye = np.asarray(scene.camera.eye, dtype=np.float64)
            K.smooth_duv(
                tri_sel, f64("bary"), faces, frames, f64("normal"), f64("position"),
                f64("dposition_dx"), f64("dposition_dy"), eye, duv_dx, duv_dy,
            )  # fmt: skip
        if orient_charts:
            m = SYMMETRIES[sym[tri_sel]]  # (N, 2, 2): u' = M u + offset
            uv = np.ascontiguousarray(np.einsum("nij,nj->ni", m, uv) + offset[tri_sel])
            chart = group[tri_sel]
            duv_dx = np.ascontiguousarray(np.einsum("nij,nj->ni", m, duv_dx))
            duv_dy = np.ascontiguousarray(np.einsum("nij,nj->ni", m, duv_dy))
            uv_scale = np.ascontiguousarray(np.einsum("nij,nj->ni", np.abs(m), uv_scale))
    if uv.size:
        extent = float(np.max(np.abs(uv * uv_scale))) * np.sqrt(2.0)
        if not extent < TILE_LIMIT:
            raise ValueError(
                f"uv: scaled texture coordinates reach {extent:.4g} tiles, but stroke ids hold "
                f"tiles within +-{TILE_LIMIT}; lower the material's uv_scale"
            )
    return FieldInputs(
        sample=np.flatnonzero(sel.ravel()),
        uv=uv,
        duv_dx=duv_dx,
        duv_dy=duv_dy,
        uv_scale=uv_scale,
        darkness=np.ascontiguousarray(darkness(ctx, sel, constant_tone)),
        chart=np.ascontiguousarray(chart),
        shape=tuple(tri.shape),
        n=gb.n,
    )


def layer_scale(inp: FieldInputs, field: StrokeField) -> np.ndarray:
    """(N, layers) float64 dyadic scale s = log2(D_q / (7 period)) of each layer per sample.

    D_q = 1 / |grad q| in pixels per unit of q (the spacing of q's iso-lines): Veryovka's eq. 5
    for the coordinate across the strokes, with line period 7 * ``period`` (7 rows per cell). For
    strokes along u (q = v, uv_scale 1) it is the rasterizer's ``dyadic_scale`` channel with
    ``line_period = 7 * period``. The kernels evaluate the same expression per sample.
    """
    cos_a, sin_a, _ = _layer_arrays(field)
    su, sv = inp.uv_scale[:, :1], inp.uv_scale[:, 1:]
    qx = -sin_a * inp.duv_dx[:, :1] * su + cos_a * inp.duv_dx[:, 1:] * sv
    qy = -sin_a * inp.duv_dy[:, :1] * su + cos_a * inp.duv_dy[:, 1:] * sv
    with np.errstate(divide="ignore"):
        return np.log2(1.0 / np.hypot(qx, qy) / (7.0 * field.period))


def _layer_arrays(field: StrokeField):
    a = np.radians(np.asarray(field.directions, dtype=np.float64))
    return np.cos(a), np.sin(a), np.asarray(field.layer_tones, dtype=np.float64)


def _run(mode, inp: FieldInputs, field: StrokeField, width_px, fade, offsets, counts, outs):
    cos_a, sin_a, tone_lo = _layer_arrays(field)
    K.field_pass(
        mode,
        inp.uv,
        inp.duv_dx,
        inp.duv_dy,
        inp.uv_scale,
        inp.darkness,
        inp.chart,
        cos_a,
        sin_a,
        tone_lo,
        float(field.density),
        float(field.period),
        int(field.max_level),
        float(field.length),
        float(field.length_jitter),
        float(field.width_jitter),
        float(width_px),
        float(fade),
        salt_offset(SALT_TONE),
        salt_offset(SALT_LENGTH),
        salt_offset(SALT_WIDTH),
        offsets,
        counts,
        *outs,
    )


@dataclass(frozen=True, eq=False)
class Fragments:
    """Stroke fragments of one frame (TAMISS fig. 5, "fragment gathering").

    Attributes
    ----------
    sample : (n,) int64, flat sample index (row-major on the (nH, nW) grid)
    x, y : (n,) float64, sample centre in pixels
    t : (n,) float64, stroke-space coordinate in [0, 1]
    id : (n,) int64, global stroke id
    layer, level : (n,) int8, hatching layer and the stroke's birth level
    shape : (nH, nW); n_axis : samples per pixel along an axis
    """

    sample: np.ndarray
    x: np.ndarray
    y: np.ndarray
    t: np.ndarray
    id: np.ndarray
    layer: np.ndarray
    level: np.ndarray
    shape: tuple[int, int]
    n_axis: int

    def __len__(self) -> int:
        return int(self.id.shape[0])

    def per_sample_count(self) -> np.ndarray:
        """(nH, nW) int64 fragments per sample."""
        return np.bincount(self.sample, minlength=self.shape[0] * self.shape[1]).reshape(self.shape)

    def subset(self, keep: np.ndarray) -> Fragments:
        """The fragments where ``keep`` (bool or index array)."""
        return Fragments(
            self.sample[keep],
            self.x[keep],
            self.y[keep],
            self.t[keep],
            self.id[keep],
            self.layer[keep],
            self.level[keep],
            self.shape,
            self.n_axis,
        )


def gather_fragments(
    inp: FieldInputs, field: StrokeField, *, gather_width: float = 1.0
) -> Fragments:
    """Gather (x, y, t, id) fragments: strokes within ``gather_width / 2`` pixels of a sample
    centre across, with t in [0, 1], passing tau < rho * gain. Ordered by sample, then layer, birth
    level, row and cell (deterministic)."""
    n = inp.sample.shape[0]
    counts = np.zeros(n, dtype=np.int64)
    dummy_i = np.zeros(1, dtype=np.int64)
    dummy_f = np.zeros(1)
    dummy_b = np.zeros(1, dtype=np.int8)
    _run(
        K.MODE_COUNT, inp, field, gather_width, 1.0, dummy_i, counts,
        (dummy_i, dummy_f, dummy_b, dummy_b, dummy_f),
    )  # fmt: skip
    offsets = np.zeros(n, dtype=np.int64)
    np.cumsum(counts[:-1], out=offsets[1:])
    total = int(counts.sum())
    ids = np.empty(total, dtype=np.int64)
    t = np.empty(total)
    layer = np.empty(total, dtype=np.int8)
    level = np.empty(total, dtype=np.int8)
    _run(
        K.MODE_EMIT, inp, field, gather_width, 1.0, offsets, counts,
        (ids, t, layer, level, dummy_f),
    )  # fmt: skip
    sample = np.repeat(inp.sample, counts)
    x, y = inp.pixel_xy(sample)
    return Fragments(sample, x, y, t, ids, layer, level, inp.shape, inp.n)


def tam_ink(
    inp: FieldInputs,
    field: StrokeField,
    *,
    width: float = 1.5,
    density_mode: str = "fade",
    fade: float = 0.15,
) -> np.ndarray:
    """(nH, nW) float64 ink coverage of the texture-space TAM/RPTAM rendering of the field.

    Each stroke covers a sample with a = clip(w f / 2 - d + 0.5, 0, 1) * clip(0.5 - e, 0, 1) *
    o, where d is the distance across in pixels, e the signed distance past its nearer end in
    pixels (negative inside: full coverage from half a pixel inside the end),
    f its width factor and o its density opacity: 1 if tau < rho * gain else 0 ("clip"), or
    clip((rho * gain - tau) / fade, 0, 1) ("fade"); strokes combine as 1 - prod(1 - a).
    """
    n = inp.sample.shape[0]
    ink = np.zeros(n)
    dummy_i = np.zeros(1, dtype=np.int64)
    dummy_f = np.zeros(1)
    dummy_b = np.zeros(1, dtype=np.int8)
    mode = K.MODE_TAM_CLIP if density_mode == "clip" else K.MODE_TAM_FADE
    _run(mode, inp, field, width, fade, dummy_i, dummy_i, (dummy_i, dummy_f, dummy_b, dummy_b, ink))
    out = np.zeros(inp.shape[0] * inp.shape[1])
    out[inp.sample] = ink
    return out.reshape(inp.shape)
