"""``rasterize``: meshes + camera -> GBuffer, computing exactly the channels asked for."""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence

import numpy as np

from . import _kernels as K
from .camera import Camera
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
_LOD_FLOOR = 2.0**-64
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


def _attribute_names(meshes: list[Mesh]) -> set[str]:
    names = set(meshes[0].attributes)
    for m in meshes[1:]:
        names &= set(m.attributes)
    return names


def valid_channels(meshes: Mesh | Sequence[Mesh] | None = None) -> list[str]:
    """Channel names ``rasterize`` accepts (built-ins plus the meshes' common vertex attributes)."""
    names = set(BUILTIN_CHANNELS)
    if meshes is not None:
        for a in _attribute_names(_meshes_of(meshes)):
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
    if n * n != spp:
        raise ValueError(
            f"spp: expected a square number of samples per pixel (1, 4, 9, 16, ...), got {spp}; "
            f"use {n * n} or {(n + 1) ** 2}"
        )
    return n


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


def _concat(meshes: list[Mesh], key: str, what: str) -> np.ndarray:
    arrays = []
    for m in meshes:
        a = m.attributes.get(key) if key not in ("uv", "normals") else getattr(m, key)
        if a is None:
            remedy = {
                "uv": "give the mesh uv, or project them (refnpr.scenes.project_uv(mesh, 'planar'|"
                "'box'|'spherical'|'cylindrical'))",
                "normals": "give the mesh vertex normals (e.g. trimesh's vertex_normals)",
            }.get(key, f"add attributes={{{key!r}: ...}} to the mesh")
            raise ValueError(
                f"channels: {what} requested but mesh {m.name!r} has no {key}; {remedy}"
            )
        arrays.append(a.reshape(a.shape[0], -1))
    ncols = {a.shape[1] for a in arrays}
    if len(ncols) != 1:
        raise ValueError(
            f"channels: attribute {key!r} has different widths across meshes: {sorted(ncols)}"
        )
    return np.ascontiguousarray(np.concatenate(arrays), dtype=np.float64)


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
    if cull_backfaces not in (True, False):
        raise TypeError(f"cull_backfaces: expected a bool, got {cull_backfaces!r}")
    wanted = _parse_channels(channels, _attribute_names(meshes))
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
    tri_id = np.empty((nh, nw), dtype=np.int32)
    K.raster_visibility(
        coords,
        bbox,
        sub,
        sub_bbox,
        sub_parent,
        qplane,
        (1.0 - _DEPTH_CLIP_SLACK) / camera.far,
        (1.0 + _DEPTH_CLIP_SLACK) / camera.near,
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
        K.raster_count(coords, bbox, sub, sub_bbox, tile_first, lists, n, nw, nh, tile, tiles_x, cc)
        out["coverage_count"] = cc
    if "mesh_id" in wanted:
        mesh_id = np.searchsorted(first_tri, tri_id, side="right").astype(np.int32) - 1
        mesh_id[tri_id < 0] = -1
        out["mesh_id"] = mesh_id
    if "coverage" in wanted:
        cov = np.empty((height, width), dtype=dtype)
        K.resolve_coverage(tri_id, n, cov)
        out["coverage"] = cov
    if wanted - {"tri_id", "coverage_count", "mesh_id", "coverage", "depth"}:
        # exact perspective-correct barycentric planes, only for triangles that own a sample
        mark = np.zeros(m_tris, dtype=np.uint8)
        K.mark_visible(tri_id, mark)
        lam = np.empty((m_tris, 3, 3), dtype=np.float64)
        K.lam_for_marked(clip, faces, mark, n, width, height, lam)
    if "depth" in wanted or "ndc_z" in wanted:
        depth = np.empty((nh, nw), dtype=np.float64 if "ndc_z" in wanted else dtype)
        K.interp_depth(tri_id, qplane, depth)
        if "ndc_z" in wanted:
            zc = np.empty((nh, nw, 1), dtype=np.float64)
            K.interp_attr(tri_id, lam, faces, np.ascontiguousarray(clip[:, 2:3]), 0.0, zc)
            with np.errstate(invalid="ignore"):
                ndc = np.where(tri_id >= 0, zc[..., 0] / np.where(tri_id >= 0, depth, 1.0), 1.0)
            out["ndc_z"] = ndc.astype(dtype)
        if "depth" in wanted:
            out["depth"] = depth.astype(dtype, copy=False)
    if "bary" in wanted:
        bary = np.empty((nh, nw, 3), dtype=dtype)
        K.interp_bary(tri_id, lam, bary)
        out["bary"] = bary
    if "normal" in wanted:
        normals = _concat(meshes, "normals", "normal")
        nrm = np.empty((nh, nw, 3), dtype=dtype)
        K.interp_normal(tri_id, lam, faces, normals, nrm)
        out["normal"] = nrm

    def attribute(values_key: str, base: str, want: set[str], dest: dict) -> None:
        """Interpolate one per-vertex quantity; derivatives only if one of them is wanted."""
        d_names = (f"d{base}_dx", f"d{base}_dy")
        need_d = any(d in want for d in d_names)
        if not need_d and base not in want:
            return
        values = positions if values_key == "position" else _concat(meshes, values_key, base)
        vals = np.empty((nh, nw, values.shape[1]), dtype=dtype)
        squeeze = (
            values_key not in ("uv", "position") and meshes[0].attributes[values_key].ndim == 1
        )
        results = {base: vals}
        if need_d:
            dx, dy = np.empty_like(vals), np.empty_like(vals)
            K.interp_attr_deriv(tri_id, lam, faces, values, n, vals, dx, dy)
            results[d_names[0]], results[d_names[1]] = dx, dy
        else:
            K.interp_attr(tri_id, lam, faces, values, 0.0, vals)
        for key, arr in results.items():
            if key in want:
                dest[key] = arr[..., 0] if squeeze else arr

    attribute("position", "position", wanted, out)
    for a in _attribute_names(meshes):
        attribute(a, a, wanted, out)
    if {"lod", "dyadic_scale"} & wanted:
        internal: dict[str, np.ndarray] = {}
        attribute("uv", "uv", wanted | {"duv_dx", "duv_dy"}, internal)
        for key in ("uv", "duv_dx", "duv_dy"):
            if key in wanted:
                out[key] = internal[key]
        duv_dx = internal["duv_dx"].astype(np.float64)
        duv_dy = internal["duv_dy"].astype(np.float64)
        empty = tri_id < 0
        if "lod" in wanted:
            tw, th = texture_size
            # OpenGL 4.x sec. 8.14: rho = max(|d(u,v)/dx|, |d(u,v)/dy|) in texels, lambda = log2 rho
            rho = np.maximum(
                np.hypot(duv_dx[..., 0] * tw, duv_dx[..., 1] * th),
                np.hypot(duv_dy[..., 0] * tw, duv_dy[..., 1] * th),
            )
            lod = np.log2(np.maximum(rho, _LOD_FLOOR))
            lod[empty] = 0.0
            out["lod"] = lod.astype(dtype)
        if "dyadic_scale" in wanted:
            k = 1 if dyadic_coord == "v" else 0
            grad = np.hypot(duv_dx[..., k], duv_dy[..., k])
            # Veryovka eq. 5: d = 1/|grad v| (pixels between iso-lines v and v + 1), s = log2(d / w)
            s = -np.log2(np.maximum(grad, _LOD_FLOOR)) - math.log2(line_period)
            s = np.clip(s, -64.0, 64.0)  # finite even where v is constant on screen
            s[empty] = 0.0
            out["dyadic_scale"] = s.astype(dtype)
    else:
        attribute("uv", "uv", wanted, out)
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
