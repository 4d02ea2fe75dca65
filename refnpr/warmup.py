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

import time
from collections.abc import Callable, Sequence

from .render import render

__all__ = ["WARM_ROWS", "warm"]

#: (scene, style) pairs rendered: each style's benchmark scene (benchmarks/bench_frame.py) and the
#: default scene with its own style (``None``: what ``refnpr render`` draws).
WARM_ROWS: tuple[tuple[str, str | None], ...] = (
    ("default", None),
    ("teapot", "toon"),
    ("teapot", "smooth"),
    ("xtoon_teapot", "xtoon"),
    ("veryovka_plane", "threshold"),
    ("halftone_teapot", "halftone"),
    ("tamiss_teapot", "tam"),
    ("tamiss_teapot", "tamiss"),
)

#: Tiny frames: compilation depends on argument types, not on sizes.
_SIZE = (64, 36)


def warm(
    rows: Sequence[tuple[str, str | None]] = WARM_ROWS,
    *,
    progress: Callable[[str, float], None] | None = None,
) -> dict[str, float]:
    """Render each row at 64x36, spp 1 and spp 4 with contours, so their kernels are compiled
    and cached.

    Parameters
    ----------
    rows : sequence of (scene, style or None)
        Built-in scene names (or scene files) and style names; None for the scene's own style.
    progress : callable(label, fraction), optional
        Called before each render with ``"scene / style spp N"`` and the fraction done.

    Returns
    -------
    dict of str to float
        Seconds per render, keyed like the progress labels (the first ones include compiling).
    """
    if isinstance(rows, (str, bytes)) or not all(
        isinstance(r, tuple) and len(r) == 2 for r in rows
    ):
        raise TypeError(f"rows: expected a sequence of (scene, style or None) pairs, got {rows!r}")
    jobs = []
    for scene, style in rows:
        jobs.append((scene, style, 1, False))
        jobs.append((scene, style, 4, True))
    times: dict[str, float] = {}
    for i, (scene, style, spp, contours) in enumerate(jobs):
        label = f"{scene} / {style or 'its style'} spp {spp}{' + contours' if contours else ''}"
        if progress is not None:
            progress(label, i / len(jobs))
        spec = style
        if contours and style is not None:
            spec = {"name": style, "contours": True}
        t = time.perf_counter()
        render(scene, spec, *_SIZE, spp)
        times[label] = time.perf_counter() - t
    if progress is not None:
        progress("done", 1.0)
    return times
