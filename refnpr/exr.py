"""OpenEXR files: one writer for every EXR refnpr writes, and the pass layout of rendered images.

:func:`write_exr_channels` writes named 2-D channels as one single-part scanline OpenEXR file
(ZIP compression, lossless; row 0 is the top row), through a temporary file and an atomic
rename, and reads the file back before the rename: OpenEXR's writer does not always report a
failed write (a full disk can leave a truncated file and no error), so a write that fails or
does not read back is a ValueError naming the file and, where a full disk is the likely cause,
the free space. The conformance kit's textures and expected images
(:func:`refnpr.kit.exr.write_exr`), ``refnpr animate --exr`` frames and
``Image.save("x.exr")`` / ``refnpr render --exr`` all go through it.

Rendered images as EXR (:func:`image_channels`): one part with the linear RGBA result and the
image's G-buffer passes (``Image.passes``), named as compositing tools expect:

========================== ======================================================== ==========
channel                    value                                                    pixel type
========================== ======================================================== ==========
``R``, ``G``, ``B``, ``A`` linear colour premultiplied by alpha (OpenEXR's          FLOAT
                           convention; equal to ``Image.rgba`` where alpha is 1,
                           as over an opaque background), and alpha
``depth.Z``                eye-space distance along the view axis; +inf where empty FLOAT
``normal.X/Y/Z``           world-space interpolated normal; 0 where empty           FLOAT
``uv.U/V``                 texture coordinates                                      FLOAT
``position.X/Y/Z``         world-space position                                     FLOAT
``tri_id``, ``mesh_id``    the int32 id's bit pattern: the id, 4294967295 (int32    UINT
                           -1) where empty; read back with ``.view(numpy.int32)``
others                     every other channel the frame computed: a scalar by      FLOAT
                           its name (``ndc_z``, ``lod``, ``coverage``, ...); C
                           components as ``name.X/Y/Z/W`` (``duv_dx.U/V``; more
                           than 4: ``name.0``, ``name.1``, ...); integer
                           channels as UINT like the ids
style intermediates        the values the style's formulas computed on the way      FLOAT
                           to the colour (``Style.INTERMEDIATES``): ``tone`` and
                           ``detail`` (X-Toon), ``tone`` and ``threshold``
                           (threshold), ``intensity`` and ``threshold``
                           (halftone), ``darkness`` (tam, tamiss), ``tone`` and
                           ``toon_tone`` (toon), ``tone`` (smooth); a base style
                           under strokes adds its own as ``base.<name>``; 0
                           where empty
``stroke_id.lo/.hi``       a 64-bit integer pass (tamiss: the stroke id of the       UINT
                           first fragment gathered at the pixel) as its low and
                           high 32 bits; both 4294967295 (-1) where none:
                           ``(hi.astype(uint64) << 32 | lo).view(int64)``
========================== ======================================================== ==========

Passes are per pixel, not per sample: see :func:`pixel_passes`.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ._atomic import atomic_file, check_output_file

__all__ = [
    "EXR_PASSES",
    "channel_names",
    "check_exr_path",
    "image_channels",
    "passes_for",
    "pixel_passes",
    "write_exr_channels",
]

#: The G-buffer channels ``render(..., passes=True)`` adds to what the style needs: the geometry
#: every mesh has (``normal`` and ``uv`` only where every mesh has normals / uv).
EXR_PASSES: tuple[str, ...] = ("depth", "position", "tri_id", "mesh_id", "normal", "uv")

#: Component names of multi-component channels, by channel.
_COMPONENTS: dict[str, tuple[str, ...]] = {
    "uv": ("U", "V"),
    "duv_dx": ("U", "V"),
    "duv_dy": ("U", "V"),
}
_XYZW = ("X", "Y", "Z", "W")


def _missing_openexr(what: str, path: Any) -> ValueError:
    return ValueError(
        f"{what}: writing {str(path)!r} needs the OpenEXR package; install it with "
        "`pip install 'refnpr[kit]'` (or `pip install OpenEXR`)"
    )


def check_exr_path(path: str | os.PathLike, *, what: str = "path") -> Path:
    """``path`` as a Path, validated before any work: not a directory, an ``.exr`` suffix, a
    parent directory that exists (or can be created) and is writable, and OpenEXR installed;
    else a ValueError naming ``what``, the path as given and what to give instead."""
    p = check_output_file(path, what, ".exr")
    try:
        import OpenEXR  # noqa: F401
    except ImportError:
        raise _missing_openexr(what, os.fspath(path)) from None
    return p


def write_exr_channels(
    path: str | os.PathLike,
    channels: Mapping[str, np.ndarray],
    *,
    what: str = "exr",
    opener: Callable[..., Any] = atomic_file,
) -> Path:
    """Write named channels as one single-part scanline OpenEXR file (ZIP), atomically.

    Parameters
    ----------
    path : str or path
        The target; its directory is created.
    channels : mapping of str to (H, W) array
        Channel name -> pixels, all of one shape. float16/float32/float64 are written as FLOAT
        (float32; exact for float32 input), uint32 as UINT; other dtypes are refused. Names are
        written as given, in sorted order (OpenEXR's own order).
    what : str
        The start of every error message (``"exr"``, ``"texture"``).
    opener : callable(path, suffix=...) -> context manager yielding a Path
        Where the bytes go first: :func:`refnpr.image.atomic_file` (a temporary file renamed
        over ``path`` when the block ends).

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        No channels, an empty or non-text name, arrays of different or non-2-D shapes, an
        unsupported dtype, OpenEXR missing, or a failed write (naming ``path``; with the free
        space where the file system is full).
    """
    path = Path(path)
    if not channels:
        raise ValueError(f"{what}: no channels to write to {str(path)!r}")
    arrays: dict[str, np.ndarray] = {}
    shape = None
    for name, a in channels.items():
        if not isinstance(name, str) or not name or not name.isprintable():
            raise ValueError(f"{what}: channel name {name!r} for {str(path)!r} is not a name")
        a = np.asarray(a)
        if a.ndim != 2 or min(a.shape) < 1:
            raise ValueError(
                f"{what}: channel {name!r} for {str(path)!r}: expected an (H, W) array, got "
                f"shape {a.shape}"
            )
        if shape is not None and a.shape != shape:
            raise ValueError(
                f"{what}: channel {name!r} for {str(path)!r} is {a.shape}, the others {shape}; "
                "every channel needs one shape"
            )
        shape = a.shape
        if a.dtype.kind == "f":
            a = a.astype(np.float32, copy=False)
        elif a.dtype != np.uint32:
            raise ValueError(
                f"{what}: channel {name!r} for {str(path)!r} has dtype {a.dtype}; expected "
                "float (FLOAT) or uint32 (UINT)"
            )
        arrays[name] = np.ascontiguousarray(a)
    try:
        import OpenEXR
    except ImportError:
        raise _missing_openexr(what, path) from None
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    nbytes = sum(a.nbytes for a in arrays.values())
    with opener(path, suffix=".exr") as tmp:
        try:
            with OpenEXR.File(header, arrays) as f:
                f.write(str(tmp))
        except RuntimeError as exc:  # OpenEXR's I/O errors ("No space left on device")
            _write_failed(what, Path(tmp), path, nbytes, str(exc))
        if not _reads_back(Path(tmp), shape, set(arrays)):
            _write_failed(what, Path(tmp), path, nbytes, "the written file does not read back")
    return path


def _reads_back(tmp: Path, shape: tuple, names: set[str]) -> bool:
    """Whether the EXR at ``tmp`` reads back with exactly ``names``, each of ``shape``."""
    import OpenEXR

    try:
        with OpenEXR.File(str(tmp), separate_channels=True) as f:
            got = {n: c.pixels.shape[:2] for n, c in f.channels().items()}
    except Exception:  # noqa: BLE001 -- any failure to read back is a failed write
        return False
    return set(got) == names and all(tuple(g) == tuple(shape) for g in got.values())


def _write_failed(what: str, tmp: Path, path: Path, nbytes: int, detail: str) -> None:
    """ValueError for an EXR that could not be written, naming ``path`` and the free space where
    a full disk is the likely cause."""
    try:
        free = shutil.disk_usage(tmp.parent).free
    except OSError:
        free = 0
    full = "No space left" in detail or free < max(1 << 20, 2 * nbytes)
    why = (
        f"the file system is full ({free} bytes free); free some space or write elsewhere"
        if full
        else f"{detail}; check the disk and try again"
    )
    raise ValueError(f"{what}: writing {str(path)!r} failed: {why}") from None


def channel_names(name: str, components: int) -> tuple[str, ...]:
    """The EXR channel names of a pass (module docstring): ``depth`` -> ``depth.Z``; a scalar
    -> its name; ``uv`` -> ``uv.U/V``; 3 components -> ``name.X/Y/Z``; more than 4 ->
    ``name.0 ..``."""
    if name == "depth" and components == 0:
        return ("depth.Z",)
    if components == 0:
        return (name,)
    if name in _COMPONENTS and components == len(_COMPONENTS[name]):
        return tuple(f"{name}.{c}" for c in _COMPONENTS[name])
    if components <= 4:
        return tuple(f"{name}.{c}" for c in _XYZW[:components])
    return tuple(f"{name}.{i}" for i in range(components))


def _as_exr_array(a: np.ndarray, name: str = "pass") -> np.ndarray:
    """A pass component as FLOAT (float32) or UINT (an integer's 32-bit pattern; an integer
    outside the int32 / uint32 range is refused, naming the channel)."""
    if a.dtype.kind in "iub":
        wide = a.astype(np.int64, copy=False)
        if wide.size and (wide.min() < -(1 << 31) or wide.max() >= 1 << 32):
            raise ValueError(
                f"passes: channel {name!r} holds integers beyond 32 bits; give a 64-bit id "
                "pass as a 2-D int64 array (written as name.lo / name.hi)"
            )
        return np.ascontiguousarray(wide.astype(np.uint32))
    return np.ascontiguousarray(a, dtype=np.float32)


def image_channels(
    rgba: np.ndarray, passes: Mapping[str, np.ndarray] | None = None
) -> dict[str, np.ndarray]:
    """The EXR channels of a rendered image: premultiplied ``R``, ``G``, ``B``, alpha ``A`` and
    each pass under :func:`channel_names` (module docstring).

    Parameters
    ----------
    rgba : (H, W, 4) float
        Linear straight-alpha pixels (``Image.rgba``).
    passes : mapping of str to (H, W) or (H, W, C) array, optional
        Per-pixel G-buffer channels (``Image.passes``); float as FLOAT, integer as UINT.

    Returns
    -------
    dict of str to (H, W) float32 or uint32
    """
    rgba = np.asarray(rgba, dtype=np.float32)
    alpha = rgba[..., 3]
    out = {c: np.ascontiguousarray(rgba[..., i] * alpha) for i, c in enumerate("RGB")}
    out["A"] = np.ascontiguousarray(alpha)
    for name, a in sorted((passes or {}).items()):
        a = np.asarray(a)
        if a.shape[:2] != rgba.shape[:2] or a.ndim not in (2, 3):
            raise ValueError(
                f"passes: {name!r} has shape {a.shape}; expected ({rgba.shape[0]}, "
                f"{rgba.shape[1]}) or ({rgba.shape[0]}, {rgba.shape[1]}, C), the image's size"
            )
        if a.ndim == 2 and a.dtype == np.int64:  # a 64-bit id: its two 32-bit halves
            bits = a.view(np.uint64)
            out[f"{name}.lo"] = np.ascontiguousarray((bits & 0xFFFFFFFF).astype(np.uint32))
            out[f"{name}.hi"] = np.ascontiguousarray((bits >> np.uint64(32)).astype(np.uint32))
            continue
        comps = 0 if a.ndim == 2 else a.shape[2]
        for i, n in enumerate(channel_names(name, comps)):
            out[n] = _as_exr_array(a if comps == 0 else a[..., i], n)
    return out


def pixel_passes(
    gb: Any, names: Iterable[str] | None = None, samples: Mapping[str, np.ndarray] | None = None
) -> dict[str, np.ndarray]:
    """Per-pixel copies of G-buffer channels: at each pixel, sample ``(k, k)`` of its n x n
    samples with ``k = (n - 1) // 2``.

    For odd n (spp 1, 9, 25) that sample lies at the pixel centre ``(x + 0.5, y + 0.5)``, so a
    pass holds the attribute at the pixel centre; for even n (spp 4, 16) it is the upper-left of
    the four samples around the centre, at ``(x + 0.5 - 0.5 / n, y + 0.5 - 0.5 / n)``. Values are
    picked, never averaged (an average of depths or ids across an edge is no surface's).
    ``coverage`` is per pixel already and copied as is.

    Parameters
    ----------
    gb : GBuffer
        Channels ``(n H, n W)`` or ``(n H, n W, C)`` (``coverage``: ``(H, W)``).
    names : iterable of str, optional
        The channels to take (default: all of ``gb``).
    samples : mapping of str to (n H, n W) array, optional
        More per-sample arrays on the G-buffer's grid (a style's intermediates), picked the
        same way; their names must not repeat a channel's.

    Returns
    -------
    dict of str to (H, W) or (H, W, C) array
        New arrays of the channels' own dtypes.
    """
    n = gb.n
    k = (n - 1) // 2
    arrays = {name: gb[name] for name in (gb.channels if names is None else names)}
    for name, a in (samples or {}).items():
        if name in arrays:
            raise ValueError(f"samples: {name!r} repeats a G-buffer channel's name")
        arrays[name] = a
    out = {}
    for name in sorted(arrays):
        a = arrays[name]
        if a.shape[:2] == (gb.height, gb.width):  # per pixel (n == 1, or coverage)
            out[name] = np.array(a)
        else:
            out[name] = np.ascontiguousarray(a[k::n, k::n])
    return out


def passes_for(meshes: Iterable[Any]) -> frozenset[str]:
    """The channels of :data:`EXR_PASSES` every mesh of ``meshes`` can give (``normal`` needs
    vertex normals, ``uv`` texture coordinates)."""
    meshes = list(meshes)
    wanted = set(EXR_PASSES)
    if any(getattr(m, "normals", None) is None for m in meshes):
        wanted.discard("normal")
    if any(getattr(m, "uv", None) is None for m in meshes):
        wanted.discard("uv")
    return frozenset(wanted)
