"""The HTML of the ``kit check`` report: ``index.html`` and one page per case.

Everything from a kit, a render or a check (names, messages, styles, parameters, derived texts)
is escaped here: HTML-escaped, control characters written as ``\\xNN``. Pages use inline CSS and
a few lines of inline JavaScript, nothing from the network, and fit a 1,280 px wide window.
"""

from __future__ import annotations

import html
import json
import math
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import quote

from .._reading import printable
from .check import CaseCheck
from .diagnose import DIVERGING, Flip, Margin, WorstPixel, straight_linear, straight_srgb

__all__ = ["CaseRecord", "Picture", "case_page", "index_page"]

#: Status groups of the report, in page order (missing cases are listed apart, last).
GROUPS = {"fail": "fail", "kit": "kit error", "pass": "pass", "missing": "missing"}

#: The heatmaps' colour map as CSS gradient stops (piecewise linear in sRGB, as drawn).
_GRADIENT = ", ".join(f"rgb{c} {50 * (t + 1):g}%" for t, c in DIVERGING)


def text(s: object, *, lines: bool = False) -> str:
    """``s`` as HTML text: non-printable characters as Python escapes (``\\x1b``), then
    HTML-escaped (quotes too); ``lines`` keeps line feeds (for ``<pre>`` blocks)."""
    if lines:
        return "\n".join(text(part) for part in str(s).split("\n"))
    return html.escape(printable(s), quote=True)


def href(url: str) -> str:
    """A relative URL (``/``-separated path) quoted for an attribute."""
    return html.escape(quote(url, safe="/#"), quote=True)


@dataclass(frozen=True)
class Picture:
    """One image of a case as the page shows it.

    Attributes
    ----------
    key, caption : str
        Its ``CaseCheck.images`` key and caption.
    src : str
        The full-size file, relative to the report directory.
    width, height : int
        Its size in pixels.
    thumb, thumb_width, thumb_height : str, int, int
        The file and size the index shows (a reduced file keeps single failing pixels).
    pixelated : bool
        The thumbnail is an integer magnification or a reduced file (drawn without smoothing).
    """

    key: str
    caption: str
    src: str
    width: int
    height: int
    thumb: str
    thumb_width: int
    thumb_height: int
    pixelated: bool


@dataclass
class CaseRecord:
    """What the pages show of one case (small: no full-size arrays).

    Attributes
    ----------
    check : CaseCheck
        The verdict, ``images`` filled.
    folder : str
        ``cases/<folder>/`` holds the case's files and its page.
    group : str
        A :data:`GROUPS` key.
    style : str
        The case's style (``case.json`` ``style.name``), ``"G-buffer"`` or ``"?"``.
    label : str
        What reference and result show (``Visual.label``).
    pictures : list of Picture
    worst : list of WorstPixel
    margin : Margin or None
    flip : Flip or None
    scale : float or None
        The difference heatmaps' scale.
    threshold : float or None
        The case's threshold (image cases), for the scale bar's ticks.
    crop : str
        The crop window, e.g. ``"x 100-123, y 40-63"``.
    links : dict of str to str
        ``"case.json"``, ``"kit folder"``, ``"render"``: relative URLs from the report directory.
    """

    check: CaseCheck
    folder: str
    group: str
    style: str
    label: str
    pictures: list[Picture] = field(default_factory=list)
    worst: list[WorstPixel] = field(default_factory=list)
    margin: Margin | None = None
    flip: Flip | None = None
    scale: float | None = None
    threshold: float | None = None
    crop: str = ""
    links: dict[str, str] = field(default_factory=dict)

    @property
    def picture(self) -> dict[str, Picture]:
        return {p.key: p for p in self.pictures}


# -- numbers -----------------------------------------------------------------------------------


def _k255(t: float) -> str:
    k = t * 255
    if abs(k - round(k)) < 1e-6:
        return f"{round(k)}/255 ({t:.4f})"
    return f"{t:.4g}"


def _v8(v: float) -> str:
    k = v * 255
    return str(round(k)) if abs(k - round(k)) < 1e-6 else f"{k:.1f}"


def _num(v: float | None, fmt: str) -> str:
    if v is None:
        return ""
    if math.isnan(v):  # an SSIM not computable (under 3 px), not judged
        return "n/a"
    return "inf" if not math.isfinite(v) else fmt.format(v)


def _attr(v: float | None) -> str:
    if v is None or math.isnan(v):  # sorted with the missing values
        return ""
    return "inf" if not math.isfinite(v) else repr(float(v))


# -- shared pieces -----------------------------------------------------------------------------


def _scale_bar(scale: float, threshold: float | None) -> str:
    """The diverging colour bar of a heatmap with its range in the labels."""
    ticks = ""
    if threshold is not None and 0 < threshold <= scale:
        for sign in (-1, 1):
            pos = 50 * (1 + sign * threshold / scale)
            ticks += f'<span class="tick" style="left:{pos:.2f}%"></span>'
    note = (
        f"ticks: &plusmn;threshold {text(_k255(threshold))}"
        if ticks
        else (f"threshold {text(_k255(threshold))} beyond the scale" if threshold else "")
    )
    k = round(scale * 255)
    return (
        f'<div class="scalebar" data-scale="{scale!r}"><div class="bar" '
        f'style="background:linear-gradient(to right, {_GRADIENT})">{ticks}</div>'
        f'<div class="labels"><span>&minus;{k}/255</span><span>0</span>'
        f"<span>+{k}/255</span></div>"
        f'<div class="labels"><span>result lower</span><span>higher</span></div>'
        f'<div class="note">{note}</div></div>'
    )


def worst_table(rec: CaseRecord, count: int) -> str:
    """The worst-pixel table (at most ``count`` rows)."""
    rows = rec.worst[:count]
    if not rows:
        return '<p class="none">no pixel differs</p>'
    image = rec.check.kind == "image"
    if image:
        head = (
            "<tr><th>x</th><th>y</th><th>verdict</th><th>max |d| (of 255)</th>"
            "<th>reference sRGB 0-255</th><th>result sRGB 0-255</th>"
            "<th>reference linear</th><th>result linear</th></tr>"
        )
    else:
        head = (
            "<tr><th>x</th><th>y</th><th>verdict</th><th>|d|</th>"
            f"<th>reference ({text(rec.label)})</th><th>result</th></tr>"
        )
    body = []
    for p in rows:
        cells = [str(p.x), str(p.y), "fails" if p.fails else "passes"]
        if image:
            cells.append(_v8(p.diff))
            for v in (p.reference, p.result):
                cells.append(" ".join(_v8(c) for c in straight_srgb(v)))
            for v in (p.reference, p.result):
                cells.append(" ".join(f"{c:.4f}" for c in straight_linear(v)))
        else:
            cells += [f"{p.diff:.4g}", f"{p.reference[0]:.4g}", f"{p.result[0]:.4g}"]
        tds = "".join(f"<td>{text(c)}</td>" for c in cells)
        body.append(
            f'<tr class="{"bad" if p.fails else "ok"}" data-x="{p.x}" data-y="{p.y}">{tds}</tr>'
        )
    return f'<table class="worst">{head}{"".join(body)}</table>'


def margin_table(rec: CaseRecord) -> str:
    """The tolerance margin: per criterion, the case's value and where this render passes."""
    m = rec.margin
    if m is None:
        return ""

    def row(key: str, case: str, passes: str, ok: bool) -> str:
        return (
            f'<tr class="{"ok" if ok else "bad"}" data-criterion="{key}"><td>{key}</td>'
            f"<td>{text(case)}</td><td>{text(passes)}</td></tr>"
        )

    ssim = (
        "-"
        if m.ssim is None
        else "not judged (SSIM needs 3x3 pixels)"
        if math.isnan(m.ssim)
        else f"min_ssim <= {m.ssim:.5f}"
    )
    return (
        '<table class="margin"><tr><th>criterion</th><th>case</th>'
        "<th>this render passes at</th></tr>"
        + row(
            "threshold",
            _k255(m.threshold),
            f"threshold >= {_k255(m.pass_threshold)}",
            m.pass_threshold <= m.threshold,
        )
        + row("max_frac_over", f"{m.max_frac_over:g}", f"max_frac_over >= {m.frac:.6g}", m.frac_ok)
        + row("min_ssim", f"{m.min_ssim:g}", ssim, m.ssim_ok)
        + f'<tr><td colspan="3" class="note">each with the other criteria as the case states '
        f"them; position_deviation N = {m.deviation}</td></tr></table>"
    )


def _flip_text(rec: CaseRecord) -> str:
    f = rec.flip
    if f is None:
        return ""
    if f.mean is None:
        return f'<p class="flip">FLIP: {text(f.note)}</p>'
    return f'<p class="flip">mean FLIP <b class="flip-mean">{f.mean:.5f}</b> (reported only)</p>'


def _links(rec: CaseRecord, up: str) -> str:
    """Links to the kit's files of the case (and the case page from the index)."""
    items = []
    if up == "":
        items.append(f'<a href="{href(f"cases/{rec.folder}/case.html")}">case page</a>')
    for name, url in rec.links.items():
        items.append(f'<a class="kit" href="{href(up + url)}">{text(name)}</a>')
    if up == "" and "case.json" in rec.links:
        items.append(
            f'<a href="{href(f"cases/{rec.folder}/case.html#derived")}">parameters, derived</a>'
        )
    return f'<div class="links">{" &middot; ".join(items)}</div>'


_LEGEND = """
<p id="legend-short">Mask: <span class="sw" style="background:#0f0"></span> pass
<span class="sw" style="background:#f00"></span> fail
<span class="sw" style="background:#000"></span> background (passes; both images show the
case's background colour) &middot; signed difference: <span class="sw grad"></span> blue: result
lower, near-black: equal, red: result higher (scale under each heatmap) &middot;
<span class="sw" style="background:#ffe600"></span> frame: the worst pixel</p>
<details id="legend"><summary>How to read this report</summary>
<dl>
<dt>mask</dt><dd><span class="sw" style="background:#0f0"></span> green: the pixel passes;
<span class="sw" style="background:#f00"></span> red: it fails (the position-tolerant compare that
decides the case); <span class="sw" style="background:#000"></span> black: it passes and both
images show the case's background colour (within the threshold; the images carry no coverage, so
a surface of exactly the background colour is black too). G-buffer cases: black where
<code>tri_id</code> is -1 in both, red where any channel fails.</dd>
<dt>signed difference</dt><dd>result &minus; reference on the compared values (sRGB composited
over black, alpha as a fourth channel; G-buffer cases: the normalised preview). Blue: result
lower, red: result higher, near-black: equal. The thumbnail shows per pixel the channel of
largest |difference|; its full view shows R, G / B, A apart. The scale is chosen per case (the
smallest of 1, 2, 4, ..., 128, 255 / 255 that holds the largest |difference|) and written under
each heatmap; ticks mark &plusmn; the case's threshold.</dd>
<dt>worst region</dt><dd>a 24 x 24 pixel window around the worst pixel, magnified 8x without
smoothing: reference | result | signed difference | mask; a yellow frame marks the worst
pixel.</dd>
<dt>worst pixels</dt><dd>failing pixels first, each group by largest per-channel |difference|,
ties in reading order; x to the right, y down from the top-left pixel. sRGB values are the
straight-alpha RGBA of the PNGs (0-255), linear values their IEC 61966-2-1 decoding (alpha
kept); |d| is on the compared values (colour times alpha).</dd>
<dt>tolerance margin</dt><dd>for each criterion, the value at which this render would pass with
the other two as the case states them: the smallest threshold k/255, the fraction of pixels
failing (the smallest <code>max_frac_over</code>), the SSIM (the largest
<code>min_ssim</code>).</dd>
<dt>thumbnails</dt><dd>images larger than the thumbnail box are reduced by an integer factor;
the mask and difference thumbnails keep every failing pixel (a block is red when any of its
pixels fails and shows its largest difference). Click a thumbnail for the full-size view,
magnified without smoothing.</dd>
<dt>FLIP</dt><dd>NVIDIA's perceptual difference (LDR, 67 pixels per degree) of the sRGB colours
over black, when the optional <code>flip-evaluator</code> package is installed
(<code>pip install 'refnpr[flip]'</code>): mean and error map (magma: black 0 to yellow 1).
Reported only; it never decides a case.</dd>
</dl></details>
"""

_CSS = """
* { box-sizing: border-box; }
body { background: #1e1e1e; color: #ddd; font: 13px/1.4 sans-serif; margin: 12px;
       max-width: 100%; overflow-wrap: anywhere; }
h1 { font-size: 18px; margin: 0 0 8px; } h2 { font-size: 15px; margin: 18px 0 6px; }
a { color: #8cf; }
code, .path { overflow-wrap: anywhere; }
table { border-collapse: collapse; }
th, td { border: 1px solid #444; padding: 3px 6px; vertical-align: top; text-align: left; }
table.cases { width: 100%; table-layout: fixed; }
th.sort { cursor: pointer; user-select: none; background: #2c2c2c; }
th.sort:hover { background: #3a3a3a; }
th.sort.asc::after { content: " \\25B2"; } th.sort.desc::after { content: " \\25BC"; }
td.num { text-align: right; font-family: monospace; }
td.verdict { font-weight: bold; }
tbody.pass td.verdict { color: #5d5; } tbody.fail td.verdict, tbody.kit td.verdict { color: #f55; }
tbody.missing td.verdict { color: #fb4; }
tbody.case { border-top: 3px solid #555; }
.name { font-weight: bold; word-break: break-all; }
.msg { color: #aaa; font-size: 11px; }
.links { font-size: 11px; margin-top: 2px; }
.figs { display: flex; flex-wrap: wrap; gap: 8px; align-items: flex-start; }
figure { margin: 0; max-width: 100%; }
figcaption { font-size: 10px; color: #999; max-width: 100%; }
img { display: block; max-width: 100%; height: auto; background: #000; }
img.px { image-rendering: pixelated; }
.diag { display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; margin-top: 6px; }
table.worst, table.margin { font: 11px monospace; }
table.worst td, table.margin td, table.worst th, table.margin th { padding: 1px 5px; }
tr.bad td:first-child { border-left: 3px solid #f44; } tr.ok td:first-child { border-left: 3px solid #4c4; }
.scalebar { width: 100%; font-size: 10px; color: #aaa; }
.scalebar .bar { position: relative; height: 10px; border: 1px solid #555; }
.scalebar .tick { position: absolute; top: -3px; width: 1px; height: 14px; background: #fff; }
.scalebar .labels { display: flex; justify-content: space-between; font-family: monospace; }
.note { font-size: 10px; color: #999; }
.none { color: #888; font-style: italic; }
#summary td { font-size: 16px; font-weight: bold; text-align: center; }
#filters { margin: 8px 0; display: flex; flex-wrap: wrap; gap: 6px 16px; }
#filters fieldset { border: 1px solid #444; padding: 2px 8px; margin: 0; }
#filters label { margin-right: 8px; white-space: nowrap; }
#legend dt { font-weight: bold; margin-top: 4px; } #legend dd { margin-left: 16px; color: #bbb; }
.sw { display: inline-block; width: 10px; height: 10px; border: 1px solid #777; }
.sw.grad { width: 60px; background: linear-gradient(to right, GRADIENT); }
.zoom { max-width: 100%; overflow: auto; }
.views figcaption { font-size: 12px; color: #bbb; }
.zoom img { max-width: none; }
pre { white-space: pre-wrap; overflow-wrap: anywhere; background: #262626; padding: 6px;
      font-size: 11px; }
dl.derived dt { font-weight: bold; margin-top: 6px; font-family: monospace; }
dl.derived dd { margin-left: 16px; white-space: pre-wrap; }
"""

_CSS = _CSS.replace("GRADIENT", _GRADIENT)

_JS = """
(function () {
  var table = document.getElementById("cases");
  var heads = table.querySelectorAll("th.sort");
  var boxes = document.querySelectorAll("#filters input[type=checkbox]");
  function value(body, key, type) {
    var v = body.getAttribute("data-" + key);
    if (type === "str") return v || "";
    var x = parseFloat(v);
    return isNaN(x) ? (v === "inf" ? Infinity : null) : x;
  }
  function sortBy(key, desc) {
    var th = table.querySelector('th[data-key="' + key + '"]');
    if (!th) return;
    var type = th.getAttribute("data-type");
    var bodies = Array.prototype.slice.call(table.tBodies);
    bodies.sort(function (a, b) {
      var x = value(a, key, type), y = value(b, key, type);
      if (x === null && y === null) return 0;
      if (x === null) return 1;           /* cases without the metric go last */
      if (y === null) return -1;
      var c = type === "str" ? x.localeCompare(y) : (x < y ? -1 : x > y ? 1 : 0);
      return desc ? -c : c;
    });
    bodies.forEach(function (b) { table.appendChild(b); });
    heads.forEach(function (h) { h.classList.remove("asc", "desc"); });
    th.classList.add(desc ? "desc" : "asc");
    table.setAttribute("data-sorted", (desc ? "-" : "") + key);
  }
  function chosen(kind) {
    var on = {};
    boxes.forEach(function (b) {
      if (b.getAttribute("data-filter") === kind && b.checked) on[b.value] = true;
    });
    return on;
  }
  function filter() {
    var status = chosen("status"), style = chosen("style"), shown = 0, all = 0;
    document.querySelectorAll(".case").forEach(function (c) {
      var show = !!(status[c.getAttribute("data-status")] && style[c.getAttribute("data-style")]);
      c.hidden = !show;
      all += 1; shown += show ? 1 : 0;
    });
    document.getElementById("shown").textContent = shown + " of " + all + " cases shown";
  }
  heads.forEach(function (th) {
    th.addEventListener("click", function () {
      var key = th.getAttribute("data-key");
      var desc = th.classList.contains("asc") ? true
               : th.classList.contains("desc") ? false : th.getAttribute("data-type") !== "str";
      sortBy(key, desc);
    });
  });
  boxes.forEach(function (b) { b.addEventListener("change", filter); });
  /* the address may set the view: #sort=-error&status=fail,missing&style=toon */
  window.location.hash.replace(/^#/, "").split("&").forEach(function (part) {
    var i = part.indexOf("="), k = part.slice(0, i), v = decodeURIComponent(part.slice(i + 1));
    if (k === "sort") sortBy(v.replace(/^-/, ""), v.charAt(0) === "-");
    if (k === "status" || k === "style") {
      var want = {};
      v.split(",").forEach(function (x) { want[x] = true; });
      boxes.forEach(function (b) {
        if (b.getAttribute("data-filter") === k) b.checked = !!want[b.value];
      });
    }
  });
  filter();
})();
"""

#: Sortable number columns of the index: (data key, header, format).
_COLUMNS = [
    ("error", "error", "{:.5f}"),
    ("frac_over", "frac over (N=0)", "{:.5f}"),
    ("max_abs", "max |diff|", "{:.4f}"),
    ("ssim", "SSIM", "{:.4f}"),
    ("flip", "FLIP", "{:.4f}"),
]


def _thumbs(rec: CaseRecord) -> str:
    figs = []
    for p in rec.pictures:
        if p.key == "diff_channels":  # on the case page only (the difference links to it)
            continue
        cls = "px" if p.pixelated else "smooth"
        alt = text(f"{rec.check.name}: {p.caption}")
        body = (
            f'<a href="{href(f"cases/{rec.folder}/case.html#{p.key}")}">'
            f'<img class="{cls}" src="{href(p.thumb)}" width="{p.thumb_width}" '
            f'height="{p.thumb_height}" alt="{alt}" title="{alt}"></a>'
        )
        extra = ""
        if p.key == "diff" and rec.scale is not None:
            extra = _scale_bar(rec.scale, rec.threshold)
        cap = text(p.caption + (f" ({rec.crop})" if p.key == "crop" else ""))
        if p.key == "diff" and "diff_channels" in rec.picture:
            cap += (
                f' &middot; <a href="{href(f"cases/{rec.folder}/case.html#diff_channels")}">'
                "per channel</a>"
            )
        figs.append(
            f'<figure class="fig-{p.key}" style="width:{p.thumb_width}px">{body}'
            f"<figcaption>{cap}</figcaption>{extra}</figure>"
        )
    return f'<div class="figs">{"".join(figs)}</div>' if figs else ""


def _case_body(rec: CaseRecord) -> str:
    c = rec.check
    values = {k: c.error if k == "error" else c.metrics.get(k) for k, _, _ in _COLUMNS}
    if rec.flip is not None:
        values["flip"] = rec.flip.mean
    attrs = " ".join(f'data-{k}="{_attr(v)}"' for k, v in values.items())
    nums = "".join(f'<td class="num">{_num(values[k], fmt)}</td>' for k, _, fmt in _COLUMNS)
    verdict = {"pass": "PASS", "fail": "FAIL", "kit": "KIT ERROR", "missing": "MISSING"}
    sub = f"{c.kind}, status {c.status}" + (f", {rec.label}" if c.kind == "gbuffer" else "")
    detail = ""
    if c.kind == "gbuffer" and c.channels:
        detail = "<br>".join(
            text(
                f"{ch}: {r.get('bad_pixels')} bad ({r.get('kind')}, max |d| "
                f"{_num(r.get('max_abs'), '{:.3g}')})"
            )
            for ch, r in c.channels.items()
        )
        detail = f'<div class="msg">{detail}</div>'
    diag = ""
    if rec.group != "missing" and (rec.worst or rec.margin or rec.flip):
        inner = worst_table(rec, 5) + margin_table(rec) + _flip_text(rec)
        open_ = " open" if rec.group != "pass" else ""
        diag = (
            f'<details class="diagnosis"{open_}><summary>worst pixels, tolerance margin'
            f'</summary><div class="diag">{inner}</div></details>'
        )
    more = _thumbs(rec) + diag
    return (
        f'<tbody class="case {rec.group}" id="case-{text(rec.folder)}" '
        f'data-name="{text(c.name)}" data-style="{text(rec.style)}" '
        f'data-status="{rec.group}" data-result="{int(c.passed)}" {attrs}>'
        f'<tr class="head"><td><div class="name">{text(c.name)}</div>'
        f"<small>{text(sub)}</small>"
        f'<div class="msg">{text(c.message)}</div>{detail}{_links(rec, "")}</td>'
        f"<td>{text(rec.style)}</td>"
        f'<td class="verdict">{verdict[rec.group]}</td>{nums}</tr>'
        + (f'<tr class="more"><td colspan="{3 + len(_COLUMNS)}">{more}</td></tr>' if more else "")
        + "</tbody>"
    )


def _missing_body(rec: CaseRecord) -> str:
    c = rec.check
    return (
        f'<tbody class="case missing" id="case-{text(rec.folder)}" data-name="{text(c.name)}" '
        f'data-style="{text(rec.style)}" data-status="missing">'
        f'<tr><td class="name">{text(c.name)}</td><td>{text(rec.style)}</td>'
        f'<td class="verdict">MISSING</td>'
        f'<td><div class="msg">{text(c.message)}</div>{_links(rec, "")}</td></tr></tbody>'
    )


def _checkboxes(kind: str, counts: dict[str, int], labels: dict[str, str]) -> str:
    boxes = "".join(
        f'<label><input type="checkbox" data-filter="{kind}" value="{text(k)}" checked> '
        f"{text(labels.get(k, k))} ({n})</label>"
        for k, n in counts.items()
    )
    return f'<fieldset id="filter-{kind}"><legend>{kind}</legend>{boxes}</fieldset>'


def index_page(records: list[CaseRecord], *, kit_dir: str, renders_dir: str) -> str:
    """``index.html``: summary, legend, filters, the compared cases (failing first), then the
    missing ones.

    Parameters
    ----------
    records : list of CaseRecord
        In any order; the page orders them: fail, kit error, pass (each by error, largest
        first, then name), missing apart (by name).
    kit_dir, renders_dir : str
        Shown at the top.
    """
    rank = {"fail": 0, "kit": 1, "pass": 2, "missing": 3}
    ordered = sorted(records, key=lambda r: (rank[r.group], -r.check.error, r.check.name))
    shown = [r for r in ordered if r.group != "missing"]
    missing = [r for r in ordered if r.group == "missing"]
    n = len(records)
    passed = sum(r.check.passed for r in records)
    count = {g: sum(r.group == g for r in records) for g in GROUPS}
    styles: dict[str, int] = {}
    for r in sorted(records, key=lambda r: r.style):
        styles[r.style] = styles.get(r.style, 0) + 1
    status_counts = {g: count[g] for g in GROUPS if count[g]}
    head = "".join(
        f'<th class="sort" data-key="{k}" data-type="num">{text(h)}</th>' for k, h, _ in _COLUMNS
    )
    widths = "".join(f'<col style="width:{w}px">' for w in (96, 78, 86, 86, 76, 66, 66))
    missing_html = ""
    if missing:
        missing_html = (
            f'<h2 id="missing-title">Missing renders ({len(missing)})</h2>'
            '<table class="cases" id="missing"><colgroup><col><col style="width:96px">'
            '<col style="width:78px"><col style="width:45%"></colgroup>'
            "<thead><tr><th>case</th><th>style</th><th>result</th><th>why</th></tr></thead>"
            + "".join(_missing_body(r) for r in missing)
            + "</table>"
        )
    title = f"refnpr kit check: {passed}/{n} passed"
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{text(title)}</title><style>{_CSS}</style></head>
<body>
<h1>refnpr kit check</h1>
<p>kit <code class="path">{text(kit_dir)}</code>, renders <code class="path">{text(renders_dir)}</code></p>
<table id="summary"><tr><th>cases</th><th>passed</th><th>failed</th><th>missing</th>
<th>kit errors (of the failed)</th></tr>
<tr><td id="n-cases">{n}</td><td id="n-passed">{passed}</td>
<td id="n-failed">{n - passed - count["missing"]}</td><td id="n-missing">{count["missing"]}</td>
<td id="n-kit">{count["kit"]}</td></tr></table>
<p>An image case passes when the fraction of pixels failing the position-tolerant compare
(threshold per channel on sRGB values composited over black; a pixel also matches a pixel of the
other image within N pixels, checked both ways) is at most <code>max_frac_over</code> and SSIM is at
least <code>min_ssim</code> (not judged under 3 px, where it cannot be computed: n/a). G-buffer
cases: float channels by rtol/atol, discrete channels exact except <code>max_pixels</code>.
Failing cases come first; click a header to sort.</p>
{_LEGEND}
<div id="filters">{_checkboxes("status", status_counts, GROUPS)}{_checkboxes("style", styles, {})}
<span id="shown"></span></div>
<table class="cases" id="cases"><colgroup><col>{widths}</colgroup><thead><tr>
<th class="sort" data-key="name" data-type="str">case</th>
<th class="sort" data-key="style" data-type="str">style</th>
<th class="sort" data-key="result" data-type="num">result</th>{head}</tr></thead>
{"".join(_case_body(r) for r in shown)}
</table>
{missing_html}
<script>{_JS}</script>
</body></html>
"""


def _json_block(value: Any, limit: int = 200_000) -> str:
    s = json.dumps(value, indent=1, ensure_ascii=False, allow_nan=True, default=str)
    if len(s) > limit:
        s = s[:limit] + f"\n... ({len(s) - limit} more characters: see case.json)"
    return f"<pre>{text(s, lines=True)}</pre>"


def _full_views(rec: CaseRecord) -> str:
    """Each image at a whole-pixel magnification (two side by side when they fit), linked to
    its file."""
    out = []
    for p in rec.pictures:
        zoom = max(1, min(8, 600 // max(p.width, 1), 720 // max(p.height, 1)))
        extra = ""
        if p.key in ("diff", "diff_channels") and rec.scale is not None:
            extra = _scale_bar(rec.scale, rec.threshold)
        cap = p.caption + (f" ({rec.crop})" if p.key == "crop" else "")
        file = href(p.src.rsplit("/", 1)[-1])
        out.append(
            f'<figure class="view" id="{p.key}" style="width:{p.width * zoom}px">'
            f"<figcaption>{text(cap)} ({p.width} x {p.height} px, shown {zoom}x)</figcaption>"
            f'<div class="zoom"><a href="{file}"><img class="px" src="{file}" '
            f'width="{p.width * zoom}" height="{p.height * zoom}" alt="{text(cap)}"></a></div>'
            f"{extra}</figure>"
        )
    return f'<div class="figs views">{"".join(out)}</div>'


def case_page(rec: CaseRecord, info: dict[str, Any] | None, *, note: str = "") -> str:
    """``cases/<folder>/case.html``: verdict, margin, worst pixels, full-size views magnified
    without smoothing, and the case's parameters and derived texts from ``case.json``.

    Parameters
    ----------
    rec : CaseRecord
    info : dict or None
        The parsed ``case.json`` (None when it could not be read safely; ``note`` says why).
    """
    c = rec.check
    parts = [
        f'<p><a href="../../index.html#case-{href(rec.folder)}">&larr; report</a></p>',
        f'<h1 class="name">{text(c.name)}</h1>',
        f"<p><b>{text(GROUPS[rec.group].upper())}</b> &middot; {text(c.kind)}, status "
        f'{text(c.status)} &middot; style {text(rec.style)}</p><p class="msg">{text(c.message)}</p>',
        _links(rec, "../../"),
    ]
    if rec.margin is not None:
        parts.append("<h2>Tolerance margin</h2>" + margin_table(rec))
    if rec.worst:
        parts.append("<h2>Worst pixels</h2>" + worst_table(rec, len(rec.worst)))
    if rec.flip is not None:
        parts.append("<h2>FLIP</h2>" + _flip_text(rec))
    if rec.pictures:
        parts.append("<h2>Images</h2>" + _full_views(rec))
    if info is None:
        parts.append(f'<h2 id="derived">case.json</h2><p class="none">{text(note)}</p>')
    else:
        style = info.get("style")
        derived = info.get("derived")
        parts.append('<h2 id="derived">Parameters</h2>')
        if isinstance(info.get("description"), str):
            parts.append(f"<p>{text(info['description'])}</p>")
        parts.append("<h3>style</h3>" + _json_block(style))
        parts.append("<h3>tolerance</h3>" + _json_block(info.get("tolerance")))
        parts.append("<h2>Derived texts</h2>")
        if isinstance(derived, dict) and derived:
            items = "".join(
                f'<dt id="derived-{text(k)}">{text(k)}</dt><dd>{text(v, lines=True)}</dd>'
                for k, v in derived.items()
            )
            parts.append(f'<dl class="derived">{items}</dl>')
        else:
            parts.append('<p class="none">none</p>')
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{text(c.name)}: refnpr kit check</title><style>{_CSS}</style></head>
<body>{"".join(parts)}</body></html>
"""
