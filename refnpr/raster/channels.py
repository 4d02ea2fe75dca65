"""Per-sample channels interpolated from the visible triangle of each sample.

Everything here reads ``tri_id`` from the visibility pass and the exact float64 vertex data: each
channel family is computed only when asked for and written straight into its array; the first
family with derivatives, the first without, the normals and the depth go through one fused
kernel, so every sample gathers its triangle's data once.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._jit import call_banded as run
from .._memory import INTERPOLATED, needs_interpolation
from . import _kernels as K
from .mesh import Mesh

__all__ = [
    "interpolated_channels",
    "attribute_names",
    "check_vertex_data",
    "INTERPOLATED",
]

#: Channels computed from the uv derivatives after the interpolation (``_kernels.screen_scales``).
SCALES = frozenset({"lod", "dyadic_scale"})


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
    """A read-only view of ``a``: kernel inputs are always read-only, so numba compiles one
    specialisation per kernel instead of one per writeable flag (each a cold-start compile)."""
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
                "uv": "give the mesh uv, or project them: in a TOML scene, uv_projection = "
                "'planar'|'box'|'spherical'|'cylindrical' in the object's [[object]] table (a "
                "glTF file without TEXCOORD_0: [[object]] path = 'model.glb' with "
                "uv_projection, docs/scenes.md); in Python, refnpr.scenes.project_uv(mesh, "
                "'box')",
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


def interpolated_channels(
    wanted: set[str],
    dest: dict[str, np.ndarray],
    scratch,
    *,
    meshes: Sequence[Mesh],
    positions: np.ndarray,
    faces: np.ndarray,
    clip: np.ndarray,
    qplane: np.ndarray,
    tri_id: np.ndarray,
    grid: K.Grid,
    dtype: np.dtype,
    scales: K.Scales,
    depth_done: bool = False,
) -> None:
    """The interpolated channels of ``wanted`` for the samples of ``tri_id`` (nH, nW), written
    into the arrays of ``dest`` (those of ``out``, or fresh ones). Families after the first with
    derivatives and the first without get a pass each (each column is computed alone: the same
    values as in one table); ``lod`` and ``dyadic_scale`` come from the uv derivatives as
    stored. ``scratch.get(key, shape, dtype)`` gives work buffers (uv derivatives nobody asked
    for, the per-triangle planes). ``depth_done``: the visibility pass wrote ``depth``."""
    nh, nw = tri_id.shape
    attrs = attribute_names(meshes)
    if not needs_interpolation(wanted, attrs):
        if "depth" in wanted and not depth_done:  # nothing to interpolate: the depth planes
            run(K.interp_depth, tri_id, qplane, dest["depth"])
        return
    d_parts, v_parts = [], []
    for name in ["uv", "position", *sorted(attrs)]:
        if {f"d{name}_dx", f"d{name}_dy"} & wanted or (name == "uv" and SCALES & wanted):
            d_parts.append(name)
        elif name in wanted:
            v_parts.append(name)

    def values(name):
        if name == "position":
            return frozen(np.ascontiguousarray(positions, dtype=np.float64))
        return _concat(meshes, name, name)

    def target(name, key, comps):
        if name in wanted:
            return dest[name].reshape(nh, nw, comps)  # a view: dest is C-contiguous
        return scratch.get(key, (nh, nw, comps), dtype)

    # exact perspective-correct barycentric planes, only for triangles that own a sample
    m_tris = faces.shape[0]
    mark = scratch.get("mark", (m_tris,), np.uint8, zero=True)
    K.mark_visible(tri_id, mark)
    lam = scratch.get("lam", (m_tris, 3, 3), np.float64)
    run(K.lam_for_marked, clip, faces, mark, grid, lam)
    if "bary" in wanted:
        run(K.interp_bary, tri_id, lam, dest["bary"])
    if "ndc_z" in wanted:
        z = frozen(np.ascontiguousarray(clip[:, 2]))
        run(K.interp_ndc_z, tri_id, lam, faces, z, dest["ndc_z"])
    zero = np.empty((nh, nw, 0), dtype)

    def d_family(name):
        tab = values(name)
        c = tab.shape[1]
        outs = (target(name, f"dval:{name}", c),)
        return tab, outs + tuple(target(f"d{name}_d{x}", f"d{x}:{name}", c) for x in "xy")

    def v_family(name):
        tab = values(name)
        return tab, target(name, f"vval:{name}", tab.shape[1])

    dtab = vtab = ntab = _NONE
    dout = dxout = dyout = vout = nout = wout = zero
    if d_parts:
        dtab, (dout, dxout, dyout) = d_family(d_parts[0])
    if v_parts:
        vtab, vout = v_family(v_parts[0])
    if "normal" in wanted:
        ntab = _concat(meshes, "normals", "normal")
        nout = dest["normal"].reshape(nh, nw, ntab.shape[1])
    if "depth" in wanted:
        wout = dest["depth"].reshape(nh, nw, 1)
    tables = K.Tables(dtab, vtab, ntab)
    outs = K.Outs(dout, dxout, dyout, vout, nout, wout)
    n = grid.n
    if dtab.shape[1] == 2 and vtab.shape[1] == 0 and ntab.shape[1] == 3 and wout.shape[2] == 1:
        # the full G-buffer (uv + derivatives, normal, depth): the specialised kernel
        run(K.interp_fused_full, tri_id, lam, faces, n, tables, outs)
    elif dtab.shape[1] + vtab.shape[1] + ntab.shape[1] + wout.shape[2] > 0:
        run(K.interp_fused, tri_id, lam, faces, n, tables, outs)
    for name in d_parts[1:]:
        tab, (d, dx, dy) = d_family(name)
        outs = K.Outs(d, dx, dy, zero, zero, zero)
        run(K.interp_fused, tri_id, lam, faces, n, K.Tables(tab, _NONE, _NONE), outs)
    for name in v_parts[1:]:
        tab, v = v_family(name)
        outs = K.Outs(zero, zero, zero, v, zero, zero)
        run(K.interp_fused, tri_id, lam, faces, n, K.Tables(_NONE, tab, _NONE), outs)
    if SCALES & wanted:  # from the uv derivatives as stored (d_parts[0] is uv)
        lod = dest["lod"] if "lod" in wanted else np.empty((nh, 0), dtype)
        dyadic = dest["dyadic_scale"] if "dyadic_scale" in wanted else np.empty((nh, 0), dtype)
        run(K.screen_scales, tri_id, dxout, dyout, scales, lod, dyadic)
