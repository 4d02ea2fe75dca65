"""Per-sample channels interpolated from the visible triangle of each sample.

Everything here reads ``tri_id`` from the visibility pass and the exact float64 vertex data: each
channel family is computed only when asked for, and all per-vertex quantities go through one
fused kernel so every sample gathers its triangle's data once.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .._memory import INTERPOLATED, needs_interpolation
from . import _kernels as K
from .mesh import Mesh

__all__ = [
    "interpolated_channels",
    "screen_scales",
    "attribute_names",
    "check_vertex_data",
    "INTERPOLATED",
]

#: Smallest footprint / gradient ``lod`` and ``dyadic_scale`` take (finite logarithms).
LOD_FLOOR = 2.0**-64


def attribute_names(meshes: Sequence[Mesh]) -> set[str]:
    """Vertex attribute names every mesh has (the ones that can be rasterized)."""
    names = set(meshes[0].attributes)
    for m in meshes[1:]:
        names &= set(m.attributes)
    return names


def check_vertex_data(meshes: Sequence[Mesh], wanted: set[str]) -> None:
    """Raise the missing-uv/normals error before any rasterization work is done."""
    if {"uv", "duv_dx", "duv_dy", "lod", "dyadic_scale"} & wanted:
        for m in meshes:
            if m.uv is None:
                _concat([m], "uv", "uv")
    if "normal" in wanted:
        for m in meshes:
            if m.normals is None:
                _concat([m], "normals", "normal")


def frozen(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a``: kernel inputs are always passed read-only, so numba compiles
    one specialisation per kernel instead of one per writeable flag (a mesh's own arrays are
    read-only, concatenations and copies are not; every variant costs a cold-start compile)."""
    v = a.view()
    v.flags.writeable = False
    return v


_NONE = frozen(np.zeros((1, 0)))


def _concat(meshes: Sequence[Mesh], key: str, what: str) -> np.ndarray:
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
    return frozen(np.ascontiguousarray(np.concatenate(arrays), dtype=np.float64))


def _table(parts: list[tuple[str, np.ndarray]], n_rows: int) -> tuple[np.ndarray, list]:
    """Concatenate (name, (N, C)) columns; returns the table and (name, start, stop) slices."""
    if not parts:
        return frozen(np.zeros((n_rows, 0))), []
    slices, start = [], 0
    for name, arr in parts:
        slices.append((name, start, start + arr.shape[1]))
        start += arr.shape[1]
    table = parts[0][1] if len(parts) == 1 else np.concatenate([a for _, a in parts], axis=1)
    return frozen(np.ascontiguousarray(table, dtype=np.float64)), slices


def _column(arr: np.ndarray, start: int, stop: int, squeeze: bool) -> np.ndarray:
    if squeeze:
        return np.ascontiguousarray(arr[..., start])
    if start == 0 and stop == arr.shape[-1]:
        return arr
    return np.ascontiguousarray(arr[..., start:stop])


def interpolated_channels(
    wanted: set[str],
    *,
    meshes: Sequence[Mesh],
    positions: np.ndarray,
    faces: np.ndarray,
    clip: np.ndarray,
    qplane: np.ndarray,
    tri_id: np.ndarray,
    n: int,
    width: int,
    height: int,
    dtype: np.dtype,
    texture_size: tuple[int, int] | None,
    line_period: float,
    dyadic_coord: str,
) -> dict[str, np.ndarray]:
    """depth, ndc_z, bary, position, normal, uv and their derivatives, lod, dyadic_scale and
    vertex attributes, for the samples of ``tri_id`` (nH, nW); only those in ``wanted``."""
    nh, nw = tri_id.shape
    out: dict[str, np.ndarray] = {}
    attrs = attribute_names(meshes)
    need_depth = "depth" in wanted or "ndc_z" in wanted
    depth_dtype = np.float64 if "ndc_z" in wanted else dtype
    if not needs_interpolation(wanted, attrs):
        if need_depth:  # nothing to interpolate: depth from the depth planes alone
            depth = np.empty((nh, nw), dtype=depth_dtype)
            K.interp_depth(tri_id, qplane, depth)
            out["depth"] = depth.astype(dtype, copy=False)
        return out

    # exact perspective-correct barycentric planes, only for triangles that own a sample
    m_tris = faces.shape[0]
    mark = np.zeros(m_tris, dtype=np.uint8)
    K.mark_visible(tri_id, mark)
    lam = np.empty((m_tris, 3, 3), dtype=np.float64)
    K.lam_for_marked(clip, faces, mark, n, width, height, lam)
    if "bary" in wanted:
        bary = np.empty((nh, nw, 3), dtype=dtype)
        K.interp_bary(tri_id, lam, bary)
        out["bary"] = bary

    # which quantities, with or without derivatives
    need_uv_d = bool({"duv_dx", "duv_dy", "lod", "dyadic_scale"} & wanted)
    d_parts: list[tuple[str, np.ndarray]] = []
    v_parts: list[tuple[str, np.ndarray]] = []
    squeeze: set[str] = set()

    def add(name: str, values) -> None:
        if {f"d{name}_dx", f"d{name}_dy"} & wanted or (name == "uv" and need_uv_d):
            d_parts.append((name, values()))
        elif name in wanted:
            v_parts.append((name, values()))

    add("uv", lambda: _concat(meshes, "uv", "uv"))
    add("position", lambda: positions)
    for a in sorted(attrs):
        add(a, lambda a=a: _concat(meshes, a, a))
        if meshes[0].attributes[a].ndim == 1:
            squeeze.add(a)
    if "ndc_z" in wanted:
        v_parts.append(("z_clip", frozen(np.ascontiguousarray(clip[:, 2:3]))))
    dtab, d_slices = _table(d_parts, positions.shape[0])
    vtab, v_slices = _table(v_parts, positions.shape[0])
    ntab = _concat(meshes, "normals", "normal") if "normal" in wanted else _NONE

    dout = np.empty((nh, nw, dtab.shape[1]), dtype=dtype)
    dxout = np.empty_like(dout)
    dyout = np.empty_like(dout)
    vout = np.empty((nh, nw, vtab.shape[1]), dtype=np.float64 if "ndc_z" in wanted else dtype)
    nout = np.empty((nh, nw, ntab.shape[1]), dtype=dtype)
    wout = np.empty((nh, nw, 1 if need_depth else 0), dtype=depth_dtype)
    K.interp_fused(tri_id, lam, faces, dtab, vtab, ntab, n, dout, dxout, dyout, vout, nout, wout)
    if need_depth:
        depth = wout.reshape(nh, nw)  # w = 1 / Q, +inf where empty
        if "depth" in wanted:
            out["depth"] = depth.astype(dtype, copy=False)

    internal: dict[str, np.ndarray] = {}
    for name, a, b in d_slices:
        sq = name in squeeze
        internal[name] = _column(dout, a, b, sq)
        internal[f"d{name}_dx"] = _column(dxout, a, b, sq)
        internal[f"d{name}_dy"] = _column(dyout, a, b, sq)
    for name, a, b in v_slices:
        internal[name] = _column(vout, a, b, name in squeeze)
    if "normal" in wanted:
        out["normal"] = nout
    if "ndc_z" in wanted:
        covered = tri_id >= 0
        z = internal.pop("z_clip")[..., 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            out["ndc_z"] = np.where(covered, z / np.where(covered, depth, 1.0), 1.0).astype(dtype)
    for key, arr in internal.items():
        if key in wanted:
            out[key] = arr.astype(dtype, copy=False)

    if need_uv_d and {"lod", "dyadic_scale"} & wanted:
        out.update(
            screen_scales(
                wanted,
                internal["duv_dx"],
                internal["duv_dy"],
                tri_id,
                dtype=dtype,
                texture_size=texture_size,
                line_period=line_period,
                dyadic_coord=dyadic_coord,
            )
        )
    return out


def screen_scales(
    wanted: set[str],
    duv_dx: np.ndarray,
    duv_dy: np.ndarray,
    tri_id: np.ndarray,
    *,
    dtype: np.dtype,
    texture_size: tuple[int, int] | None,
    line_period: float,
    dyadic_coord: str,
) -> dict[str, np.ndarray]:
    """``lod`` and ``dyadic_scale`` (those in ``wanted``), (nH, nW) of ``dtype``, from the
    uv derivatives ``duv_dx, duv_dy (nH, nW, 2)`` as stored (``dtype``); 0 where empty.

    The numpy form, for sets with ``ndc_z`` and as the tests' oracle of the kernel
    ``_kernels.screen_scales`` the other sets take: the same operations, but numpy's ``log2``
    may be a SIMD one (AVX-512) within an ulp of libm's, so the two can differ by an ulp in
    float64 (not, in practice, after rounding to float32)."""
    out: dict[str, np.ndarray] = {}
    duv_dx = duv_dx.astype(np.float64)
    duv_dy = duv_dy.astype(np.float64)
    empty = tri_id < 0
    if "lod" in wanted:
        tw, th = texture_size
        # OpenGL 4.x sec. 8.14: rho = max(|d(u,v)/dx|, |d(u,v)/dy|) in texels, lambda = log2 rho
        rho = np.maximum(
            np.hypot(duv_dx[..., 0] * tw, duv_dx[..., 1] * th),
            np.hypot(duv_dy[..., 0] * tw, duv_dy[..., 1] * th),
        )
        lod = np.log2(np.maximum(rho, LOD_FLOOR))
        lod[empty] = 0.0
        out["lod"] = lod.astype(dtype)
    if "dyadic_scale" in wanted:
        k = 1 if dyadic_coord == "v" else 0
        grad = np.hypot(duv_dx[..., k], duv_dy[..., k])
        # Veryovka eq. 5: d = 1/|grad v| (pixels between iso-lines v and v + 1), s = log2(d / w)
        s = -np.log2(np.maximum(grad, LOD_FLOOR)) - math.log2(line_period)
        s = np.clip(s, -64.0, 64.0)  # finite even where v is constant on screen
        s[empty] = 0.0
        out["dyadic_scale"] = s.astype(dtype)
    return out
