"""The ``halftone`` style's per-sample shading in one numba pass per object.

:func:`shade_object_into` validates what :mod:`._kernels` reads and shades one object's samples:
lighting and the target intensity, the screen lookup (isotropic or anisotropic), the
threshold (sec. 3.1 mux form / sec. 3.2 ramp, per level with tone LUTs) and ink/paper
compositing, the same arithmetic as the numpy path of :class:`~.style.HalftoneStyle` (which
stays the oracle of the tests; ``log2`` and ``pow`` may differ from numpy's SIMD versions by an
ulp).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _kernels as K

__all__ = [
    "LIGHT_CODES",
    "SHOW_CODES",
    "THRESHOLD_CODES",
    "shade_object_into",
    "prepare_into",
]

SHOW_CODES = {
    "color": K.SHOW_COLOR,
    "screen": K.SHOW_SCREEN,
    "normals": K.SHOW_NORMALS,
    "intensity": K.SHOW_INTENSITY,
}
LIGHT_CODES = {"directional": K.LIGHT_DIRECTIONAL, "point": K.LIGHT_POINT}
THRESHOLD_CODES = {"binary": K.THRESHOLD_BINARY, "smooth": K.THRESHOLD_SMOOTH}
_DUMMY3 = np.zeros((1, 1, 3), dtype=np.float32)


def _grid(name: str, arr: Any, shape: tuple[int, ...]) -> np.ndarray:
    a = np.asarray(arr)
    if a.shape != shape:
        raise ValueError(
            f"G-buffer channel {name!r}: expected shape {shape} (the sample grid), got "
            f"{a.shape}; rasterize every channel at the same size and spp"
        )
    if a.dtype.kind != "f":
        raise TypeError(f"G-buffer channel {name!r}: expected a float array, got {a.dtype}")
    return np.ascontiguousarray(a)


def _vec(name: str, value: Any, n: int) -> np.ndarray:
    a = np.ascontiguousarray(value, dtype=np.float64)
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected {n} finite numbers, got {value!r}")
    return a


def _packed(pyramid: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    texels, offsets, shapes = pyramid.packed()
    return texels, offsets, shapes


def shade_object_into(
    out: np.ndarray,
    raw: np.ndarray | None,
    *,
    obj: int,
    mesh_id: np.ndarray,
    mask: np.ndarray,
    channels: dict[str, np.ndarray],
    scale: Any,
    screen: Any,
    luts: np.ndarray | None,
    per_level: bool,
    indication: np.ndarray | None,
    indication_scale: Any,
    ambient: Any,
    diffuse: Any,
    specular_color: Any,
    shininess: float,
    specular: bool,
    lights: list[tuple[int, np.ndarray, np.ndarray]],
    eye: Any,
    anisotropy: int,
    lod_offset: float,
    threshold: str,
    c: float,
    centred: bool,
    show: str,
    ink: Any,
    paper: Any,
) -> None:
    """Shade the samples ``mesh_id == obj`` of the sample grid (nH, nW).

    Parameters
    ----------
    out : (nH, nW, 4) float32, C-contiguous
        RGBA written at the object's samples (``show == "color"``; alpha 1 where ``mask``).
    raw : (nH, nW, 3) float64 or None
        The raw value (gray) or the normal map's RGB at the object's samples (other ``show``).
    mesh_id : (nH, nW) int; mask : (nH, nW) bool
    channels : dict
        G-buffer channels on the grid: ``normal`` (nH, nW, 3), ``uv``, ``duv_dx``, ``duv_dy``
        (nH, nW, 2); ``position`` (nH, nW, 3) with ``specular`` or point lights;
        ``dposition_dx``, ``dposition_dy`` (nH, nW, 3) when the screen has a normal map.
    scale : (2,) uv scale; screen : ``screens.Screen``; luts : (L, B) float64 tone LUTs or None
    per_level : bool
        Threshold the two level samples separately (forced on by ``luts``).
    indication : (rows, cols) float64 in [-1, 1] or None; indication_scale : (2,)
    ambient, diffuse, specular_color : (3,) m_a l_a, m_d, m_s; shininess : float
    lights : list of (``LIGHT_CODES`` value, (3,) unit direction or position, (3,) colour)
    eye : (3,); anisotropy : int in [1, 16]; lod_offset : float
    threshold : {"binary", "smooth"}; c : float > 0; centred : bool
    show : {"color", "screen", "normals", "intensity"}; ink, paper : (3,)
    """
    if threshold not in THRESHOLD_CODES:
        raise ValueError(f"threshold: expected one of {list(THRESHOLD_CODES)}, got {threshold!r}")
    if show not in SHOW_CODES:
        raise ValueError(f"show: expected one of {list(SHOW_CODES)}, got {show!r}")
    if not (isinstance(c, (int, float)) and c > 0 and np.isfinite(c)):
        raise ValueError(f"c: expected a finite number > 0, got {c!r}")
    anisotropy = int(anisotropy)
    if not 1 <= anisotropy <= 16:
        raise ValueError(f"anisotropy: expected an int in [1, 16], got {anisotropy!r}")
    shape = tuple(np.shape(mesh_id))
    if len(shape) != 2 or np.shape(mask) != shape:
        raise ValueError(
            f"mesh_id, mask: expected the same (nH, nW) shape, got {shape} and {np.shape(mask)}"
        )
    if not (
        isinstance(out, np.ndarray)
        and out.shape == shape + (4,)
        and out.dtype == np.float32
        and out.flags.c_contiguous
    ):
        raise ValueError(f"out: expected a C-contiguous {shape + (4,)} float32 array")
    if show != "color" and not (
        isinstance(raw, np.ndarray) and raw.shape == shape + (3,) and raw.dtype == np.float64
    ):
        raise ValueError(f"raw: expected a {shape + (3,)} float64 array for show={show!r}")
    if raw is None:
        raw = np.zeros((1, 1, 3))
    has_normals = screen.normals is not None
    light_vecs = [np.asarray(v, dtype=np.float64) for _, v, _ in lights]
    need_pos = specular or any(kind == K.LIGHT_POINT for kind, _, _ in lights)
    normal = _grid("normal", channels["normal"], shape + (3,))
    uv = _grid("uv", channels["uv"], shape + (2,))
    dx = _grid("duv_dx", channels["duv_dx"], shape + (2,))
    dy = _grid("duv_dy", channels["duv_dy"], shape + (2,))
    position = _grid("position", channels["position"], shape + (3,)) if need_pos else _DUMMY3
    if has_normals and show in ("color", "intensity"):  # the tangent frame of sec. 5.2
        dp_dx = _grid("dposition_dx", channels["dposition_dx"], shape + (3,))
        dp_dy = _grid("dposition_dy", channels["dposition_dy"], shape + (3,))
    else:
        dp_dx = dp_dy = _DUMMY3
    texels, offsets, shapes = _packed(screen.pyramid)
    if has_normals:
        ntexels, noffsets, nshapes = _packed(screen.normals)
        if ntexels.shape[1] != 3:
            raise ValueError(f"screen.normals: expected 3 channels, got {ntexels.shape[1]}")
    else:
        ntexels, noffsets, nshapes = np.zeros((1, 3), np.float32), offsets[:1], shapes[:1]
    if luts is None:
        lut_arr, lut_x = np.zeros((1, 2)), np.linspace(0.0, 1.0, 2)
    else:
        lut_arr = np.ascontiguousarray(luts, dtype=np.float64)
        if lut_arr.ndim != 2 or lut_arr.shape[0] != offsets.shape[0] or lut_arr.shape[1] < 2:
            raise ValueError(
                f"luts: expected ({offsets.shape[0]}, B >= 2) tone LUTs, got {lut_arr.shape}"
            )
        lut_x = np.linspace(0.0, 1.0, lut_arr.shape[1])
    imap = np.zeros((1, 1)) if indication is None else np.ascontiguousarray(indication, np.float64)
    if imap.ndim != 2:
        raise ValueError(f"indication: expected a (rows, cols) map, got shape {imap.shape}")
    kinds = np.array([k for k, _, _ in lights], dtype=np.int64)
    if np.any((kinds != K.LIGHT_DIRECTIONAL) & (kinds != K.LIGHT_POINT)):
        raise ValueError(f"lights: unknown light kind codes {kinds.tolist()}")
    light_vec = np.array(light_vecs, dtype=np.float64).reshape(-1, 3)
    light_color = np.array([np.asarray(col, np.float64) for _, _, col in lights]).reshape(-1, 3)
    direction = screen.direction
    kernel = K.shade_object_for(SHOW_CODES[show], has_normals)
    kernel(
        int(obj),
        np.ascontiguousarray(mesh_id),
        np.ascontiguousarray(mask),
        normal,
        uv,
        dx,
        dy,
        position,
        dp_dx,
        dp_dy,
        _vec("scale", scale, 2),
        _vec("direction", (0.0, 0.0) if direction is None else direction, 2),
        direction is not None,
        texels,
        offsets,
        shapes,
        ntexels,
        noffsets,
        nshapes,
        lut_arr,
        lut_x,
        luts is not None,
        bool(per_level or luts is not None),
        imap,
        indication is not None,
        _vec("indication_scale", indication_scale, 2),
        _vec("ambient", ambient, 3),
        _vec("diffuse", diffuse, 3),
        _vec("specular", specular_color, 3),
        float(shininess),
        bool(specular),
        kinds,
        light_vec,
        light_color,
        _vec("eye", eye, 3),
        anisotropy,
        float(lod_offset),
        THRESHOLD_CODES[threshold],
        float(c),
        0.5 if centred else 1.0,
        _vec("ink", ink, 3),
        _vec("paper", paper, 3),
        out,
        raw,
    )


def prepare_into(
    out: np.ndarray, mesh_id: np.ndarray, mask: np.ndarray, rgb: Any, n_objects: int
) -> np.ndarray:
    """Fill ``out (nH, nW, 4) float32`` where ``mesh_id < 0`` ((rgb, 1) if ``mask``, else 0)
    and return which of the ``n_objects`` objects some sample shows, (n_objects,) bool."""
    mid = np.ascontiguousarray(mesh_id)
    shape = mid.shape
    if mid.ndim != 2 or mid.dtype.kind not in "iu":
        raise ValueError(f"mesh_id: expected an (nH, nW) int array, got {mid.dtype} {shape}")
    if np.shape(mask) != shape:
        raise ValueError(f"mask: expected shape {shape} (mesh_id's), got {np.shape(mask)}")
    if not (
        isinstance(out, np.ndarray)
        and out.shape == shape + (4,)
        and out.dtype == np.float32
        and out.flags.c_contiguous
    ):
        raise ValueError(f"out: expected a C-contiguous {shape + (4,)} float32 array")
    n = int(n_objects)
    if n < 0:
        raise ValueError(f"n_objects: expected a count >= 0, got {n_objects!r}")
    rows = np.empty((shape[0], max(n, 1)), dtype=np.int64)
    K.prepare(mid, np.ascontiguousarray(mask, dtype=bool), n, _vec("rgb", rgb, 3), rows, out)
    return rows.sum(axis=0)[:n] > 0
