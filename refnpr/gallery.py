"""The gallery: one small image per paper (and the TAM/TAMISS pair), rendered from golden cases.

``build_gallery(out_dir)`` renders the cases of :data:`GALLERY` from the golden suite at a small
size and writes ``<out_dir>/<file>.png``; ``gallery_markdown`` gives the README's table of them.
Both stay current by being re-run: ``refnpr gallery docs/images/gallery --markdown`` renders
them and prints the table.
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .image import write_png_atomic

if TYPE_CHECKING:
    from argparse import Namespace

    from .golden import GoldenCase

__all__ = [
    "DEFAULT_SIZE",
    "GALLERY",
    "GalleryEntry",
    "build_gallery",
    "compact_pixels",
    "default_suite",
    "gallery_markdown",
    "run",
]


@dataclass(frozen=True)
class GalleryEntry:
    """One gallery image: the golden case it renders, its file name and its caption."""

    case: str
    file: str
    paper: str
    caption: str


#: The case that shows each paper best (read from ``refnpr/suite/*.toml``), in README order.
GALLERY: tuple[GalleryEntry, ...] = (
    GalleryEntry(
        "veryovka-fig6-vase-cross-filtered",
        "veryovka",
        "Veryovka 2002, threshold textures",
        "Fig. 6: multi-scale cross-hatching (dyadic lines, eqs. 5-8), filtered thresholding",
    ),
    GalleryEntry(
        "halftone-fig5-teapot-engraving-smooth",
        "halftone",
        "Freudenberg et al. 2002, real-time halftoning",
        "Fig. 5: engraving screen, smooth threshold",
    ),
    GalleryEntry(
        "xtoon-fig7b-loa-blur",
        "xtoon",
        "Barla et al. 2006, X-Toon",
        "Fig. 7b: level of abstraction, detail from depth in a blurred 2D toon texture",
    ),
    GalleryEntry(
        "tamiss-teapot-tam",
        "tam",
        "Szécsi et al., TAMISS (its RPTAM baseline)",
        "texture-space tonal art map, cross-hatching along u and v",
    ),
    GalleryEntry(
        "tamiss-teapot",
        "tamiss",
        "Szécsi et al., TAMISS",
        "the same strokes fitted in image space (stroke-ID fragments, least squares)",
    ),
)

#: Width and height of the gallery images in pixels.
DEFAULT_SIZE = (320, 240)


def default_suite() -> Path:
    """The golden suite installed with refnpr (``refnpr/suite/suite.toml``)."""
    from .golden import DEFAULT_SUITE  # imported on use: `refnpr --help` stays instant

    return DEFAULT_SUITE


def compact_pixels(rgba: np.ndarray) -> np.ndarray:
    """The same picture in the fewest channels: alpha dropped where it is opaque everywhere,
    colour kept as one grey channel where R = G = B everywhere (PNGs of half the size).

    Parameters
    ----------
    rgba : (H, W, 4) uint8

    Returns
    -------
    (H, W), (H, W, 2), (H, W, 3) or (H, W, 4) uint8
        Decodes to ``rgba`` (grey expands to R = G = B, a missing alpha is 255).
    """
    rgba = np.asarray(rgba)
    if rgba.dtype != np.uint8 or rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"rgba: expected (H, W, 4) uint8, got {rgba.shape} {rgba.dtype}")
    grey = bool(np.all(rgba[..., 0] == rgba[..., 1]) and np.all(rgba[..., 1] == rgba[..., 2]))
    opaque = bool(np.all(rgba[..., 3] == 255))
    colour = rgba[..., :1] if grey else rgba[..., :3]
    out = colour if opaque else np.concatenate([colour, rgba[..., 3:]], axis=2)
    return out[..., 0] if out.shape[2] == 1 else out


def _check_size(size: object) -> tuple[int, int]:
    if (
        not isinstance(size, (tuple, list))
        or len(size) != 2
        or not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in size)
    ):
        raise ValueError(
            f"size: expected (width, height), two positive integers in pixels, got {size!r}"
        )
    return int(size[0]), int(size[1])


def _cases(suite: Path, entries: Sequence[GalleryEntry]) -> list[GoldenCase]:
    from .golden import load_suite  # imported on use: `refnpr --help` stays instant

    by_name = {c.name: c for c in load_suite(suite)}
    missing = [e.case for e in entries if e.case not in by_name]
    if missing:
        raise ValueError(
            f"entries: golden cases {missing} are not in {str(suite)!r}; the gallery renders "
            f"cases of the suite (choose from {sorted(by_name)})"
        )
    cases = [by_name[e.case] for e in entries]
    bad = [c.name for c in cases if c.kind != "image"]
    if bad:
        raise ValueError(f"entries: cases {bad} are G-buffer cases; the gallery shows images")
    return cases


def build_gallery(
    out_dir: str | os.PathLike,
    size: tuple[int, int] = DEFAULT_SIZE,
    *,
    suite: str | os.PathLike | None = None,
    entries: Sequence[GalleryEntry] = GALLERY,
    spp: int | None = None,
    log=None,
) -> list[Path]:
    """Render every gallery entry's golden case at ``size`` into ``out_dir``.

    Parameters
    ----------
    out_dir : str or path
        Created if missing; each entry is written to ``out_dir/<entry.file>.png`` (8-bit sRGB,
        atomic write; grey or without alpha where the picture allows, see
        :func:`compact_pixels`), replacing what was there.
    size : (width, height)
        Pixels; the cases' own cameras and styles are used, only the size changes.
    suite : path, optional
        The golden suite file (default :func:`default_suite`).
    entries : sequence of GalleryEntry
        What to render (default :data:`GALLERY`).
    spp : int, optional
        Samples per pixel for every entry (default: each case's own).
    log : callable(str), optional
        Called with one line per written file.

    Returns
    -------
    list of Path
        The written files, in ``entries`` order.
    """
    from .render import render

    width, height = _check_size(size)
    suite = Path(suite) if suite is not None else default_suite()
    cases = _cases(suite, entries)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out_dir: {str(out_dir)!r} is a file; give a directory")
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for entry, case in zip(entries, cases, strict=True):
        image = render(case.scene, case.style, width, height, case.spp if spp is None else spp)
        path = write_png_atomic(out / f"{entry.file}.png", compact_pixels(image.to_srgb8()))
        paths.append(path)
        if log is not None:
            log(f"{path} ({entry.case}, {path.stat().st_size / 1024:.0f} kB)")
    return paths


def gallery_markdown(
    image_dir: str, entries: Sequence[GalleryEntry] = GALLERY, *, per_row: int = 3
) -> str:
    """The README table: thumbnails ``image_dir/<file>.png`` with one line each on the paper,
    the figure and the golden case (``per_row`` images per table row)."""
    image_dir = image_dir.rstrip("/")
    lines = []
    for start in range(0, len(entries), per_row):
        row = entries[start : start + per_row]
        cells = [f"![{e.paper}]({image_dir}/{e.file}.png)" for e in row]
        notes = [f"**{e.paper}**: {e.caption} (`{e.case}`)" for e in row]
        lines.append("| " + " | ".join(cells) + " |")
        if start == 0:  # the first thumbnails are the table's header row
            lines.append("|" + "---|" * len(row))
        lines.append("| " + " | ".join(notes) + " |")
    return "\n".join(lines) + "\n"


def run(args: Namespace) -> int:
    """``refnpr gallery``: build the gallery from the parsed options (``out_dir``, ``size``,
    ``suite``, ``spp``, ``only``, ``markdown``, ``quiet``: no line per image); 0 on success
    (errors: ValueError)."""
    entries = GALLERY
    if args.only:
        unknown = [n for n in args.only if n not in {e.file for e in GALLERY}]
        if unknown:
            raise ValueError(
                f"--only: unknown gallery entries {unknown}; choose from {[e.file for e in GALLERY]}"
            )
        entries = tuple(e for e in GALLERY if e.file in args.only)
    log = None if getattr(args, "quiet", False) else functools.partial(print, file=sys.stderr)
    build_gallery(args.out_dir, args.size, suite=args.suite, entries=entries, spp=args.spp, log=log)
    if args.markdown:
        print(gallery_markdown(Path(args.out_dir).as_posix(), entries), end="")
    return 0
