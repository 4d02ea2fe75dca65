"""What every mesh-file check shares: the error, number parsing, face and finiteness checks, and
the check of what trimesh read."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable

import numpy as np

from ...raster.mesh import coordinate_limit_message


class BadMeshFile(Exception):
    """What is wrong with a file (the caller adds the path)."""


FIX = "re-export the file from its source, or repair it"
_SPACE = np.zeros(256, bool)
_SPACE[[9, 10, 11, 12, 13, 32]] = True


def _float(tok: str, where: str) -> float:
    try:
        v = float(tok)
    except ValueError:
        raise BadMeshFile(f"{where}: {tok[:40]!r} is not a number") from None
    if not math.isfinite(v):
        raise BadMeshFile(
            f"{where}: non-finite coordinate {tok[:40]!r}; every vertex must be finite"
        )
    return v


def _is_count(n: float) -> bool:
    return math.isfinite(n) and n >= 0 and n == math.floor(n)


def _numbers(buf: bytes, dtype=np.float64) -> np.ndarray | None:
    """All whitespace-separated numbers of ``buf`` (C speed), or None if one does not parse."""
    if not buf.strip():
        return np.zeros(0, dtype)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            return np.fromstring(buf, dtype=dtype, sep=" ")
        except (DeprecationWarning, ValueError):
            return None


def _check_finite(v: np.ndarray, where: Callable[[int], str]) -> None:
    ok = np.isfinite(v).all(axis=1)
    if not ok.all():
        i = int(np.argmin(ok))
        raise BadMeshFile(
            f"{where(i)} is not finite ({v[i].tolist()}): non-finite coordinates are refused; "
            "every vertex must be finite"
        )


def _integral(counts: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """Face indices read as floats (``flat``, faces of ``counts`` indices) as int64, whole."""
    bad = flat != np.floor(flat)
    if bad.any():
        i = int(np.searchsorted(np.cumsum(counts), np.argmax(bad), "right"))
        raise BadMeshFile(f"face {i}: vertex indices must be integers")
    return flat.astype(np.int64)


def _check_faces(
    counts: np.ndarray, flat: np.ndarray, nv: int, where: Callable[[int], str], base: int = 0
) -> None:
    """Faces given as their vertex counts and all their indices in a row (zero-based): each has
    at least 3 vertices, each index names an existing vertex (shown as ``index + base``)."""
    short = np.flatnonzero(counts < 3)
    if short.size:
        i = int(short[0])
        raise BadMeshFile(f"{where(i)}: a face needs at least 3 vertices, got {int(counts[i])}")
    bad = (flat < 0) | (flat >= nv)
    if bad.any():
        k = int(np.argmax(bad))
        i = int(np.searchsorted(np.cumsum(counts), k, side="right"))
        raise BadMeshFile(
            f"{where(i)}: face references vertex {int(flat[k]) + base}, but the file has {nv} "
            "vertices (missing vertices? the file may be truncated or corrupt)"
        )


def _lines(data: bytes, keep: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None):
    """Split text into lines with numpy: (buffer of the kept lines, each ending in a newline,
    with each line's first byte blanked when ``keep`` selects; kept line numbers, zero-based;
    the whitespace-separated token count of each kept line)."""
    if not data.endswith(b"\n"):
        data = data + b"\n"
    arr = np.frombuffer(data, np.uint8)
    ends = np.flatnonzero(arr == 10)
    starts = np.empty_like(ends)
    starts[0] = 0
    starts[1:] = ends[:-1] + 1
    if keep is None:
        rows = np.arange(ends.size)
        buf = arr
    else:
        sel = keep(arr[starts], arr[np.minimum(starts + 1, arr.size - 1)])
        rows = np.flatnonzero(sel)
        buf = arr[np.repeat(sel, ends - starts + 1)]
        lens = (ends - starts + 1)[rows]
        buf[np.cumsum(lens) - lens] = 32  # the keyword ("v", "f")
    if not rows.size:
        return b"", rows, np.zeros(0, np.int64)
    space = _SPACE[buf]
    first = ~space
    first[1:] &= space[:-1]
    del space
    tokens = np.flatnonzero(first)  # where each token starts
    del first
    bounds = np.searchsorted(tokens, np.flatnonzero(buf == 10))
    counts = np.diff(bounds, prepend=0)
    return (data if keep is None else buf.tobytes()), rows, counts


def _gather(values: np.ndarray, counts: np.ndarray, skip: np.ndarray | int, take: np.ndarray):
    """From rows of ``counts`` values laid end to end, take ``take[i]`` after ``skip[i]``."""
    take = np.asarray(take, np.int64)
    row0 = np.cumsum(counts) - counts + skip
    first = np.cumsum(take) - take
    idx = np.repeat(row0 - first, take) + np.arange(int(take.sum()))
    return values[idx]


def check_geometry(g, what: str) -> None:
    """Checks on what trimesh read (process=False) that must run before ``process()``: finite
    positions, indices in range and coordinates within the limit (merging vertices indexes the
    faces and overflows int64 on huge coordinates), not all triangles degenerate. Mesh checks
    the rest when load_mesh builds it."""
    v = np.asarray(g.vertices, dtype=np.float64)
    f = np.asarray(g.faces)
    if f.ndim != 2 or f.shape[0] == 0:
        raise BadMeshFile(f"{what} has no triangles (a point cloud or a path?)")
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
        raise BadMeshFile(f"{what} has no vertices")
    _check_finite(v, lambda i: f"{what}: vertex {i}")
    if f.min() < 0 or f.max() >= v.shape[0]:
        raise BadMeshFile(
            f"{what}: face indices span {int(f.min())}..{int(f.max())} for {v.shape[0]} vertices"
        )
    msg = coordinate_limit_message(what, v) or zero_area_message(what, v, f)
    if msg is not None:
        raise BadMeshFile(msg)


def zero_area_message(what: str, positions: np.ndarray, faces: np.ndarray) -> str | None:
    """The refusal of a mesh whose triangles all have zero area (nothing to draw), in the one
    wording the mesh-file checks and the glTF reader share; ``None`` when some triangle has an
    area. ``positions`` (N, 3) finite, ``faces`` (F, 3) valid indices into them."""
    for s in range(0, faces.shape[0], 1 << 14):  # stop at the first chunk that draws something
        tri = positions[faces[s : s + (1 << 14)]]
        if np.any(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]) != 0):
            return None
    return f"{what}: all {faces.shape[0]} triangles have zero area (nothing to draw)"
