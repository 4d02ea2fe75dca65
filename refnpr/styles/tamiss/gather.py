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
from refnpr.formulas._shading_checks import unit_vectors

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
_REC709 = np.array([0.2126, 0.7152, 0.0722])


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
    return 1.0 - np.clip(lighting.luminance(rgb), 0.0, 1.0)


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
    shape = tuple(tri.shape)
    tri_flat = np.ascontiguousarray(tri).reshape(-1)
    sample = np.flatnonzero(tri_flat >= 0)
    n_sel = sample.shape[0]
    charts = scene_charts(scene, gb)
    scale = np.array([o.material.uv_scale for o in scene.objects], dtype=np.float64).reshape(-1, 2)
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
    smooth = derivatives == "smooth" and n_sel > 0
    orient = bool(orient_charts) and n_sel > 0
    shade = constant_tone is None and n_sel > 0

    def flat(name: str, width: int) -> np.ndarray:  # (H W, width) view of a channel
        a = np.asarray(gb[name])
        if a.dtype not in (np.float32, np.float64):
            a = a.astype(np.float64)
        return np.ascontiguousarray(a).reshape(-1, width)

    d3 = np.zeros((1, 3))
    faces, frames = np.zeros((1, 3), dtype=np.int64), np.zeros((1, 3, 2))
    sym = np.zeros(1, dtype=np.int64)
    offset, group = np.zeros((1, 2)), np.zeros(1, dtype=np.int64)
    if smooth or orient:
        faces, frames, sym, offset, group = _scene_frames(scene)
    m_a = m_d = d3
    ambient = np.zeros(3)
    l_dir, l_color, l_pos = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3))
    l_point = np.zeros(0, dtype=np.bool_)
    if shade:
        objs = scene.objects
        m_a = np.array([o.material.ambient for o in objs], dtype=np.float64).reshape(-1, 3)
        m_d = np.array([o.material.diffuse for o in objs], dtype=np.float64).reshape(-1, 3)
        ambient = np.broadcast_to(np.asarray(scene.ambient, dtype=np.float64), (3,)).copy()
        l_dir, l_color, l_pos, l_point = _light_arrays(scene)
    uses_position = smooth or (shade and bool(l_point.any()))
    uses_normal = smooth or shade
    uv = np.empty((n_sel, 2))
    duv_dx = np.empty((n_sel, 2))
    duv_dy = np.empty((n_sel, 2))
    uv_scale = np.empty((n_sel, 2))
    chart = np.empty(n_sel, dtype=np.int64)
    dark = np.empty(n_sel if shade else 0)
    chunk_max = np.zeros((n_sel + K._CHUNK - 1) // K._CHUNK)
    K.sample_inputs(
        sample,
        tri_flat,
        np.ascontiguousarray(gb["mesh_id"]).reshape(-1),
        flat("uv", 2),
        flat("duv_dx", 2),
        flat("duv_dy", 2),
        scale,
        charts,
        smooth,
        flat("bary", 3) if smooth else d3,
        faces,
        frames,
        flat("normal", 3) if uses_normal else d3,
        flat("position", 3) if uses_position else d3,
        flat("dposition_dx", 3) if smooth else d3,
        flat("dposition_dy", 3) if smooth else d3,
        np.asarray(scene.camera.eye, dtype=np.float64).reshape(3),
        orient,
        SYMMETRIES,
        sym,
        offset,
        group,
        shade,
        m_a,
        m_d,
        ambient,
        l_dir,
        l_color,
        l_point,
        l_pos,
        uv,
        duv_dx,
        duv_dy,
        uv_scale,
        chart,
        dark,
        chunk_max,
    )
    if n_sel:
        extent = float(np.max(chunk_max)) * np.sqrt(2.0)
        if not extent < TILE_LIMIT:
            raise ValueError(
                f"uv: scaled texture coordinates reach {extent:.4g} tiles, but stroke ids hold "
                f"tiles within +-{TILE_LIMIT}; lower the material's uv_scale"
            )
    if constant_tone is not None:
        dark = np.full(n_sel, float(constant_tone))
    elif not n_sel:
        dark = darkness(ctx, tri >= 0, None)
    return FieldInputs(
        sample=sample,
        uv=uv,
        duv_dx=duv_dx,
        duv_dy=duv_dy,
        uv_scale=uv_scale,
        darkness=np.ascontiguousarray(dark),
        chart=chart,
        shape=shape,
        n=gb.n,
    )


def _light_arrays(scene) -> tuple[np.ndarray, ...]:
    """Per light of ``scene``: unit direction (directional lights; as ``ShadeContext.light_dirs``
    then ``lighting.diffuse`` normalize it), colour, position (point lights), is-point flag."""
    lights = list(scene.lights)
    n = len(lights)
    l_dir, l_color, l_pos = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    l_point = np.zeros(n, dtype=np.bool_)
    for k, light in enumerate(lights):
        l_color[k] = np.asarray(light.color, dtype=np.float64)
        if light.kind == "point":
            l_point[k] = True
            l_pos[k] = np.asarray(light.position, dtype=np.float64)
        else:
            d = np.asarray(light.direction, dtype=np.float64)
            l_dir[k] = unit_vectors(d / np.linalg.norm(d))
    return l_dir, l_color, l_pos, l_point


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
    n_chunks = (n + K._CHUNK - 1) // K._CHUNK
    chunks = np.arange(n_chunks, dtype=np.int64)
    # one pass into per-chunk runs of room _ROOM; chunks with more fragments are run again
    room = np.full(n_chunks, _ROOM, dtype=np.int64)
    buf = _fragment_arrays(n_chunks * _ROOM)
    count = np.zeros(n_chunks, dtype=np.int64)
    _gather(inp, field, gather_width, chunks, chunks * _ROOM, room, count, buf)
    offsets = np.zeros(n_chunks, dtype=np.int64)
    np.cumsum(count[:-1], out=offsets[1:])
    total = int(count.sum())
    out = _fragment_arrays(total)
    sample, x, y = np.empty(total, dtype=np.int64), np.empty(total), np.empty(total)
    fits = count <= room
    run_src = np.empty(n_chunks, dtype=np.int64)
    run_src[fits] = chunks[fits] * _ROOM
    run_len = np.where(fits, count, 0)
    over = chunks[~fits]
    if over.size:  # write the overflowing chunks straight to their place
        src = np.zeros(total, dtype=np.int32)
        count_over = np.zeros(over.size, dtype=np.int64)
        dst = (*out[:4], src)
        _gather(inp, field, gather_width, over, offsets[over], count[over], count_over, dst)
        run_src[over] = offsets[over]
        run_len[over] = count[over]
        K.finish_fragments(
            offsets[over], count[over], offsets[over], src, inp.sample, inp.shape[1], inp.n,
            *out[:4], *out[:4], sample, x, y,
        )  # fmt: skip
    sel = np.flatnonzero(fits)
    K.finish_fragments(
        run_src[sel], run_len[sel], offsets[sel], buf[4], inp.sample, inp.shape[1], inp.n,
        *buf[:4], *out[:4], sample, x, y,
    )  # fmt: skip
    ids, t, layer, level = out[:4]
    return Fragments(sample, x, y, t, ids, layer, level, inp.shape, inp.n)


#: Room for fragments per chunk of ``_kernels._CHUNK`` samples in the single gathering pass.
_ROOM = 2 * K._CHUNK


def _fragment_arrays(n: int) -> tuple[np.ndarray, ...]:
    """Empty (id int64, t float64, layer int8, level int8, sample-in-inputs int32) of length n."""
    return (
        np.empty(n, dtype=np.int64),
        np.empty(n),
        np.empty(n, dtype=np.int8),
        np.empty(n, dtype=np.int8),
        np.empty(n, dtype=np.int32),
    )


def _gather(inp, field, width_px, chunks, dst_off, dst_cap, count, outs) -> None:
    cos_a, sin_a, tone_lo = _layer_arrays(field)
    K.field_gather(
        chunks,
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
        float(width_px),
        salt_offset(SALT_TONE),
        salt_offset(SALT_LENGTH),
        dst_off,
        dst_cap,
        count,
        *outs,
    )


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
