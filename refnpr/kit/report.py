"""The ``refnpr kit check`` report: per-case images and one self-contained ``index.html``.

Layout of a report directory::

    REPORT/index.html                      summary (cases, passed, failed) and one row per case
    REPORT/cases/<case>/reference.png      the expected image (sRGB composited over black)
    REPORT/cases/<case>/result.png         the backend's render, the same way
    REPORT/cases/<case>/diff16.png         |result - reference| x 16 per channel (clipped)
    REPORT/cases/<case>/mask.png           error mask: green pass, red fail, black background

The error mask follows the Vulkan CTS image comparisons (green where a pixel passes, red where
it fails) with the pixel verdict that decides the case (the position-tolerant compare); pixels
that pass and where both images show the case's background colour (within the threshold: the
images carry no coverage, so a surface of exactly that colour is black too) are black. G-buffer cases show a gray preview of one
channel (``depth`` when present, normalised by the expected range) and its |diff| x 16 instead
of colours, and a mask over all channels.

The HTML page needs nothing but the PNGs beside it: inline CSS, a few lines of inline JavaScript
that sort the rows when a column header is clicked (or on load by ``#sort=KEY`` / ``#sort=-KEY``
in the address, descending with ``-``), no network.
"""

from __future__ import annotations

import html
import math
from dataclasses import replace
from pathlib import Path
from urllib.parse import quote

import numpy as np

from ..image import atomic_file, write_png_atomic
from .check import CaseCheck, Visual

__all__ = ["diff16_image", "error_mask", "render_html", "write_report"]

#: The CTS mask colours.
PASS_RGB = (0, 255, 0)
FAIL_RGB = (255, 0, 0)
EMPTY_RGB = (0, 0, 0)


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
    bad = np.asarray(bad, dtype=bool)
    if bad.ndim != 2:
        raise ValueError(f"bad: expected an (H, W) bool array, got shape {bad.shape}")
    out = np.empty(bad.shape + (3,), dtype=np.uint8)
    out[...] = PASS_RGB
    if empty is not None:
        empty = np.asarray(empty, dtype=bool)
        if empty.shape != bad.shape:
            raise ValueError(f"empty: expected shape {bad.shape} like bad, got {empty.shape}")
        out[empty] = EMPTY_RGB
    out[bad] = FAIL_RGB
    return out


def diff16_image(reference: np.ndarray, result: np.ndarray, *, gain: float = 16.0) -> np.ndarray:
    """(H, W, 3) uint8: ``clip(gain * |result - reference|)`` per colour channel, brightened by
    the alpha difference where that is larger (``max(|d_c|, |d_alpha|)``).

    Parameters
    ----------
    reference, result : (H, W, 4) float in [0, 1]
        The compared images (sRGB composited over black, alpha last).
    """
    d = np.abs(np.asarray(result, dtype=np.float64) - np.asarray(reference, dtype=np.float64))
    if d.ndim != 3 or d.shape[2] != 4:
        raise ValueError(f"reference, result: expected (H, W, 4) arrays, got {d.shape}")
    return _rgb8(np.maximum(d[..., :3], d[..., 3:4]) * gain)


def _rgb8(a: np.ndarray) -> np.ndarray:
    return np.rint(np.clip(a[..., :3], 0.0, 1.0) * 255.0).astype(np.uint8)


def write_report(
    report_dir: Path,
    cases: list[tuple[CaseCheck, Visual]],
    *,
    kit_dir: Path,
    renders_dir: Path,
) -> list[CaseCheck]:
    """Write the case images and ``index.html``; return the checks with ``images`` filled.

    Parameters
    ----------
    report_dir : path
        Created if missing (a file there is a ValueError).
    cases : list of (CaseCheck, Visual)
        The verdicts and what :func:`refnpr.kit.check.check_kit` kept to draw.
    kit_dir, renders_dir : path
        Shown at the top of the page.
    """
    report_dir = Path(report_dir)
    if report_dir.exists() and not report_dir.is_dir():
        raise ValueError(f"report_dir: {str(report_dir)!r} is a file; expected a directory")
    out = []
    for check, vis in cases:
        pictures = {}
        if vis.reference is not None:
            pictures["reference"] = _rgb8(vis.reference)
        if vis.result is not None:
            pictures["result"] = _rgb8(vis.result)
            pictures["diff16"] = diff16_image(vis.reference, vis.result)
        if vis.bad is not None:
            pictures["mask"] = error_mask(vis.bad, vis.empty)
        images = {key: f"cases/{check.name}/{key}.png" for key in pictures}
        for key, pixels in pictures.items():
            write_png_atomic(report_dir / images[key], pixels)
        out.append((replace(check, images=images), vis))
    page = render_html(out, kit_dir=kit_dir, renders_dir=renders_dir)
    with atomic_file(report_dir / "index.html", suffix=".html") as tmp:
        tmp.write_text(page, encoding="utf-8")
    return [c for c, _ in out]


_CSS = """
body { background: #1e1e1e; color: #ddd; font: 13px/1.4 sans-serif; margin: 12px; }
h1 { font-size: 18px; margin: 0 0 8px; }
table { border-collapse: collapse; }
th, td { border: 1px solid #444; padding: 3px 6px; vertical-align: top; text-align: left; }
th.sort { cursor: pointer; user-select: none; background: #2c2c2c; }
th.sort:hover { background: #3a3a3a; }
th.sort.asc::after { content: " \\25B2"; } th.sort.desc::after { content: " \\25BC"; }
td.num { text-align: right; font-family: monospace; }
tr.pass td.verdict { color: #5d5; font-weight: bold; }
tr.fail td.verdict { color: #f55; font-weight: bold; }
.msg { color: #aaa; max-width: 360px; font-size: 11px; }
td.imgs { padding: 3px; }
.strip { display: flex; gap: 6px; align-items: flex-start; }
figure { margin: 0; }
figcaption { font-size: 10px; color: #999; }
img { display: block; max-width: 256px; height: auto; image-rendering: pixelated;
      background: #000; }
.none { color: #888; font-style: italic; }
#summary td { font-size: 16px; font-weight: bold; text-align: center; }
"""

_JS = """
(function () {
  var table = document.getElementById("cases");
  var body = table.tBodies[0];
  var heads = table.querySelectorAll("th.sort");
  function value(row, key, type) {
    var v = row.getAttribute("data-" + key);
    if (type === "str") return v || "";
    var x = parseFloat(v);
    return isNaN(x) ? (v === "inf" ? Infinity : null) : x;
  }
  function sortBy(key, desc) {
    var th = table.querySelector('th[data-key="' + key + '"]');
    if (!th) return;
    var type = th.getAttribute("data-type");
    var rows = Array.prototype.slice.call(body.rows);
    rows.sort(function (a, b) {
      var x = value(a, key, type), y = value(b, key, type);
      if (x === null && y === null) return 0;
      if (x === null) return 1;           /* rows without the metric go last */
      if (y === null) return -1;
      var c = type === "str" ? x.localeCompare(y) : (x < y ? -1 : x > y ? 1 : 0);
      return desc ? -c : c;
    });
    rows.forEach(function (r) { body.appendChild(r); });
    heads.forEach(function (h) { h.classList.remove("asc", "desc"); });
    th.classList.add(desc ? "desc" : "asc");
    table.setAttribute("data-sorted", (desc ? "-" : "") + key);
  }
  heads.forEach(function (th) {
    th.addEventListener("click", function () {
      var key = th.getAttribute("data-key");
      var desc = th.classList.contains("asc") ? true
               : th.classList.contains("desc") ? false : th.getAttribute("data-type") !== "str";
      sortBy(key, desc);
    });
  });
  var m = /sort=(-?)([A-Za-z0-9_]+)/.exec(window.location.hash);
  if (m) sortBy(m[2], m[1] === "-");
})();
"""

#: Columns of the case table: (data key, header, number format).
_COLUMNS = [
    ("error", "error", "{:.5f}"),
    ("frac_over_position", "frac over (pos. tol.)", "{:.5f}"),
    ("frac_over", "frac over", "{:.5f}"),
    ("max_abs", "max |diff|", "{:.4f}"),
    ("rmse", "RMSE", "{:.5f}"),
    ("ssim", "SSIM", "{:.4f}"),
]


def _attr(x: float | None) -> str:
    if x is None:
        return ""
    if not math.isfinite(x):
        return "inf"
    return repr(float(x))


def _short(v: object) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


#: The report images of a case (``CaseCheck.images`` keys) and their captions, in order.
_STRIP = {"reference": "reference", "result": "result", "diff16": "|diff| x 16", "mask": "mask"}


def _strip(name: str, images: dict[str, str]) -> str:
    """One cell: reference | result | |diff| x 16 | mask side by side (a placeholder if absent)."""
    figs = []
    for key, caption in _STRIP.items():
        if key in images:
            src = html.escape(quote(images[key]))
            alt = html.escape(f"{name}: {caption}")
            body = f'<a href="{src}"><img src="{src}" alt="{alt}" title="{alt}"></a>'
        else:
            body = '<span class="none">none</span>'
        figs.append(f"<figure>{body}<figcaption>{html.escape(caption)}</figcaption></figure>")
    return f'<td class="imgs"><div class="strip">{"".join(figs)}</div></td>'


def render_html(cases: list[tuple[CaseCheck, Visual]], *, kit_dir: Path, renders_dir: Path) -> str:
    """The report page as a string (see the module docstring)."""
    n = len(cases)
    passed = sum(c.passed for c, _ in cases)
    esc = html.escape
    head = "".join(
        f'<th class="sort" data-key="{k}" data-type="num">{esc(h)}</th>' for k, h, _ in _COLUMNS
    )
    rows = []
    for c, vis in cases:
        values = {k: c.error if k == "error" else c.metrics.get(k) for k, _, _ in _COLUMNS}
        attrs = " ".join(f'data-{k}="{_attr(v)}"' for k, v in values.items())
        cells = []
        for (_, _, fmt), v in zip(_COLUMNS, values.values(), strict=True):
            text = "" if v is None else ("inf" if not math.isfinite(v) else fmt.format(v))
            cells.append(f'<td class="num">{text}</td>')
        detail = ""
        if c.kind == "gbuffer" and c.channels:
            detail = "<br>".join(
                f"{esc(ch)}: {r['bad_pixels']} bad ({r['kind']}, max |d| {r['max_abs']:.3g})"
                for ch, r in c.channels.items()
            )
            detail = f'<details class="msg"><summary>channels</summary>{detail}</details>'
        tol = ", ".join(
            f"{esc(str(k))}={esc(_short(v))}"
            for k, v in c.tolerance.items()
            if not isinstance(v, (dict, list))
        )
        tol_short = ", ".join(
            f"{esc(str(k))}={v:.3g}"
            for k, v in c.tolerance.items()
            if isinstance(v, (int, float)) and not isinstance(v, bool)
        )
        label = esc(vis.label) if c.kind == "gbuffer" else ""
        rows.append(
            f'<tr class="case {"pass" if c.passed else "fail"}" data-name="{esc(c.name)}" '
            f'data-result="{int(c.passed)}" {attrs}>'
            f"<td><b>{esc(c.name)}</b><br><small>{esc(c.kind)}, {esc(c.status)}"
            f"{', ' + label if label else ''}</small>"
            f'<div class="msg">{esc(c.message)}</div>{detail}'
            f'<div class="msg" title="{tol}">tolerance: {tol_short}</div></td>'
            f'<td class="verdict">{"PASS" if c.passed else "FAIL"}</td>'
            + "".join(cells)
            + _strip(c.name, c.images)
            + "</tr>"
        )
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>refnpr kit check: {passed}/{n} passed</title>
<style>{_CSS}</style></head>
<body>
<h1>refnpr kit check</h1>
<p>kit <code>{esc(str(kit_dir))}</code>, renders <code>{esc(str(renders_dir))}</code></p>
<table id="summary"><tr><th>cases</th><th>passed</th><th>failed</th></tr>
<tr><td id="n-cases">{n}</td><td id="n-passed">{passed}</td><td id="n-failed">{n - passed}</td></tr>
</table>
<p>An image case passes when the fraction of pixels failing the position-tolerant compare
(threshold per channel on sRGB values composited over black; a pixel also matches a pixel of the
other image within N pixels, checked both ways) is at most <code>max_frac_over</code> and SSIM is at
least <code>min_ssim</code>. G-buffer cases: float channels by rtol/atol, discrete channels exact
except <code>max_pixels</code>. Mask: green pass, red fail, black background. Click a header to sort.</p>
<table id="cases"><thead><tr>
<th class="sort" data-key="name" data-type="str">case</th>
<th class="sort" data-key="result" data-type="num">result</th>{head}
<th>reference | result | |diff| &times; 16 | mask</th></tr></thead>
<tbody>
{chr(10).join(rows)}
</tbody></table>
<script>{_JS}</script>
</body></html>
"""
