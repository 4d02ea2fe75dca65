"""Texture files of a kit case: one file per mip level, EXR for float data, PNG for 8-bit.

A style module calls :func:`write_texture_levels` for every texture its style samples and puts
the returned entry in ``StyleExport.textures[role]``; params reference the texture by ``role``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from ..image import write_png_atomic
from .exr import write_exr

__all__ = [
    "ENCODINGS",
    "WRAPS",
    "FILTERS",
    "ORIENTATION_ROW0_V0",
    "ORIENTATION_ROW0_TOP",
    "write_texture_levels",
    "write_pyramid",
    "write_table",
]

ENCODINGS = ("linear", "srgb")
WRAPS = ("repeat", "clamp")
FILTERS = ("nearest", "linear", "linear_mipmap_linear", "per_level")
#: refnpr's sampler convention (refnpr.texture.sample): texel row r covers v in [r/H, (r+1)/H).
ORIENTATION_ROW0_V0 = (
    "row 0 = v 0: texel (i, j) = array[j, i] covers u in [i/W, (i+1)/W), v in [j/H, (j+1)/H)"
)
#: Image-like data indexed by screen or detail rows (row 0 = the top / first row).
ORIENTATION_ROW0_TOP = "row 0 = the first (top) row of the array; no flip"
_ROLE = re.compile(r"^[a-z0-9][a-z0-9_\-]*$")


def write_texture_levels(
    case_dir: str | Path,
    role: str,
    levels: list[np.ndarray],
    *,
    encoding: str,
    wrap: str,
    filter: str,
    orientation: str,
    used_for: str,
) -> dict[str, Any]:
    """Write a texture's mip levels under ``case_dir/textures/<role>/`` and describe them.

    Parameters
    ----------
    case_dir : path
        The case directory (``DIR/<name>``).
    role : str
        Texture role name, ``[a-z0-9][a-z0-9_-]*`` (params reference it).
    levels : list of (H, W) or (H, W, C) arrays, C in 1-4
        Level 0 first. Floating arrays are written as 32-bit float EXR (``level_<L>.exr``,
        exact values), uint8 arrays as PNG (``level_<L>.png``, exact bytes). All levels share
        the dtype and channel count.
    encoding : {"linear", "srgb"}
        How the stored values map to what the style uses (refnpr samples the values as stored:
        "linear" unless the style applies an sRGB decode).
    wrap : {"repeat", "clamp"}
    filter : {"nearest", "linear", "linear_mipmap_linear", "per_level"}
        What refnpr does ("per_level": the style samples chosen levels itself).
    orientation : str
        How texel rows map to v (see ``ORIENTATION_ROW0_V0``).
    used_for : str
        One line: what the style samples it for.

    Returns
    -------
    dict
        The ``textures[role]`` entry: ``file``, ``levels`` (paths relative to ``case_dir``),
        ``shape`` (level 0), ``dtype``, ``encoding``, ``wrap``, ``filter``, ``orientation``,
        ``used_for``.

    Raises
    ------
    ValueError, TypeError
        Naming the parameter and value (unknown option, empty levels, mixed dtypes, bad shape).
    """
    if not isinstance(role, str) or not _ROLE.match(role):
        raise ValueError(f"role: expected a name matching [a-z0-9][a-z0-9_-]*, got {role!r}")
    for key, value, allowed in (
        ("encoding", encoding, ENCODINGS),
        ("wrap", wrap, WRAPS),
        ("filter", filter, FILTERS),
    ):
        if value not in allowed:
            raise ValueError(f"{key}: expected one of {list(allowed)}, got {value!r}")
    for key, value in (("orientation", orientation), ("used_for", used_for)):
        if not isinstance(value, str) or not value.strip():
            raise TypeError(f"{key}: expected a non-empty string, got {value!r}")
    if not isinstance(levels, (list, tuple)) or not levels:
        raise ValueError(f"levels: expected a non-empty list of arrays for role {role!r}")
    arrays = [np.asarray(a) for a in levels]
    first = arrays[0]
    for i, a in enumerate(arrays):
        if a.dtype != np.uint8 and a.dtype.kind != "f":
            raise TypeError(
                f"levels[{i}] of role {role!r}: expected float or uint8 data, got {a.dtype}"
            )
        if (a.dtype == np.uint8) != (first.dtype == np.uint8):
            raise TypeError(
                f"levels of role {role!r}: mixed dtypes {first.dtype} and {a.dtype} (level {i})"
            )
        if a.ndim not in (2, 3) or (a.ndim == 3 and not 1 <= a.shape[2] <= 4):
            raise ValueError(
                f"levels[{i}] of role {role!r}: expected shape (H, W) or (H, W, C), C in 1-4, "
                f"got {a.shape}"
            )
        if a.shape[2:] != first.shape[2:]:
            raise ValueError(
                f"levels of role {role!r}: channel count changes at level {i} "
                f"({first.shape} vs {a.shape})"
            )
    case_dir = Path(case_dir)
    is8 = first.dtype == np.uint8
    paths = []
    for i, a in enumerate(arrays):
        rel = f"textures/{role}/level_{i}.{'png' if is8 else 'exr'}"
        if is8:
            write_png_atomic(case_dir / rel, a)
        else:
            write_exr(case_dir / rel, a.astype(np.float32))
        paths.append(rel)
    return {
        "file": paths[0],
        "levels": paths,
        "shape": [int(s) for s in first.shape],
        "dtype": "uint8" if is8 else "float32",
        "encoding": encoding,
        "wrap": wrap,
        "filter": filter,
        "orientation": orientation,
        "used_for": used_for,
    }


def write_pyramid(
    case_dir: str | Path, role: str, levels: Any, *, filter: str, used_for: str
) -> dict[str, Any]:
    """A float texture's mip levels (each as float32), GL_REPEAT in refnpr's orientation
    (``ORIENTATION_ROW0_V0``): :func:`write_texture_levels` with those options."""
    return write_texture_levels(
        case_dir,
        role,
        [np.asarray(lv, dtype=np.float32) for lv in levels],
        encoding="linear",
        wrap="repeat",
        filter=filter,
        orientation=ORIENTATION_ROW0_V0,
        used_for=used_for,
    )


def write_table(
    case_dir: str | Path,
    role: str,
    table: np.ndarray,
    *,
    orientation: str,
    used_for: str,
    filter: str = "nearest",
) -> dict[str, Any]:
    """One float32 level clamped to edge (a lookup table or a per-pixel map):
    :func:`write_texture_levels` with those options."""
    return write_texture_levels(
        case_dir,
        role,
        [np.asarray(table, dtype=np.float32)],
        encoding="linear",
        wrap="clamp",
        filter=filter,
        orientation=orientation,
        used_for=used_for,
    )
