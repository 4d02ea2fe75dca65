"""The frame record: everything a style's kernels read of one frame, built and validated once.

A :class:`Frame` holds the G-buffer grids on the sample grid (channels the frame did not
rasterize are 1-element stand-ins of the same dtype, never read), the eye, the lights
(:class:`refnpr.device.lights.Lights`) and the materials per object (:class:`Materials`). The
style kernels take it as one argument beside the style's own record.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from refnpr._jit import frozen
from refnpr.device.lights import Lights, lights_record

__all__ = ["Frame", "Materials", "frame_record", "materials_record"]


class Materials(NamedTuple):
    """Material properties per scene object (O objects), float64.

    ambient : (O, 3) m_a l_a (the ambient term of Veryovka eq. 1, times the scene's ambient)
    diffuse, specular : (O, 3) m_d, m_s
    shininess : (O,)
    uv_scale : (O, 2)
    """

    ambient: np.ndarray
    diffuse: np.ndarray
    specular: np.ndarray
    shininess: np.ndarray
    uv_scale: np.ndarray


class Frame(NamedTuple):
    """One frame as the style kernels read it.

    cover : (nH, nW) int, covered where >= 0 (``tri_id``, else ``mesh_id``)
    mesh_id : (nH, nW) int, the object of each sample (-1 where empty)
    normal, position, dposition_dx, dposition_dy : (nH, nW, 3) float
    depth, dyadic_scale : (nH, nW) float
    uv, duv_dx, duv_dy : (nH, nW, 2) float
    eye : (3,) float64
    lights : Lights
    materials : Materials
    """

    cover: np.ndarray
    mesh_id: np.ndarray
    normal: np.ndarray
    position: np.ndarray
    depth: np.ndarray
    uv: np.ndarray
    duv_dx: np.ndarray
    duv_dy: np.ndarray
    dyadic_scale: np.ndarray
    dposition_dx: np.ndarray
    dposition_dy: np.ndarray
    eye: np.ndarray
    lights: Lights
    materials: Materials


#: Grid channels of a Frame and their trailing shape.
_GRIDS = {
    "normal": (3,),
    "position": (3,),
    "depth": (),
    "uv": (2,),
    "duv_dx": (2,),
    "duv_dy": (2,),
    "dyadic_scale": (),
    "dposition_dx": (3,),
    "dposition_dy": (3,),
}


def _grid(name: str, arr: Any, shape: tuple[int, ...], kind: str) -> np.ndarray:
    """Channel ``name`` on the sample grid, C-contiguous: int32/int64 (``kind`` "i") or
    float32/float64 ("f") kept, other dtypes converted to the 64-bit one."""
    arr = np.asarray(arr)
    if arr.shape != shape:
        raise ValueError(
            f"G-buffer channel {name!r}: expected shape {shape} (the sample grid), got "
            f"{arr.shape}; rasterize every channel at the same size and spp"
        )
    if arr.dtype.kind != kind or arr.dtype.itemsize not in (4, 8):
        arr = arr.astype(np.int64 if kind == "i" else np.float64)
    return np.ascontiguousarray(arr)


def _table(scene: Any, attr: str, width: int) -> np.ndarray:
    rows = [np.asarray(getattr(o.material, attr), dtype=np.float64) for o in scene.objects]
    arr = np.array(rows, dtype=np.float64).reshape(len(scene.objects), -1)
    if arr.shape[1] != width:
        raise ValueError(
            f"material {attr}: expected {width} value(s) per object, got shape {arr.shape}"
        )
    return np.ascontiguousarray(arr)


def materials_record(scene: Any) -> Materials:
    """:class:`Materials` of ``scene``'s objects."""
    return Materials(
        np.ascontiguousarray(_table(scene, "ambient", 3) * np.asarray(scene.ambient, float)),
        _table(scene, "diffuse", 3),
        _table(scene, "specular", 3),
        _table(scene, "shininess", 1).reshape(-1),
        _table(scene, "uv_scale", 2),
    )


def frame_record(ctx: Any, channels: tuple[str, ...] = ()) -> Frame:
    """The :class:`Frame` of a shading context (``ShadeContext``: ``gb`` and ``scene``).

    ``channels`` are the grid channels the kernels will read (each must be in the G-buffer,
    on the sample grid); the others are stand-ins. ``mesh_id`` must name objects of the scene.
    """
    gb, scene = ctx.gb, ctx.scene
    mesh_id = np.asarray(gb["mesh_id"])
    shape = mesh_id.shape
    mesh_id = _grid("mesh_id", mesh_id, shape, "i")
    cover = _grid("tri_id", gb["tri_id"], shape, "i") if "tri_id" in gb else mesh_id
    objs = scene.objects
    if mesh_id.size and int(mesh_id.max()) >= len(objs):
        raise ValueError(
            f"G-buffer channel 'mesh_id': got object index {int(mesh_id.max())} but the scene has "
            f"{len(objs)} objects; shade the G-buffer with the scene it was rasterized from"
        )
    grids = {}
    for name, tail in _GRIDS.items():
        if name in channels:
            grids[name] = _grid(name, gb[name], shape + tail, "f")
        else:
            grids[name] = _STAND_IN[len(tail) and tail[0]]
    frame = Frame(
        cover=cover,
        mesh_id=mesh_id,
        eye=np.ascontiguousarray(np.asarray(scene.camera.eye, dtype=np.float64)),
        lights=lights_record(scene.lights),
        materials=materials_record(scene),
        **grids,
    )
    return frozen(frame)  # kernels only read it: one compiled kernel, whatever the G-buffer


#: Channels not rasterized for a frame: float32 stand-ins by trailing size (0: a scalar grid).
_STAND_IN = {
    0: np.zeros((1, 1), dtype=np.float32),
    2: np.zeros((1, 1, 2), dtype=np.float32),
    3: np.zeros((1, 1, 3), dtype=np.float32),
}
