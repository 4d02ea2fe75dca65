"""Compile refnpr's numba kernels ahead of the first render (``refnpr warmup``).

numba compiles a kernel the first time it is called with a new combination of argument types and
caches the machine code on disk (``cache=True``, in ``__pycache__`` beside the sources or under
``NUMBA_CACHE_DIR``). A fresh install therefore pays the compilation on its first render: about
ten seconds for the default scene on a 2-core machine, most of it the rasterizer's kernels.
:func:`warm` renders tiny frames that take every style's default path, at one and at several
samples per pixel, with and without the contour layer, so that afterwards every such render only
loads cached code. The set-up command of the README runs it once after installing.

Nothing here changes any result: it only renders (and discards) small images.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed

from .render import render
from .styles._declare import check_number

__all__ = ["WARM_ROWS", "warm"]

#: (scene, style) pairs rendered: each style's benchmark scene (benchmarks/bench_frame.py) and the
#: default scene with its own style (``None``: what ``refnpr render`` draws). After the default
#: scene, costliest to compile first, so that worker processes take the long ones first.
WARM_ROWS: tuple[tuple[str, str | None], ...] = (
    ("default", None),
    ("tamiss_teapot", "tam"),
    ("tamiss_teapot", "tamiss"),
    ("veryovka_plane", "threshold"),
    ("teapot", "toon"),
    ("teapot", "smooth"),
    ("xtoon_teapot", "xtoon"),
    ("halftone_teapot", "halftone"),
)

#: Tiny frames: compilation depends on argument types, not on sizes.
_SIZE = (64, 36)


def _label(scene: str, style: str | None, spp: int, contours: bool) -> str:
    return f"{scene} / {style or 'its style'} spp {spp}{' + contours' if contours else ''}"


def _jobs(rows: Sequence[tuple[str, str | None]]) -> list[tuple[str, str | None, int, bool]]:
    """Each row at spp 1, then at spp 4 with contours."""
    return [(scene, style, spp, spp > 1) for scene, style in rows for spp in (1, 4)]


def _render_job(scene: str, style: str | None, spp: int, contours: bool) -> float:
    spec = {"name": style, "contours": True} if contours and style is not None else style
    t = time.perf_counter()
    render(scene, spec, *_SIZE, spp)
    return time.perf_counter() - t


def _warm_group(rows: list[tuple[str, str | None]]) -> dict[str, float]:
    """One worker's task: the renders of ``rows`` in order (a worker process's entry point)."""
    return {_label(*job): _render_job(*job) for job in _jobs(rows)}


def _groups(rows: Sequence[tuple[str, str | None]]) -> list[list[tuple[str, str | None]]]:
    """Rows grouped by scene, in order of first appearance: rows of one scene share most of
    their kernels (toon and smooth, TAM and TAMISS), so one worker compiles them once."""
    groups: dict[str, list[tuple[str, str | None]]] = {}
    for row in rows:
        groups.setdefault(str(row[0]), []).append(row)
    return list(groups.values())


def warm(
    rows: Sequence[tuple[str, str | None]] = WARM_ROWS,
    *,
    jobs: int = 1,
    progress: Callable[[str, float], None] | None = None,
) -> dict[str, float]:
    """Render each row at 64x36, spp 1 and spp 4 with contours, so their kernels are compiled
    and cached.

    numba compiles one kernel at a time on one core, so with ``jobs > 1`` the rows are rendered
    in up to ``jobs`` worker processes (``spawn``; they share the on-disk cache through
    ``NUMBA_CACHE_DIR`` or ``__pycache__``, whose saves :mod:`refnpr._jit` serialises), the rows
    of one scene in one worker (toon and smooth, TAM and TAMISS share most of their kernels),
    in the order of ``rows``. The workers all compile the rasterizer's kernels at first (on
    two cores: 62-69 s serial, 38-43 s with two workers for :data:`WARM_ROWS`). This process
    renders nothing then: what it leaves is the on-disk cache, as with ``jobs=1``.

    Parameters
    ----------
    rows : sequence of (scene, style or None)
        Built-in scene names (or scene files) and style names; None for the scene's own style.
    jobs : int
        Processes compiling at once, 1 to 64 (default 1: everything in this process).
    progress : callable(label, fraction), optional
        Called with ``"scene / style spp N"`` and the fraction done: before each render when
        ``jobs`` is 1, after each worker's renders otherwise.

    Returns
    -------
    dict of str to float
        Seconds per render, keyed like the progress labels, in the order of ``rows`` (the first
        ones include compiling; with ``jobs > 1`` a worker's first render also includes its
        imports).
    """
    if isinstance(rows, (str, bytes)) or not all(
        isinstance(r, tuple) and len(r) == 2 for r in rows
    ):
        raise TypeError(f"rows: expected a sequence of (scene, style or None) pairs, got {rows!r}")
    jobs = check_number("jobs", jobs, integer=True, lo=1, hi=64)
    rows = list(rows)
    work = _jobs(rows)
    groups = _groups(rows)
    tell = progress or (lambda label, fraction: None)
    done: dict[str, float] = {}
    if jobs == 1 or len(groups) < 2:
        for i, job in enumerate(work):
            tell(_label(*job), i / len(work))
            done[_label(*job)] = _render_job(*job)
    else:
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(min(jobs, len(groups)), mp_context=ctx) as pool:
            for fut in as_completed([pool.submit(_warm_group, group) for group in groups]):
                part = fut.result()
                done.update(part)
                for label in part:
                    tell(label, len(done) / len(work))
    tell("done", 1.0)
    return {_label(*job): done[_label(*job)] for job in work}
