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
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.formulas.tamiss import dyadic_scale, layer_frame

from .._declare import Params, Values
from .._frame import frame_record
from ..base import ShadeContext
from . import _kernels as K
from .charts import SYMMETRIES, chart_layout, per_mesh, vertex_frames
from .field import MAX_CHARTS, TILE_LIMIT, StrokeField
from .params import DERIVATIVES, PARAMS, TAM_PARAMS, salts

__all__ = [
    "FieldInputs",
    "Fragments",
    "field_inputs",
    "scene_charts",
    "DERIVATIVES",
    "gather_fragments",
    "tam_ink",
    "layer_scale",
    "CANDIDATE_CAP",
]

#: Candidates the TAM pass keeps per sample and layer (in enumeration order).
CANDIDATE_CAP = K._CAP

_SMOOTH_CHANNELS = frozenset({"bary", "normal", "position", "dposition_dx", "dposition_dy"})


@per_mesh
def _mesh_charts(mesh) -> np.ndarray:
    return K.chart_labels(np.ascontiguousarray(mesh.faces, dtype=np.int64), mesh.positions.shape[0])


def chart_meshes(scene) -> Iterator[tuple[int, Any, np.ndarray, int]]:
    """Per object of ``scene``: its index, world mesh, chart per face (labels 0..C-1) and the
    number of its first chart over the scene (charts are numbered over objects in order)."""
    offset = 0
    for k, mesh in enumerate(scene.world_meshes()):
        labels = _mesh_charts(mesh)
        yield k, mesh, labels, offset
        offset += int(labels.max()) + 1 if labels.size else 0


def scene_charts(scene, gb=None) -> np.ndarray:
    """(total triangles,) int64 chart per triangle, over the scene's meshes concatenated.

    A chart is a connected component of a mesh's faces through shared vertices (the teapot's 32
    patches, each with its own uv square, are 32 charts); numbering runs over objects in order.
    """
    out = [labels + offset for _, _, labels, offset in chart_meshes(scene)]
    charts = np.concatenate(out) if out else np.zeros(0, dtype=np.int64)
    n_charts = int(charts.max()) + 1 if charts.size else 0
    if n_charts > MAX_CHARTS:
        raise ValueError(
            f"scene: {n_charts} uv charts (connected components of the meshes), but stroke ids "
            f"hold at most {MAX_CHARTS}; weld the meshes or split the scene"
        )
    if gb is not None and charts.size != int(gb.mesh_first_tri[-1]):
        raise ValueError(
            f"gb: rasterized {int(gb.mesh_first_tri[-1])} triangles but the scene has "
            f"{charts.size}; pass the scene the G-buffer was rendered from"
        )
    return charts


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


def _scene_frames(scene) -> tuple[np.ndarray, ...]:
    """Faces (T, 3) into the scene's concatenated vertices, their frames (V, 3, 2), and per
    triangle its chart's symmetry (T,) (index into ``SYMMETRIES``), offset (T, 2) and id group
    (T,) (numbered over the scene like :func:`scene_charts`)."""
    faces, frames, sym, offset, group = [], [], [], [], []
    v_off = 0
    for _, mesh, labels, c_off in chart_meshes(scene):
        layout = chart_layout(mesh, labels)
        faces.append(np.asarray(mesh.faces, dtype=np.int64) + v_off)
        frames.append(vertex_frames(mesh))
        sym.append(layout.symmetry[labels])
        offset.append(layout.offset[labels])
        group.append(layout.group[labels] + c_off)
        v_off += mesh.positions.shape[0]
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
    point = any(light.kind == "point" for light in scene.lights)
    channels = ["uv", "duv_dx", "duv_dy"]
    channels += ["normal"] if smooth or shade else []
    channels += ["position"] if smooth or (shade and point) else []
    channels += ["dposition_dx", "dposition_dy"] if smooth else []
    frame = frame_record(ctx, tuple(channels))
    faces, frames = np.zeros((1, 3), dtype=np.int64), np.zeros((1, 3, 2))
    sym = np.zeros(1, dtype=np.int64)
    offset, group = np.zeros((1, 2)), np.zeros(1, dtype=np.int64)
    if smooth or orient:
        faces, frames, sym, offset, group = _scene_frames(scene)
    bary = np.zeros((1, 3))
    if smooth:
        bary = np.asarray(gb["bary"])
        if bary.dtype not in (np.float32, np.float64):
            bary = bary.astype(np.float64)
        bary = np.ascontiguousarray(bary).reshape(-1, 3)
    tables = K.InputTables(
        sample, bary, charts, faces, frames, SYMMETRIES, sym, offset, group, smooth, orient, shade
    )
    uv, duv_dx, duv_dy, uv_scale = (np.empty((n_sel, 2)) for _ in range(4))
    darkness, chart = np.empty(n_sel if shade else 0), np.empty(n_sel, dtype=np.int64)
    chunk_max = np.zeros((n_sel + K._CHUNK - 1) // K._CHUNK)
    K.sample_inputs(frame, tables, (uv, duv_dx, duv_dy, uv_scale, darkness, chart), chunk_max)
    if n_sel:
        extent = float(np.max(chunk_max)) * np.sqrt(2.0)
        if not extent < TILE_LIMIT:
            raise ValueError(
                f"uv: scaled texture coordinates reach {extent:.4g} tiles, but stroke ids hold "
                f"tiles within +-{TILE_LIMIT}; lower the material's uv_scale"
            )
    if constant_tone is not None:
        darkness = np.full(n_sel, float(constant_tone))
    return FieldInputs(sample, uv, duv_dx, duv_dy, uv_scale, darkness, chart, shape, gb.n)


def layer_scale(inp: FieldInputs, field: StrokeField) -> np.ndarray:
    """(N, layers) float64 dyadic scale s = log2(D_q / (7 period)) of each layer per sample.

    D_q = 1 / |grad q| in pixels per unit of q (the spacing of q's iso-lines): Veryovka's eq. 5
    for the coordinate across the strokes, with line period 7 * ``period`` (7 rows per cell). For
    strokes along u (q = v, uv_scale 1) it is the rasterizer's ``dyadic_scale`` channel with
    ``line_period = 7 * period``. The kernels' values (``formulas.tamiss.layer_frame``,
    ``dyadic_scale``): NaN where a layer has no strokes (|grad p| or |grad q| 0 or huge).
    """
    out = np.empty((inp.uv.shape[0], field.n_layers))
    for k, angle in enumerate(field.directions):
        d_q = layer_frame(inp.uv, inp.duv_dx, inp.duv_dy, inp.uv_scale, angle)[:, 3]
        out[:, k] = dyadic_scale(d_q, field.period)
    return out


def _layers(field: StrokeField) -> K.Layers:
    a = np.radians(np.asarray(field.directions, dtype=np.float64))
    return K.Layers(np.cos(a), np.sin(a), np.asarray(field.layer_tones, dtype=np.float64))


def _samples(inp: FieldInputs) -> tuple[np.ndarray, ...]:
    """The arrays the field kernels read (:func:`~._kernels.sample_inputs`' outputs)."""
    return inp.uv, inp.duv_dx, inp.duv_dy, inp.uv_scale, inp.darkness, inp.chart


def field_record(decl: Params, field: StrokeField, **values: Any) -> Any:
    """The style record of ``decl`` (``PARAMS`` or ``TAM_PARAMS``) the field kernels read:
    ``field``'s numbers, ``values`` (already validated), the declared defaults for the rest,
    and the hashes' salt offsets."""
    vals = {**decl.defaults(), **field.as_dict(), **values}
    return decl.record(Values(decl, vals, frozenset()), **salts())


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
    grid = (inp.shape[1], inp.n)
    over = chunks[~fits]
    if over.size:  # write the overflowing chunks straight to their place
        src = np.zeros(total, dtype=np.int32)
        count_over = np.zeros(over.size, dtype=np.int64)
        dst = (*out[:4], src)
        _gather(inp, field, gather_width, over, offsets[over], count[over], count_over, dst)
        K.finish_fragments(
            K.Runs(offsets[over], count[over], offsets[over]), (src, inp.sample), out[:4],
            (*out[:4], sample, x, y), grid,
        )  # fmt: skip
    sel = chunks[fits]
    K.finish_fragments(
        K.Runs(sel * _ROOM, count[sel], offsets[sel]), (buf[4], inp.sample), buf[:4],
        (*out[:4], sample, x, y), grid,
    )  # fmt: skip
    ids, t, layer, level = out[:4]
    return Fragments(sample, x, y, t, ids, layer, level, inp.shape, inp.n)


#: Room for fragments per chunk of ``_kernels._CHUNK`` samples in the single gathering pass.
_ROOM = 2 * K._CHUNK


def _fragment_arrays(n: int) -> tuple[np.ndarray, ...]:
    """Empty (id int64, t float64, layer int8, level int8, sample-in-inputs int32) of length n."""
    return tuple(np.empty(n, dtype=d) for d in (np.int64, np.float64, np.int8, np.int8, np.int32))


def _gather(inp, field, width_px, chunks, dst_off, dst_cap, count, outs) -> None:
    style = field_record(PARAMS, field, gather_width=float(width_px))
    run = K.Chunks(chunks, dst_off, dst_cap, count)
    K.field_gather(run, _samples(inp), _layers(field), style, outs)


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
    style = field_record(
        TAM_PARAMS, field, width=float(width), density_mode=density_mode, fade=float(fade)
    )
    ink = np.zeros(inp.sample.shape[0])
    K.tam_pass(_samples(inp), _layers(field), style, ink)
    out = np.zeros(inp.shape[0] * inp.shape[1])
    out[inp.sample] = ink
    return out.reshape(inp.shape)
