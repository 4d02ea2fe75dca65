"""Memory estimates and size limits, checked before a rasterize or render call allocates anything.

A sample grid nobody checked (``--size 100000x100000``, ``--spp 1000000``) must end in a clear
``ValueError`` naming the size, the bytes it would need and the bytes available, not in numpy's
``_ArrayMemoryError`` from deep inside (or in the kernel's OOM killer). The estimates here count
every array proportional to the sample grid (``n H x n W`` for ``spp = n * n``) that the call
allocates, final channels and internal buffers alike; ``tests/raster/test_memory_estimate.py``
pins them to within a stated factor of the measured peak.

This module imports nothing of refnpr and may be imported by every subpackage.
"""

from __future__ import annotations

import math
import os

try:
    import resource
except ImportError:  # not on Windows: no address-space limit to respect
    resource = None
from collections.abc import Iterable, Mapping

__all__ = [
    "MAX_SPP",
    "MAX_SAMPLES",
    "rasterize_bytes",
    "render_bytes",
    "available_bytes",
    "check_fits",
    "format_bytes",
    "INTERPOLATED",
    "needs_interpolation",
]

#: Largest samples per pixel (a 256 x 256 grid inside each pixel); memory is checked as well.
MAX_SPP = 65536
#: Largest sample grid (n H * n W); ids and tile lists are int32, so stay below 2**31.
MAX_SAMPLES = 2**31
#: Bytes per tile of the binning pass: 64 chunk counts (int64) held three times over (counts,
#: their running sum and the per-chunk offsets), plus about two int32 list entries per tile.
_BIN_BYTES_PER_TILE = 3 * 64 * 8 + 2 * 4
#: Per-sample bytes of a style's own shading work (its temporaries and its float32 RGBA), by
#: style name, measured with tracemalloc on the golden suite's scenes (the growth of the peak from
#: the suite's sizes to twice their width and height), plus about 15 %; other styles get 300.
#: toon and smooth shade in one numba pass (refnpr/styles/lit/_kernels.py): their float32 RGBA
#: plus the kernel's per-material tables, with a margin.
SHADE_BYTES_PER_SAMPLE: dict[str, int] = {
    "toon": 24,
    "smooth": 24,
    "threshold": 230,
    "halftone": 210,
    "xtoon": 170,
    "tam": 215,
    "tamiss": 260,
}
_SHADE_DEFAULT = 300
#: Per-sample bytes of render's composite-and-resolve: none beyond the style's float32 RGBA (one
#: fused numba pass, refnpr/_kernels.py, reads it and writes the image).
_RESOLVE_BYTES_PER_SAMPLE = 0
#: Per-pixel bytes of the resolved image (float32 RGBA).
_IMAGE_BYTES_PER_PIXEL = 16

#: Channels that go through the barycentric interpolation pass (the rasterizer's set: defined
#: here because raster imports this module, never the other way round).
INTERPOLATED = frozenset(
    "ndc_z bary position normal uv duv_dx duv_dy lod dyadic_scale dposition_dx dposition_dy".split()
)


def needs_interpolation(wanted: Iterable[str], attrs: Iterable[str]) -> bool:
    """Whether ``wanted`` has a channel of the interpolation pass: one of :data:`INTERPOLATED`,
    a vertex attribute of ``attrs`` or its derivative ``d<a>_dx`` / ``d<a>_dy``."""
    wanted, attrs = set(wanted), set(attrs)
    derived = {f"d{a}_d{x}" for a in attrs for x in "xy"}
    return bool(wanted & (INTERPOLATED | attrs | derived))


_UV_D = frozenset({"duv_dx", "duv_dy", "lod", "dyadic_scale"})


def _interp_parts(
    wanted: set[str], attributes: Mapping[str, int], s: int, f: int
) -> dict[str, int]:
    """Per-sample-grid buffers of the interpolation pass (mirrors ``raster/channels.py``)."""
    parts: dict[str, int] = {}
    if needs_interpolation(wanted, set(attributes)):
        # every family is written into its own arrays (the channel's, or a scratch one)
        need_uv_d = bool(_UV_D & wanted)
        dcols, vcols = 0, int("ndc_z" in wanted)
        for name, c in {"uv": 2, "position": 3, **attributes}.items():
            if {f"d{name}_dx", f"d{name}_dy"} & wanted or (name == "uv" and need_uv_d):
                dcols += c
            elif name in wanted:
                vcols += c
        if dcols:  # value, d/dx and d/dy
            parts["derivatives"] = 3 * dcols * s * f
        if vcols:
            parts["values"] = vcols * s * f
        for name in ("normal", "bary"):
            if name in wanted:
                parts[name] = 3 * s * f
    if "depth" in wanted:
        parts["depth"] = s * f
    return parts


def rasterize_bytes(
    width: int,
    height: int,
    spp: int,
    channels: Iterable[str],
    *,
    attributes: Mapping[str, int] | None = None,
    itemsize: int = 4,
    tile: int = 32,
) -> dict[str, int]:
    """Bytes a ``rasterize`` call allocates in proportion to its sample grid, by part.

    Parameters
    ----------
    width, height : int
        Image size in pixels.
    spp : int
        Samples per pixel (a square n * n); the sample grid is ``(n H, n W)``.
    channels : iterable of str
        Requested channel names.
    attributes : mapping of str to int, optional
        Vertex attribute name -> components (1 for a scalar attribute), for attribute channels.
    itemsize : int
        Bytes per element of floating channels (4 for float32, 8 for float64).
    tile : int
        Tile edge in samples (binning allocates per tile).

    Returns
    -------
    dict of str to int
        Part name (``"tri_id"``, ``"binning"``, ``"derivatives"``, ...) -> bytes. The sum is the
        estimate of the call's peak; per-triangle and per-vertex arrays are not counted.
    """
    n = math.isqrt(spp)
    s = (n * height) * (n * width)
    p = height * width
    wanted = set(channels)
    f = int(itemsize)
    n_tiles = -(-(n * width) // tile) * -(-(n * height) // tile)
    parts = {"tri_id": 4 * s, "binning": _BIN_BYTES_PER_TILE * n_tiles}
    parts.update({k: 4 * s for k in ("coverage_count", "mesh_id") if k in wanted})
    if "coverage" in wanted:
        parts["coverage"] = p * f
    parts.update(_interp_parts(wanted, dict(attributes or {}), s, f))
    return parts


def render_bytes(
    width: int,
    height: int,
    spp: int,
    channels: Iterable[str],
    style: str,
    *,
    attributes: Mapping[str, int] | None = None,
    tile: int = 32,
) -> dict[str, int]:
    """Bytes a ``render`` call allocates in proportion to its sample grid, by part: the G-buffer
    (:func:`rasterize_bytes`, float32), the style's shading (``SHADE_BYTES_PER_SAMPLE`` of
    ``style``, a name) or the composite and resolve, whichever is larger (they do not overlap),
    and the image."""
    parts = rasterize_bytes(width, height, spp, channels, attributes=attributes, tile=tile)
    n = math.isqrt(spp)
    s = (n * height) * (n * width)
    shade = SHADE_BYTES_PER_SAMPLE.get(style, _SHADE_DEFAULT)
    parts["shading"] = max(shade, 16 + _RESOLVE_BYTES_PER_SAMPLE) * s
    parts["image"] = _IMAGE_BYTES_PER_PIXEL * width * height
    return parts


def read_proc_number(path: str, key: str, base: int = 10) -> int | None:
    """The number after ``key`` on its line of a ``/proc`` file (``MemAvailable:``), or None."""
    try:
        with open(path, encoding="ascii") as fh:
            for line in fh:
                if line.startswith(key):
                    return int(line.split()[1], base)
    except (OSError, ValueError, IndexError):
        pass
    return None


def _meminfo_available() -> int | None:
    kib = read_proc_number("/proc/meminfo", "MemAvailable:")
    if kib is not None:
        return kib * 1024
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def _cgroup_available() -> int | None:
    """Memory left under this process's cgroup memory limit (v2 ``memory.max -
    memory.current``, v1 ``memory.limit_in_bytes - memory.usage_in_bytes``), or None without
    one: a container's limit, which ``MemAvailable`` does not show."""
    try:
        with open("/proc/self/cgroup", encoding="ascii") as fh:
            lines = [ln.strip().split(":", 2) for ln in fh if ln.count(":") >= 2]
    except OSError:
        return None
    candidates = []
    for _id, controllers, rel in lines:
        rel = rel.lstrip("/")
        if controllers == "":  # v2 unified
            candidates.append((os.path.join("/sys/fs/cgroup", rel), "max", "current"))
        elif "memory" in controllers.split(","):  # v1
            for base in (os.path.join("/sys/fs/cgroup/memory", rel), "/sys/fs/cgroup/memory"):
                candidates.append((base, "limit_in_bytes", "usage_in_bytes"))
    for base, limit_name, usage_name in candidates:
        try:
            with open(os.path.join(base, f"memory.{limit_name}"), encoding="ascii") as fh:
                limit = fh.read().strip()
            with open(os.path.join(base, f"memory.{usage_name}"), encoding="ascii") as fh:
                usage = int(fh.read().strip())
        except (OSError, ValueError):
            continue
        if limit == "max" or int(limit) >= 1 << 60:  # no limit
            return None
        return max(0, int(limit) - usage)
    return None


def available_bytes() -> tuple[int | None, str]:
    """Memory this process can still allocate, and where the figure comes from.

    The smallest of the system's available memory (``MemAvailable`` in ``/proc/meminfo``, else
    ``os.sysconf``'s available pages), what is left under a cgroup v2 memory limit (containers)
    and, when ``RLIMIT_AS`` is set, the address space left under it. ``(None, "unknown")`` when neither can be read (nothing is refused then).
    """
    avail, source = _meminfo_available(), "available memory"
    group = _cgroup_available()
    if group is not None and (avail is None or group < avail):
        avail, source = group, "memory left under the cgroup limit"
    soft = resource.getrlimit(resource.RLIMIT_AS)[0] if resource is not None else -1
    if resource is not None and soft != resource.RLIM_INFINITY and soft > 0:
        left = max(0, soft - (read_proc_number("/proc/self/status", "VmSize:") or 0) * 1024)
        if avail is None or left < avail:
            avail, source = left, "address space left under RLIMIT_AS"
    if avail is None:
        return None, "unknown"
    return avail, source


def format_bytes(n: float) -> str:
    """``123.4 GB`` (decimal units, one decimal; MB below 0.1 GB)."""
    if n < 1e8:
        return f"{n / 1e6:.1f} MB"
    return f"{n / 1e9:.1f} GB"


def check_fits(width: int, height: int, spp: int, parts: Mapping[str, int]) -> None:
    """Refuse a sample grid above ``MAX_SAMPLES`` or an estimate above the memory available.

    Parameters
    ----------
    width, height, spp : int
        The call's size (validated already).
    parts : mapping of str to int
        The call's estimate by part (:func:`rasterize_bytes` or :func:`render_bytes`).

    Raises
    ------
    ValueError
        ``size: WxH at spp=N needs about X GB (parts); Y GB are available ...`` with a size
        that would fit.
    """
    n = math.isqrt(spp)
    samples = (n * width) * (n * height)
    need = int(sum(parts.values()))
    avail, source = available_bytes()
    too_many = samples > MAX_SAMPLES
    too_big = avail is not None and need > avail
    if not (too_many or too_big):
        return
    top = sorted(parts.items(), key=lambda kv: -kv[1])
    names = ", ".join(f"{k} {format_bytes(v)}" for k, v in top[:4] if v > 0)
    budget = min(avail if avail is not None else need, need, MAX_SAMPLES / samples * need)
    k = math.sqrt(0.8 * budget / need) if need else 1.0
    sw, sh = max(1, int(width * k)), max(1, int(height * k))
    have = (
        f"{format_bytes(avail)} are available ({source})"
        if avail is not None
        else "the available memory is unknown"
    )
    grid = (
        f"; the sample grid {n * width} x {n * height} = {samples:.3g} samples is over the "
        f"limit of 2**31 = {MAX_SAMPLES}"
        if too_many
        else ""
    )
    raise ValueError(
        f"size: {width}x{height} at spp={spp} needs about {format_bytes(need)} ({names}); "
        f"{have}{grid}. Render smaller (e.g. {sw}x{sh} at spp={spp}) or with fewer samples "
        "per pixel (spp)."
    )
