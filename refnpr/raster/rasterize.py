"""``rasterize``: meshes + camera -> GBuffer, computing exactly the channels asked for."""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterable, Sequence

import numpy as np

from .. import _memory
from .._jit import call_banded as run
from . import _kernels as K
from .camera import Camera
from .channels import attribute_names, check_vertex_data, frozen, interpolated_channels
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


def _channel_names(attr_names: Iterable[str]) -> set[str]:
    return set(BUILTIN_CHANNELS).union(*({a, f"d{a}_dx", f"d{a}_dy"} for a in attr_names))


def valid_channels(meshes: Mesh | Sequence[Mesh] | None = None) -> list[str]:
    """Channel names ``rasterize`` accepts (built-ins plus the meshes' common vertex attributes)."""
    return sorted(_channel_names(() if meshes is None else attribute_names(_meshes_of(meshes))))


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
    valid = _channel_names(attr_names)
    for c in wanted:
        if not isinstance(c, str):
            raise TypeError(f"channels: names must be strings, got {c!r}")
        if c not in valid:
            raise ValueError(f"channels: unknown channel {c!r}; valid channels are {sorted(valid)}")
    if not wanted:
        raise ValueError("channels: ask for at least one channel, e.g. ('depth', 'tri_id')")
    return set(wanted)


_INT_CHANNELS = frozenset({"tri_id", "mesh_id", "coverage_count"})
#: Channels of the visibility pass (not of the interpolation).
_NOT_INTERPOLATED = frozenset({"tri_id", "mesh_id", "coverage", "coverage_count"})


def _layout(wanted, meshes, n, width, height, dtype) -> dict[str, tuple[tuple, np.dtype]]:
    """(shape, dtype) of every channel this call produces, for checking ``out``."""
    nh, nw = n * height, n * width
    comps = {name: c for name, (c, _) in BUILTIN_CHANNELS.items()}
    comps["normal"] = int(np.prod(meshes[0].normals.shape[1:])) if "normal" in wanted else 3
    for a in attribute_names(meshes):
        c = 0 if meshes[0].attributes[a].ndim == 1 else attribute_widths(meshes)[a]
        comps[a] = comps[f"d{a}_dx"] = comps[f"d{a}_dy"] = c
    layout = {}
    for name in wanted:
        shape = (height, width) if name == "coverage" else (nh, nw)
        if comps[name]:
            shape = (*shape, comps[name])
        layout[name] = (shape, np.dtype(np.int32) if name in _INT_CHANNELS else dtype)
    return layout


def _check_out(out, layout, width, height, spp, dtype) -> None:
    """Raise unless ``out`` can hold exactly what this call writes (see ``rasterize``)."""
    if not isinstance(out, GBuffer):
        raise TypeError(
            f"out: expected a GBuffer returned by an earlier rasterize call (or None), "
            f"got {type(out).__name__}"
        )
    fix = (
        "pass a GBuffer from a rasterize call with the same width, height, spp, channels and "
        "dtype, or out=None for fresh buffers"
    )
    if (out.width, out.height, out.spp) != (width, height, spp):
        raise ValueError(
            f"out: holds a {out.width} x {out.height} spp {out.spp} frame, this call renders "
            f"{width} x {height} spp {spp}; {fix}"
        )
    have, want = set(out.channels), set(layout)
    if have != want:
        raise ValueError(
            f"out: holds channels {sorted(have)}, this call asks for {sorted(want)} "
            f"(missing from out: {sorted(want - have)}, extra in out: {sorted(have - want)}); {fix}"
        )
    for name in sorted(layout):
        shape, dt = layout[name]
        a = out.channels[name]
        if not isinstance(a, np.ndarray) or a.dtype != dt or a.shape != shape:
            got = f"{a.dtype} {a.shape}" if isinstance(a, np.ndarray) else type(a).__name__
            hint = f"dtype={dtype.name} " if isinstance(a, np.ndarray) and a.dtype != dt else ""
            raise ValueError(
                f"out[{name!r}]: is {got}, this call ({hint}with these meshes) writes "
                f"{dt} {shape}; {fix}"
            )
        if not (a.flags.c_contiguous and a.flags.writeable):
            raise ValueError(
                f"out[{name!r}]: must be a writeable C-contiguous array (got a read-only or "
                f"strided view); {fix}"
            )
    for a, b in itertools.combinations(sorted(layout), 2):
        if np.may_share_memory(out.channels[a], out.channels[b]):
            raise ValueError(
                f"out: channels {a!r} and {b!r} share memory, so writing one would "
                f"overwrite the other; {fix}"
            )


class _Scratch:
    """Work buffers: fresh each call, or kept in ``out._scratch`` so repeated frames reuse them."""

    def __init__(self, store: dict | None):
        self.store = store

    def get(self, key: str, shape, dtype, *, zero: bool = False) -> np.ndarray:
        shape = tuple(int(v) for v in shape)
        if self.store is None:
            return np.zeros(shape, dtype) if zero else np.empty(shape, dtype)
        a = self.store.get(key)
        if a is None or a.shape != shape or a.dtype != np.dtype(dtype):
            a = np.zeros(shape, dtype) if zero else np.empty(shape, dtype)
            self.store[key] = a
        elif zero:
            a.fill(0)
        return a

    def grow(self, key: str, size: int, dtype) -> np.ndarray:
        """A 1-D buffer of ``size`` items (a prefix of a kept one with room to spare)."""
        if self.store is None:
            return np.empty(size, dtype)
        a = self.store.get(key)
        if a is None or a.size < size or a.dtype != np.dtype(dtype):
            a = np.empty(size + size // 4 + 1024, dtype)
            self.store[key] = a
        return a[:size]


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
    out: GBuffer | None = None,
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
    out : GBuffer, optional
        A G-buffer from an earlier call with the same width, height, spp, channel set, dtype
        (and vertex-attribute widths): its arrays are overwritten in place, it is pointed at
        this frame (camera, matrices, timings) and returned, and the work buffers it keeps make
        repeated frames allocate (and page-fault) nothing. Results are bit-identical to
        ``out=None``. Arrays previously taken from ``out`` see the new frame; copy them first
        to keep them. Any mismatch is a ``ValueError`` naming what differs.

    Returns
    -------
    GBuffer
        ``gb[name]`` arrays of shape ``(n H, n W)`` or ``(n H, n W, C)`` (``coverage``: ``(H, W)``);
        ``out`` itself when given.
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
    if out is not None:
        _check_out(
            out, _layout(wanted, meshes, n, width, height, dtype), width, height, n * n, dtype
        )
    scratch = _Scratch(None if out is None else out._scratch)
    widths = attribute_widths(meshes)
    need = _memory.rasterize_bytes(
        width, height, n * n, wanted, attributes=widths, itemsize=dtype.itemsize, tile=tile
    )
    _memory.check_fits(width, height, n * n, need)
    nw, nh = n * width, n * height
    guard = min(_MAX_GUARD, 2.0 * _FIXED_LIMIT / (max(nw, nh) * 512.0) - 1.0)
    if guard < 1.5:
        raise ValueError(
            f"width/height/spp: the sample grid {nw} x {nh} is too large for 64-bit fixed point "
            "edge functions; keep n * max(width, height) below 1,000,000"
        )

    # ---- vertex stage ----------------------------------------------------------------------
    if len(meshes) == 1:
        positions, faces = meshes[0].positions, meshes[0].faces
    else:
        positions = np.concatenate([m.positions for m in meshes])
        offsets = np.cumsum([0] + [m.n_vertices for m in meshes])
        faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets[:-1], strict=True)])
    positions, faces = frozen(positions), frozen(faces)  # one kernel specialisation (see frozen)
    first_tri = np.cumsum([0] + [m.n_faces for m in meshes]).astype(np.int64)
    vp = camera.view_projection(width, height)
    n_verts = positions.shape[0]
    m_tris = faces.shape[0]
    shift = tile.bit_length() - 1
    tiles_x = -(-nw // tile)
    tiles_y = -(-nh // tile)
    n_tiles = tiles_x * tiles_y
    grid = K.Grid(width, height, n, nw, nh, tile, shift, tiles_x)
    setup = K.Setup(float(guard), int(cull_backfaces), max(1, -(-m_tris // _BIN_CHUNKS)))
    verts = K.Verts(
        scratch.get("clip", (n_verts, 4), np.float64),
        scratch.get("snapped", (n_verts, 2), np.int32),
        scratch.get("outcode", (n_verts,), np.uint8),
    )
    run(K.transform_vertices, positions, vp, grid, setup.guard, verts)
    timings: dict[str, float] = {"vertex": time.perf_counter() - t_start}

    # ---- triangle setup (with the first binning pass), clipping -----------------------------
    t0 = time.perf_counter()
    counts = scratch.get("counts", (_BIN_CHUNKS, n_tiles), np.int64, zero=True)
    tris = K.Tris(
        scratch.get("coords", (m_tris, 6), np.int32),
        scratch.get("bbox", (m_tris, 4), np.int32),
        scratch.get("status", (m_tris,), np.int8),
        scratch.get("qplane", (m_tris, 3), np.float64),
    )
    run(K.setup_triangles, verts, faces, grid, setup, tris, counts)
    todo = np.flatnonzero(tris.status == 2)
    if todo.size:
        max_out = max(1, todo.size * (K.MAX_POLY - 2))
        coords, bbox, parent, first = K.clip_triangles(
            verts.clip, faces, todo, grid, setup, max_out
        )
        pieces = K.Pieces(todo, first, coords, bbox, parent)
        K.bin_count_clipped(pieces, grid, setup.chunk, counts)
    else:  # nothing to clip: what clip_triangles returns for no triangles, without compiling it
        pieces = K.Pieces(
            todo,
            np.zeros(1, np.int64),
            np.empty((0, 6), np.int32),
            np.empty((0, 4), np.int32),
            np.empty(0, np.int64),
        )
    timings["setup"] = time.perf_counter() - t0

    # ---- binning: per-tile primitive lists in triangle order ---------------------------------
    t0 = time.perf_counter()
    # tile-major, chunk-minor: a tile's list is its chunks' lists in chunk (= triangle) order
    starts = np.concatenate([[0], np.cumsum(counts.T.ravel())])
    offsets = np.ascontiguousarray(starts[:-1].reshape(n_tiles, _BIN_CHUNKS).T)
    tile_first = np.ascontiguousarray(starts[::_BIN_CHUNKS])  # (n_tiles + 1,)
    n_prims = m_tris + pieces.coords.shape[0]
    lists = scratch.grow("lists", int(starts[-1]), np.int32 if n_prims < 2**31 else np.int64)
    run(K.bin_fill, tris, pieces, grid, setup, offsets, lists)
    bins = K.Bins(tile_first, lists)
    timings["bin"] = time.perf_counter() - t0

    # ---- visibility ------------------------------------------------------------------------
    t0 = time.perf_counter()
    depth_range = K.DepthRange(  # per-sample near/far clip on Q = 1/w
        (1.0 - _DEPTH_CLIP_SLACK) / camera.far, (1.0 + _DEPTH_CLIP_SLACK) / camera.near
    )
    if out is not None and "tri_id" in wanted:
        tri_id = out.channels["tri_id"]
    else:
        tri_id = scratch.get("tri_id", (nh, nw), np.int32)
    # depth straight from the visibility pass where it is the only interpolated channel of a
    # float32 G-buffer (else from the interpolation pass: one specialisation of this kernel)
    depth_here = np.empty((0, 0), dtype=np.float32)
    if (
        "depth" in wanted
        and dtype == np.float32
        and not _memory.needs_interpolation(wanted, attribute_names(meshes))
    ):
        depth_here = out.channels["depth"] if out is not None else np.empty((nh, nw), np.float32)
    run(K.raster_visibility, tris, pieces, bins, grid, depth_range, K.Visible(tri_id, depth_here))
    timings["visibility"] = time.perf_counter() - t0

    # ---- channels ----------------------------------------------------------------------------
    t0 = time.perf_counter()
    res: dict[str, np.ndarray] = {}
    dest = out.channels if out is not None else {}
    if "tri_id" in wanted:
        res["tri_id"] = tri_id
    depth_done = depth_here.shape[0] > 0
    if depth_done:
        res["depth"] = depth_here
    if "coverage_count" in wanted:
        cc = dest["coverage_count"] if "coverage_count" in dest else np.empty((nh, nw), np.int32)
        cc.fill(0)
        run(K.raster_count, tris, pieces, bins, grid, depth_range, cc)
        res["coverage_count"] = cc
    if "mesh_id" in wanted:
        mesh_id = dest["mesh_id"] if "mesh_id" in dest else np.empty((nh, nw), dtype=np.int32)
        run(K.mesh_ids, tri_id, frozen(first_tri), mesh_id)
        res["mesh_id"] = mesh_id
    if "coverage" in wanted:
        cov = dest["coverage"] if "coverage" in dest else np.empty((height, width), dtype=dtype)
        run(K.resolve_coverage, tri_id, n, cov)
        res["coverage"] = cov
    if out is None:  # fresh arrays, written in place all the same
        layout = _layout(wanted, meshes, n, width, height, dtype)
        dest = {k: np.empty(*layout[k]) for k in wanted - res.keys() - _NOT_INTERPOLATED}
        dest.update(res)  # (depth from the visibility pass)
    tw, th = texture_size if "lod" in wanted else (1, 1)
    scales = K.Scales(float(tw), float(th), 1 if dyadic_coord == "v" else 0, math.log2(line_period))
    interpolated_channels(
        wanted,
        dest,
        scratch,
        meshes=meshes,
        positions=positions,
        faces=faces,
        clip=verts.clip,
        qplane=tris.qplane,
        tri_id=tri_id,
        grid=grid,
        dtype=dtype,
        scales=scales,
        depth_done=depth_done,
    )
    if out is None:
        res.update(dest)
    else:
        for key, arr in res.items():
            if arr is not dest[key]:
                np.copyto(dest[key], arr)
    timings["channels"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    frame = dict(
        camera=camera,
        view_projection=vp,
        mesh_first_tri=first_tri,
        texture_size=texture_size if "lod" in wanted else None,
        line_period=float(line_period),
        timings=timings,
    )
    if out is not None:
        return out._refill(**frame)
    channels = {k: res[k] for k in sorted(res)}
    return GBuffer(channels=channels, width=width, height=height, spp=n * n, **frame)
