"""``rasterize``: meshes + camera -> GBuffer, computing exactly the channels asked for."""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence

import numpy as np

from .. import _memory
from . import _kernels as K
from .camera import Camera
from .channels import attribute_names, check_vertex_data, interpolated_channels
from .gbuffer import BUILTIN_CHANNELS, GBuffer
from .mesh import Mesh

__all__ = ["rasterize", "valid_channels", "DEFAULT_TILE"]

#: Tile edge in samples. Each tile is owned by one thread (no atomics, no races).
DEFAULT_TILE = 32
#: Fixed chunk count for parallel binning (independent of the thread count -> same lists).
_BIN_CHUNKS = 64
#: Largest guard band (in NDC units) triangles are clipped to before fixed-point snapping.
_MAX_GUARD = 16.0
#: Sample-space coordinates in units of 1/(512 n) px must stay below this for int64 edge math.
_FIXED_LIMIT = 2.0**30
#: Relative slack of the per-sample near/far depth clip (Q = 1/w in [1/far, 1/near]).
_DEPTH_CLIP_SLACK = 1e-6


def _meshes_of(obj) -> list[Mesh]:
    if isinstance(obj, Mesh):
        return [obj]
    if hasattr(obj, "world_meshes"):
        meshes = list(obj.world_meshes())
    elif isinstance(obj, Sequence) and not isinstance(obj, (str, bytes)):
        meshes = list(obj)
    else:
        raise TypeError(
            f"mesh_or_scene: expected a Mesh, a sequence of Mesh or a Scene, got {type(obj).__name__}"
        )
    if not meshes:
        raise ValueError("mesh_or_scene: no meshes to rasterize; add at least one mesh")
    for i, m in enumerate(meshes):
        if not isinstance(m, Mesh):
            raise TypeError(f"mesh_or_scene[{i}]: expected a Mesh, got {type(m).__name__}")
    return meshes


def valid_channels(meshes: Mesh | Sequence[Mesh] | None = None) -> list[str]:
    """Channel names ``rasterize`` accepts (built-ins plus the meshes' common vertex attributes)."""
    names = set(BUILTIN_CHANNELS)
    if meshes is not None:
        for a in attribute_names(_meshes_of(meshes)):
            names |= {a, f"d{a}_dx", f"d{a}_dy"}
    return sorted(names)


def _check_int(name: str, value, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if value < lo:
        raise ValueError(f"{name}: expected an integer >= {lo}, got {value}")
    return int(value)


def _spp_side(spp) -> int:
    spp = _check_int("spp", spp, 1)
    n = math.isqrt(spp)
    if spp > _memory.MAX_SPP:
        m = math.isqrt(_memory.MAX_SPP)
        raise ValueError(
            f"spp: expected at most {_memory.MAX_SPP} samples per pixel (a {m} x {m} grid), "
            f"got {spp}; use a square such as 16, 64 or 256"
        )
    if n * n != spp:
        raise ValueError(
            f"spp: expected a square number of samples per pixel (1, 4, 9, 16, ...), got {spp}; "
            f"use {n * n} or {(n + 1) ** 2}"
        )
    return n


def attribute_widths(meshes: Sequence[Mesh]) -> dict[str, int]:
    """Components of each common vertex attribute (1 for a scalar one), for memory estimates."""
    first = meshes[0].attributes
    return {
        a: 1 if first[a].ndim == 1 else int(np.prod(first[a].shape[1:]))
        for a in attribute_names(meshes)
    }


def _parse_channels(channels: Iterable[str], attr_names: set[str]) -> set[str]:
    if isinstance(channels, str):
        channels = [channels]
    try:
        wanted = list(channels)
    except TypeError:
        raise TypeError(f"channels: expected a sequence of names, got {channels!r}") from None
    valid = set(BUILTIN_CHANNELS)
    for a in attr_names:
        valid |= {a, f"d{a}_dx", f"d{a}_dy"}
    for c in wanted:
        if not isinstance(c, str):
            raise TypeError(f"channels: names must be strings, got {c!r}")
        if c not in valid:
            raise ValueError(f"channels: unknown channel {c!r}; valid channels are {sorted(valid)}")
    if not wanted:
        raise ValueError("channels: ask for at least one channel, e.g. ('depth', 'tri_id')")
    return set(wanted)


def rasterize(
    mesh_or_scene,
    camera: Camera | None,
    width: int,
    height: int,
    channels: Iterable[str] = ("depth", "tri_id"),
    spp: int = 1,
    *,
    cull_backfaces: bool = False,
    texture_size: tuple[int, int] | int | None = None,
    line_period: float = 1.0,
    dyadic_coord: str = "v",
    dtype=np.float32,
    tile: int = DEFAULT_TILE,
) -> GBuffer:
    """Rasterize triangle meshes into a G-buffer holding exactly the requested channels.

    Parameters
    ----------
    mesh_or_scene : Mesh, sequence of Mesh, or Scene
        World-space meshes (a Scene contributes ``scene.world_meshes()``). Triangle ids run over
        the meshes concatenated in order.
    camera : Camera or None
        None takes ``mesh_or_scene.camera`` (scenes only).
    width, height : int
        Image size in pixels (> 0).
    channels : iterable of str
        Channel names (see :func:`valid_channels` and ``GBuffer``). Only these are computed.
    spp : int
        Samples per pixel, a square ``n * n``: an n x n regular grid inside each pixel.
    cull_backfaces : bool
        Drop triangles that are clockwise in NDC (back-facing for counter-clockwise meshes).
    texture_size : (int, int) or int, optional
        Texture width and height in texels for the ``lod`` channel (required for it).
    line_period : float
        w of Veryovka eq. 5 in pixels, for the ``dyadic_scale`` channel.
    dyadic_coord : {"v", "u"}
        The texture coordinate the hatching lines are a function of (eq. 5's v).
    dtype : numpy.float32 or numpy.float64
        Floating channels' dtype (ids are int32).
    tile : int
        Tile edge in samples (performance knob; results do not depend on it).

    Returns
    -------
    GBuffer
        ``gb[name]`` arrays of shape ``(n H, n W)`` or ``(n H, n W, C)`` (``coverage``: ``(H, W)``).
    """
    t_start = time.perf_counter()
    meshes = _meshes_of(mesh_or_scene)
    if camera is None:
        camera = getattr(mesh_or_scene, "camera", None)
        if camera is None:
            raise TypeError("camera: expected a Camera (None only works for a Scene with a camera)")
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected refnpr.raster.Camera, got {type(camera).__name__}")
    width = _check_int("width", width, 1)
    height = _check_int("height", height, 1)
    n = _spp_side(spp)
    tile = _check_int("tile", tile, 4)
    if tile & (tile - 1):
        raise ValueError(f"tile: expected a power of two (8, 16, 32, 64), got {tile}")
    dtype = np.dtype(dtype)
    if dtype not in (np.float32, np.float64):
        raise TypeError(f"dtype: expected numpy.float32 or numpy.float64, got {dtype}")
    if not isinstance(cull_backfaces, (bool, np.bool_)):  # 1 and 0 are not flags
        raise TypeError(f"cull_backfaces: expected a bool, got {cull_backfaces!r}")
    wanted = _parse_channels(channels, attribute_names(meshes))
    check_vertex_data(meshes, wanted)
    if "lod" in wanted:
        if texture_size is None:
            raise ValueError(
                "texture_size: the lod channel needs the texture size in texels, e.g. "
                "rasterize(..., texture_size=(512, 512))"
            )
        ts = (texture_size, texture_size) if np.isscalar(texture_size) else tuple(texture_size)
        if len(ts) != 2 or any(
            isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v <= 0 for v in ts
        ):
            raise ValueError(f"texture_size: expected two positive integers, got {texture_size!r}")
        texture_size = (int(ts[0]), int(ts[1]))
    if isinstance(line_period, bool) or not isinstance(line_period, (int, float, np.number)):
        raise TypeError(f"line_period: expected a positive number of pixels, got {line_period!r}")
    if not (math.isfinite(line_period) and line_period > 0):
        raise ValueError(f"line_period: expected a positive number of pixels, got {line_period}")
    if dyadic_coord not in ("u", "v"):
        raise ValueError(f"dyadic_coord: expected 'u' or 'v', got {dyadic_coord!r}")
    _memory.check_fits(
        width,
        height,
        n * n,
        _memory.rasterize_bytes(
            width,
            height,
            n * n,
            wanted,
            attributes=attribute_widths(meshes),
            itemsize=dtype.itemsize,
            tile=tile,
        ),
    )
    nw, nh = n * width, n * height
    guard = min(_MAX_GUARD, 2.0 * _FIXED_LIMIT / (max(nw, nh) * 512.0) - 1.0)
    if guard < 1.5:
        raise ValueError(
            f"width/height/spp: the sample grid {nw} x {nh} is too large for 64-bit fixed point "
            "edge functions; keep n * max(width, height) below 1,000,000"
        )

    # ---- vertex stage (numpy) -------------------------------------------------------------
    if len(meshes) == 1:
        positions, faces = meshes[0].positions, meshes[0].faces
    else:
        positions = np.concatenate([m.positions for m in meshes])
        offsets = np.cumsum([0] + [m.n_vertices for m in meshes])
        faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets[:-1], strict=True)])
    first_tri = np.cumsum([0] + [m.n_faces for m in meshes]).astype(np.int64)
    vp = camera.projection_matrix(width, height) @ camera.view_matrix()
    n_verts = positions.shape[0]
    clip = np.empty((n_verts, 4), dtype=np.float64)
    snapped = np.empty((n_verts, 2), dtype=np.int32)
    outcode = np.empty(n_verts, dtype=np.uint8)
    K.transform_vertices(positions, vp, width, height, guard, clip, snapped, outcode)
    timings: dict[str, float] = {"vertex": time.perf_counter() - t_start}

    # ---- triangle setup (with the first binning pass), clipping -----------------------------
    t0 = time.perf_counter()
    m_tris = faces.shape[0]
    shift = tile.bit_length() - 1
    tiles_x = -(-nw // tile)
    tiles_y = -(-nh // tile)
    n_tiles = tiles_x * tiles_y
    chunk = max(1, -(-m_tris // _BIN_CHUNKS))
    counts = np.zeros((_BIN_CHUNKS, n_tiles), dtype=np.int64)
    coords = np.empty((m_tris, 6), dtype=np.int32)
    bbox = np.empty((m_tris, 4), dtype=np.int32)
    status = np.empty(m_tris, dtype=np.int8)
    qplane = np.empty((m_tris, 3), dtype=np.float64)
    cull = int(cull_backfaces)
    K.setup_triangles(
        clip,
        snapped,
        outcode,
        faces,
        n,
        width,
        height,
        cull,
        chunk,
        shift,
        tiles_x,
        coords,
        bbox,
        status,
        qplane,
        counts,
    )
    todo = np.flatnonzero(status == 2)
    sub, sub_bbox, sub_parent, sub_first = K.clip_triangles(
        clip, faces, todo, width, height, guard, cull, n, max(1, todo.size * (K.MAX_POLY - 2))
    )
    K.bin_count_clipped(todo, sub_first, sub_bbox, chunk, shift, tiles_x, counts)
    timings["setup"] = time.perf_counter() - t0

    # ---- binning: per-tile primitive lists in triangle order ---------------------------------
    t0 = time.perf_counter()
    # tile-major, chunk-minor: a tile's list is its chunks' lists in chunk (= triangle) order
    starts = np.concatenate([[0], np.cumsum(counts.T.ravel())])
    offsets = np.ascontiguousarray(starts[:-1].reshape(n_tiles, _BIN_CHUNKS).T)
    tile_first = np.ascontiguousarray(starts[::_BIN_CHUNKS])  # (n_tiles + 1,)
    lists = np.empty(int(starts[-1]), dtype=np.int32 if m_tris + sub.shape[0] < 2**31 else np.int64)
    K.bin_fill(status, bbox, todo, sub_first, sub_bbox, chunk, shift, tiles_x, offsets, lists)
    timings["bin"] = time.perf_counter() - t0

    # ---- visibility ------------------------------------------------------------------------
    t0 = time.perf_counter()
    q_lo = (1.0 - _DEPTH_CLIP_SLACK) / camera.far  # per-sample near/far clip on Q = 1/w
    q_hi = (1.0 + _DEPTH_CLIP_SLACK) / camera.near
    tri_id = np.empty((nh, nw), dtype=np.int32)
    K.raster_visibility(
        coords,
        bbox,
        sub,
        sub_bbox,
        sub_parent,
        qplane,
        q_lo,
        q_hi,
        tile_first,
        lists,
        n,
        nw,
        nh,
        tile,
        tiles_x,
        tri_id,
    )
    timings["visibility"] = time.perf_counter() - t0

    # ---- channels ----------------------------------------------------------------------------
    t0 = time.perf_counter()
    out: dict[str, np.ndarray] = {}
    if "tri_id" in wanted:
        out["tri_id"] = tri_id
    if "coverage_count" in wanted:
        cc = np.zeros((nh, nw), dtype=np.int32)
        K.raster_count(
            coords,
            bbox,
            sub,
            sub_bbox,
            sub_parent,
            qplane,
            q_lo,
            q_hi,
            tile_first,
            lists,
            n,
            nw,
            nh,
            tile,
            tiles_x,
            cc,
        )
        out["coverage_count"] = cc
    if "mesh_id" in wanted:
        mesh_id = np.searchsorted(first_tri, tri_id, side="right").astype(np.int32) - 1
        mesh_id[tri_id < 0] = -1
        out["mesh_id"] = mesh_id
    if "coverage" in wanted:
        cov = np.empty((height, width), dtype=dtype)
        K.resolve_coverage(tri_id, n, cov)
        out["coverage"] = cov
    out.update(
        interpolated_channels(
            wanted,
            meshes=meshes,
            positions=positions,
            faces=faces,
            clip=clip,
            qplane=qplane,
            tri_id=tri_id,
            n=n,
            width=width,
            height=height,
            dtype=dtype,
            texture_size=texture_size,
            line_period=line_period,
            dyadic_coord=dyadic_coord,
        )
    )
    timings["channels"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    return GBuffer(
        channels={k: out[k] for k in sorted(out)},
        width=width,
        height=height,
        spp=n * n,
        camera=camera,
        view_projection=vp,
        mesh_first_tri=first_tri,
        texture_size=texture_size if "lod" in wanted else None,
        line_period=float(line_period),
        timings=timings,
    )
