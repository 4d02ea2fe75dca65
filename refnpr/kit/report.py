"""The ``refnpr kit check`` report: per-case images, a page per case and ``index.html``.

Layout of a report directory::

    REPORT/index.html                     summary, legend, filters, one entry per case
    REPORT/cases/<case>/case.html         the case: margin, worst pixels, full-size views,
                                          parameters and derived texts (from the kit's case.json)
    REPORT/cases/<case>/reference.png     the expected image (sRGB composited over black)
    REPORT/cases/<case>/result.png        the backend's render, the same way
    REPORT/cases/<case>/diff.png          signed difference, per pixel the channel of largest |d|
    REPORT/cases/<case>/diff_channels.png signed difference per channel (R, G / B, A)
    REPORT/cases/<case>/mask.png          error mask: green pass, red fail, black background
    REPORT/cases/<case>/crop.png          24 x 24 px around the worst pixel, magnified 8x
    REPORT/cases/<case>/flip.png          FLIP error map (with flip-evaluator installed)
    REPORT/cases/<case>/*_thumb.png       reduced mask / difference that keep single pixels

``<case>`` is the case name when it matches ``[a-z0-9][a-z0-9._-]*`` (a second case of the same
name gets ``<case>-2``), else ``case-<i>``: whatever a kit names its cases, the report writes only
inside the report directory. The pages link to the kit's ``<case>/case.json`` by relative URLs
(so the report may live outside the kit), and read only ``KIT/<case>/case.json`` of such names,
as the check reads a kit (inside it, a regular file, size- and depth-limited JSON).

The error mask follows the Vulkan CTS image comparisons (green where a pixel passes, red where
it fails) with the pixel verdict that decides the case (the position-tolerant compare); pixels
that pass and where both images show the case's background colour (within the threshold: the
images carry no coverage, so a surface of exactly that colour is black too) are black. G-buffer
cases show a gray preview of one channel (``depth`` when present, normalised by the expected
range) and a mask over all channels.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from .._reading import inside, read_regular
from ..image import atomic_file, write_png_atomic
from . import limits
from ._json import load_json
from .check import CaseCheck, Visual, case_style, valid_case_name
from .diagnose import (
    diff_scale,
    diverging_rgb,
    flip_error,
    magnified_crop,
    mask_rgb,
    pool_factor,
    pooled_diff,
    pooled_mask,
    signed_diff,
    signed_diff_heatmap,
    tolerance_margin,
    worst_pixels,
)
from .report_page import CaseRecord, Picture, case_page, index_page

__all__ = ["THUMB", "error_mask", "write_report"]

#: The thumbnail box of the index (px): longer sides are reduced by an integer factor to fit,
#: shorter ones magnified by one (up to 8x).
THUMB = 176

#: Worst pixels kept per case (the index shows 5, the case page all).
WORST_COUNT = 10


def error_mask(bad: np.ndarray, empty: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 3) uint8 error mask: red where ``bad``, black where ``empty`` (and not bad),
    green elsewhere.

    Parameters
    ----------
    bad : (H, W) bool
        Pixels that fail.
    empty : (H, W) bool, optional
        Pixels where both images show the background.
    """
    return mask_rgb(bad, empty)


def _rgb8(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.shape[2] < 3:
        a = np.repeat(a[..., :1], 3, axis=-1)
    return np.rint(np.clip(np.nan_to_num(a[..., :3]), 0.0, 1.0) * 255.0).astype(np.uint8)


def _group(check: CaseCheck) -> str:
    if check.status in ("missing", "skipped"):
        return "missing"
    if check.status == "kit":
        return "kit"
    return "pass" if check.passed else "fail"


def _folder(name: str, index: int, used: set[str]) -> str:
    base = name if valid_case_name(name) else f"case-{index}"
    folder, k = base, 2
    while folder in used:
        folder, k = f"{base}-{k}", k + 1
    used.add(folder)
    return folder


def _inside(root: Path, rel: str) -> Path | None:
    """``root/rel`` resolved when it exists inside ``root`` (resolved), else None."""
    try:
        p = inside(root, rel, what=rel, root_name="the directory")
    except ValueError:
        return None
    return p if p.exists() else None


def _rel_url(target: Path, start: Path) -> str | None:
    try:
        return os.path.relpath(target, start).replace(os.sep, "/")
    except ValueError:  # another drive
        return None


def _read_case_json(kit_root: Path, name: str) -> tuple[Path | None, dict[str, Any] | None, str]:
    """(path, data, why not): ``KIT/<name>/case.json`` read as the check reads an untrusted
    kit (inside the kit, a regular file, size- and depth-limited JSON); ``path`` is set when
    it is a regular file inside the kit, even if it does not parse."""
    if not valid_case_name(name):
        return None, None, "the case name is not a valid kit name; case.json was not read"
    what = f"kit file {name + '/case.json'!r}"
    try:
        path = inside(kit_root, f"{name}/case.json", what=what, root_name="the kit")
    except ValueError as exc:
        return None, None, str(exc)
    try:
        raw = read_regular(path, what=what, max_bytes=limits.MAX_JSON_BYTES)
    except ValueError as exc:
        return None, None, str(exc)
    try:
        data = load_json(raw, what=what, max_depth=limits.MAX_JSON_DEPTH)
    except ValueError as exc:
        return path, None, str(exc)
    if not isinstance(data, dict):
        return path, None, f"{what} is not a JSON object"
    return path, data, ""


def _style(check: CaseCheck, info: dict[str, Any] | None) -> str:
    style = getattr(check, "style", None) or (case_style(info) if info else None)
    if style is None and check.kind == "gbuffer":
        style = "gbuffer"
    return style if isinstance(style, str) and style else "?"


def _links(
    name: str, case_json: Path | None, renders_root: Path | None, root: Path
) -> dict[str, str]:
    """Relative URLs from the report directory to the case's files in the kit and renders."""
    links: dict[str, str] = {}
    if case_json is not None:
        for key, target in (("case.json", case_json), ("kit folder", case_json.parent)):
            url = _rel_url(target, root)
            if url is not None:
                links[key] = url + ("/" if key == "kit folder" else "")
    if renders_root is not None and valid_case_name(name):
        for rel in (f"{name}.png", name):
            p = _inside(renders_root, rel)
            if p is not None and (p.is_file() or p.is_dir()):
                url = _rel_url(p, root)
                if url is not None:
                    links["render"] = url + ("/" if p.is_dir() else "")
                break
    return links


class _Writer:
    """Writes one case's PNGs into ``cases/<folder>/`` and collects its :class:`Picture` s."""

    def __init__(self, root: Path, folder: str) -> None:
        self.root, self.folder = root, folder
        self.pictures: list[Picture] = []
        self.images: dict[str, str] = {}
        directory = root / "cases" / folder
        directory.mkdir(parents=True, exist_ok=True)
        if not directory.resolve().is_relative_to(root):
            raise ValueError(
                f"report_dir: {str(directory)!r} resolves outside the report directory "
                f"{str(root)!r} (a symlink?); remove it or choose another report directory"
            )

    def _png(self, name: str, pixels: np.ndarray) -> str:
        rel = f"cases/{self.folder}/{name}.png"
        write_png_atomic(self.root / rel, pixels)
        return rel

    def add(
        self,
        key: str,
        caption: str,
        pixels: np.ndarray,
        *,
        reduced: np.ndarray | None = None,
        display: tuple[int, int] | None = None,
    ) -> None:
        """Write ``pixels`` (full size) and, when it is larger than the thumbnail box,
        ``reduced`` (a thumbnail file; else the browser reduces the full image smoothly).
        ``display`` overrides the thumbnail's size (width, height)."""
        src = self._png(key, pixels)
        self.images[key] = src
        h, w = pixels.shape[:2]
        f = pool_factor(pixels.shape, THUMB)
        if display is not None:
            thumb, (tw, th), px = src, display, True
        elif f == 1:
            z = max(1, min(8, THUMB // max(h, w)))
            thumb, tw, th, px = src, w * z, h * z, True
        elif reduced is not None:
            thumb, px = self._png(f"{key}_thumb", reduced), True
            th, tw = reduced.shape[:2]
        else:
            thumb, tw, th, px = src, -(-w // f), -(-h // f), False
        self.pictures.append(Picture(key, caption, src, w, h, thumb, tw, th, px))


def _draw(rec: CaseRecord, vis: Visual, writer: _Writer) -> None:
    """Compute and write everything the pages show of a case's arrays."""
    check = rec.check
    ref, res = vis.reference, vis.result
    gray = check.kind == "gbuffer"
    if ref is not None:
        writer.add("reference", f"reference ({vis.label})" if gray else "reference", _rgb8(ref))
    if res is None or ref is None or np.shape(ref) != np.shape(res):
        return
    writer.add("result", "result", _rgb8(res))
    a = ref[..., :1] if gray else ref  # a gray preview: one channel
    b = res[..., :1] if gray else res
    h, w = a.shape[:2]
    bad = vis.bad if vis.bad is not None and np.shape(vis.bad) == (h, w) else None
    empty = vis.empty if vis.empty is not None and np.shape(vis.empty) == (h, w) else None
    rec.scale = diff_scale(float(np.abs(np.nan_to_num(b - a)).max()))
    f = pool_factor(a.shape, THUMB)
    signed = signed_diff(a, b)
    reduced = None
    if f > 1:
        reduced = diverging_rgb(pooled_diff(signed, f) / rec.scale)
    writer.add(
        "diff",
        "signed difference",
        signed_diff_heatmap(a, b, scale=rec.scale),
        reduced=reduced,
    )
    if not gray:
        writer.add(
            "diff_channels",
            "signed difference per channel: R, G / B, A",
            signed_diff_heatmap(a, b, scale=rec.scale, per_channel=True),
        )
    if bad is not None:
        writer.add(
            "mask",
            "mask",
            mask_rgb(bad, empty),
            reduced=pooled_mask(bad, empty, f) if f > 1 else None,
        )
    rec.worst = worst_pixels(a, b, bad=bad, count=WORST_COUNT)
    if rec.worst:
        top = rec.worst[0]
        crop, (rows, cols) = magnified_crop(
            a, b, x=top.x, y=top.y, scale=rec.scale, bad=bad, empty=empty
        )
        rec.crop = f"x {cols.start}-{cols.stop - 1}, y {rows.start}-{rows.stop - 1}"
        writer.add(
            "crop",
            "worst region: reference | result | difference | mask",
            crop,
            display=(crop.shape[1] // 2, crop.shape[0] // 2),
        )
    t = check.tolerance.get("threshold")
    if not gray and isinstance(t, (int, float)) and not isinstance(t, bool):
        rec.threshold = float(t)
    if not gray and check.status == "ok":
        rec.margin = tolerance_margin(ref, res, check.tolerance, ssim=check.metrics.get("ssim"))
        rec.flip = flip_error(ref, res)
        if rec.flip.error_map is not None:
            writer.add("flip", f"FLIP error map (mean {rec.flip.mean:.4f})", rec.flip.error_map)
            rec.flip = replace(rec.flip, error_map=None)  # the record keeps no full-size array


def write_report(
    report_dir: Path,
    cases: Iterable[tuple[CaseCheck, Visual]],
    *,
    kit_dir: Path,
    renders_dir: Path,
) -> list[CaseCheck]:
    """Write the case files and pages and ``index.html``; return the checks with ``images``
    filled.

    ``cases`` is consumed once, in order, and each case's files are written before the next is
    drawn; nothing keeps a case's arrays afterwards (a generator of cases holds one at a time).

    Parameters
    ----------
    report_dir : path
        Created if missing (a file there is a ValueError).
    cases : iterable of (CaseCheck, Visual)
        The verdicts and what :func:`refnpr.kit.check.check_kit` kept to draw.
    kit_dir, renders_dir : path
        Shown at the top of the page; the pages link to the case's files in them.

    Returns
    -------
    list of CaseCheck
        In the order of ``cases``, each with ``images``: report files (relative to
        ``report_dir``) keyed ``reference``, ``result``, ``diff``, ``diff_channels``, ``mask``,
        ``crop``, ``flip``, as far as the case got.
    """
    report_dir = Path(report_dir)
    if report_dir.exists() and not report_dir.is_dir():
        raise ValueError(f"report_dir: {str(report_dir)!r} is a file; expected a directory")
    report_dir.mkdir(parents=True, exist_ok=True)
    root = report_dir.resolve()
    kit_root = Path(kit_dir).resolve()
    renders_root = Path(renders_dir).resolve() if Path(renders_dir).is_dir() else None
    used: set[str] = set()
    records: list[CaseRecord] = []
    for i, (check, vis) in enumerate(cases):
        folder = _folder(check.name, i, used)
        case_json, info, why = _read_case_json(kit_root, check.name)
        rec = CaseRecord(
            check=check,
            folder=folder,
            group=_group(check),
            style=_style(check, info),
            label=vis.label,
            links=_links(check.name, case_json, renders_root, root),
        )
        writer = _Writer(root, folder)
        _draw(rec, vis, writer)
        rec.check = replace(check, images=writer.images)
        rec.pictures = writer.pictures
        page = case_page(rec, info, note=why)
        with atomic_file(root / "cases" / folder / "case.html", suffix=".html") as tmp:
            tmp.write_text(page, encoding="utf-8")
        del vis, info
        records.append(rec)
    page = index_page(records, kit_dir=str(kit_dir), renders_dir=str(renders_dir))
    with atomic_file(report_dir / "index.html", suffix=".html") as tmp:
        tmp.write_text(page, encoding="utf-8")
    return [r.check for r in records]
