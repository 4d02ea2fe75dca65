"""The ``kit check`` HTML report opens in a real browser (headless Chromium).

Chromium is Debian's ``chromium`` package, installed by ``.ci/setup``. Without it these tests
FAIL (never skip): the report is a deliverable and must be seen to render.

The kit here is hand-made (48 x 32 images): a passing case, a failing one with a planted worst
pixel, a missing render, and a case whose own tolerance is broken (a kit error); the report is
written outside the kit, so its links into the kit are relative paths that leave the report.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urljoin, urlparse

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.kit.check import check_kit
from refnpr.kit.report import THUMB

W, H = 48, 32
#: The planted worst pixel of "beta-tinted": (x, y) and its RGBA in the render.
WORST_XY = (37, 5)
WORST_RGBA = (10, 20, 30, 255)


def _chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    pytest.fail(
        "chromium is not installed, so the kit check report cannot be opened in a browser: "
        "run .ci/setup (it installs Debian's chromium package)"
    )


def _browser(tmp_path: Path, url: str, *extra: str) -> subprocess.CompletedProcess:
    cmd = [
        _chromium(),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--hide-scrollbars",
        "--force-device-scale-factor=1",
        "--force-color-profile=srgb",
        f"--user-data-dir={tmp_path / 'chromium-profile'}",
        *extra,
        url,
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, f"chromium failed ({proc.returncode}): {proc.stderr[-2000:]}"
    return proc


def _colours() -> np.ndarray:
    """(H, W, 4) uint8 opaque image in which every pixel has its own colour."""
    y, x = np.mgrid[0:H, 0:W]
    return np.stack([x * 5, y * 7, np.full_like(x, 200), np.full_like(x, 255)], -1).astype(np.uint8)


def _case(root: Path, name: str, png: np.ndarray, style: str, **tolerance) -> dict:
    d = root / name
    d.mkdir(parents=True)
    iio.imwrite(d / "expected.png", png)
    case = {
        "name": name,
        "kind": "image",
        "width": W,
        "height": H,
        "spp": 1,
        "background": [1.0, 1.0, 1.0, 1.0],
        "style": {"name": style, "params": {"n": 3}},
        "expected": {"png": "expected.png", "linear": "expected.exr"},
        "tolerance": {
            "threshold": 2 / 255,
            "max_frac_over": 0.0005,
            "min_ssim": 0.995,
            "position_deviation": 1,
            **tolerance,
        },
        "derived": {"toon_shading": f"the rule of {name}: I = <b>n.l</b> & more"},
    }
    (d / "case.json").write_text(json.dumps(case))
    return {"name": name, "kind": "image", "style": style, "case": f"{name}/case.json"}


@pytest.fixture
def report(tmp_path: Path) -> tuple[Path, Path, dict]:
    kit, renders = tmp_path / "kit", tmp_path / "renders"
    kit.mkdir()
    renders.mkdir()
    good = _colours()
    other = np.full((H, W, 4), 255, np.uint8)
    other[8:24, 10:30, :3] = (40, 90, 160)
    cases = [
        _case(kit, "alpha-good", good, "smooth"),
        _case(kit, "beta-tinted", other, "toon"),
        _case(kit, "gamma-missing", other, "toon"),
        _case(kit, "delta-broken", other, "halftone", max_frac_over="auto"),
    ]
    (kit / "index.json").write_text(
        json.dumps({"format": "refnpr-kit", "version": 1, "refnpr": "test", "cases": cases})
    )
    iio.imwrite(renders / "alpha-good.png", good)
    tinted = other.copy()
    tinted[8:24, 10:30, 0] = 80  # 40 levels off: fails, but less than the planted pixel
    tinted[WORST_XY[1], WORST_XY[0]] = WORST_RGBA
    iio.imwrite(renders / "beta-tinted.png", tinted)
    iio.imwrite(renders / "delta-broken.png", other)
    out = tmp_path / "out" / "report"  # not inside the kit
    results = {r.name: r for r in check_kit(kit, renders, report_dir=out)}
    assert {n: r.passed for n, r in results.items()} == {
        "alpha-good": True,
        "beta-tinted": False,
        "gamma-missing": False,
        "delta-broken": False,
    }
    assert results["delta-broken"].status == "kit"
    return out, kit, results


class _Tags(HTMLParser):
    """Every start tag as (tag, attrs dict), and the text of each <tr> of each <tbody>."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.rows: list[tuple[str | None, dict[str, str | None], list[str]]] = []
        self._tbody: str | None = None
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append((tag, a))
        if tag == "tbody" and "data-name" in a:  # a case (the DOM adds plain ones to tables)
            self._tbody = a["data-name"]
        elif tag == "tr":
            self.rows.append((self._tbody, a, []))
        elif tag == "td":
            self._cell = []

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None and self.rows:
            self.rows[-1][2].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _parse(page: str) -> _Tags:
    p = _Tags()
    p.feed(page)
    return p


def _case_bodies(dom: str) -> dict[str, dict]:
    """data-name -> attributes of each case's <tbody>."""
    return {a["data-name"]: a for t, a in _parse(dom).tags if t == "tbody" and "data-name" in a}


def _find_block(shot: np.ndarray, block: np.ndarray) -> list[tuple[int, int]]:
    """Top-left corners where ``block`` (h, w, 3) appears exactly in ``shot``."""
    h, w = block.shape[:2]
    ys, xs = np.nonzero(np.all(shot == block[h // 2, w // 2], axis=-1))
    hits = []
    for y, x in zip(ys - h // 2, xs - w // 2, strict=True):
        if y >= 0 and x >= 0 and y + h <= shot.shape[0] and x + w <= shot.shape[1]:
            if np.array_equal(shot[y : y + h, x : x + w], block):
                hits.append((int(y), int(x)))
    return hits


def test_report_renders_at_1280_px_with_magnified_thumbnails(report, tmp_path):
    out, _, results = report
    shot_path = tmp_path / "shot.png"
    _browser(
        tmp_path,
        (out / "index.html").resolve().as_uri(),
        f"--screenshot={shot_path}",
        "--window-size=1280,2400",
    )
    shot = iio.imread(shot_path)[..., :3]
    assert shot.shape[:2] == (2400, 1280)
    assert len(np.unique(shot.reshape(-1, 3), axis=0)) > 300  # a page, not a blank frame
    # the passing case's reference and result appear magnified by whole pixels, side by side
    zoom = THUMB // W
    ref = iio.imread(out / results["alpha-good"].images["reference"])
    big = np.repeat(np.repeat(ref, zoom, axis=0), zoom, axis=1)
    hits = _find_block(shot, big)
    assert len(hits) == 2, f"expected the reference and result thumbnails, found {hits}"
    assert hits[0][0] == hits[1][0] and hits[0][1] < hits[1][1]
    # the failing case's mask shows its red pixels, magnified the same way
    mask = iio.imread(out / results["beta-tinted"].images["mask"])
    n_red = int(np.all(mask == [255, 0, 0], axis=-1).sum())
    assert n_red > 0
    assert int(np.all(shot == [255, 0, 0], axis=-1).sum()) >= n_red * zoom * zoom
    # the worst-region crop is on the page: its worst pixel framed in yellow
    assert np.all(shot == [255, 230, 0], axis=-1).sum() > 0


def test_report_has_no_horizontal_overflow_at_1280_px(report, tmp_path):
    out, _, _ = report
    frame = tmp_path / "frame.html"
    frame.write_text(
        f"""<!doctype html><html><body style="margin:0">
<iframe id="f" src="{(out / "index.html").resolve().as_uri()}"
 style="width:1280px;height:1000px;border:0"></iframe>
<script>
window.addEventListener("load", function () {{
  var d = document.getElementById("f").contentDocument, right = 0;
  d.querySelectorAll("body *").forEach(function (e) {{
    var r = e.getBoundingClientRect();
    if (r.width > 0) right = Math.max(right, r.right);
  }});
  var s = document.createElement("pre");
  s.id = "measure";
  s.textContent = JSON.stringify({{scroll: d.documentElement.scrollWidth,
    client: d.documentElement.clientWidth, right: right,
    images: d.images.length, loaded: Array.prototype.every.call(d.images,
      function (i) {{ return i.complete && i.naturalWidth > 0; }})}});
  document.body.appendChild(s);
}});
</script></body></html>"""
    )
    dom = _browser(
        tmp_path,
        frame.as_uri(),
        "--dump-dom",
        "--allow-file-access-from-files",
        "--virtual-time-budget=5000",
    ).stdout
    m = re.search(r'<pre id="measure">(.*?)</pre>', dom)
    assert m, f"the measuring script did not run: {dom[-500:]}"
    got = json.loads(m.group(1).replace("&quot;", '"'))
    assert got["images"] >= 9 and got["loaded"], got  # every thumbnail loaded
    assert got["client"] == 1280, got
    assert got["scroll"] <= 1280 and got["right"] <= 1280, got


def test_worst_pixel_table_lists_the_planted_pixel(report, tmp_path):
    out, _, _ = report
    dom = _browser(tmp_path, (out / "index.html").resolve().as_uri(), "--dump-dom").stdout
    rows = [
        (a, cells) for case, a, cells in _parse(dom).rows if case == "beta-tinted" and "data-x" in a
    ]
    assert rows, "no worst-pixel rows for the failing case"
    first, cells = rows[0]
    assert (int(first["data-x"]), int(first["data-y"])) == WORST_XY
    x, y, verdict, d, ref8, res8, ref_lin, res_lin = cells
    assert (int(x), int(y)) == WORST_XY and verdict == "fails"
    assert int(d) == 255 - WORST_RGBA[0]  # largest channel difference, in 8-bit levels
    assert ref8 == "255 255 255 255" and res8 == " ".join(map(str, WORST_RGBA))

    def linear(v: int) -> float:  # IEC 61966-2-1
        c = v / 255
        return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4

    assert ref_lin == "1.0000 1.0000 1.0000 1.0000"
    assert [float(v) for v in res_lin.split()] == pytest.approx(
        [linear(v) for v in WORST_RGBA[:3]] + [1.0], abs=6e-5
    )
    # the tinted block's pixels follow, all failing, all less different
    assert all(c[2] == "fails" and int(c[3]) == 40 for _, c in rows[1:])


def test_filters_hide_and_show_cases(report, tmp_path):
    out, _, _ = report
    url = (out / "index.html").resolve().as_uri()

    def visible(hash_: str) -> set[str]:
        dom = _browser(tmp_path, url + hash_, "--dump-dom").stdout
        return {n for n, a in _case_bodies(dom).items() if "hidden" not in a}

    everything = {"alpha-good", "beta-tinted", "gamma-missing", "delta-broken"}
    assert visible("") == everything
    assert visible("#status=fail") == {"beta-tinted"}
    assert visible("#status=kit") == {"delta-broken"}
    assert visible("#status=missing") == {"gamma-missing"}
    assert visible("#status=pass,missing") == {"alpha-good", "gamma-missing"}
    assert visible("#style=toon") == {"beta-tinted", "gamma-missing"}
    assert visible("#style=toon,smooth&status=fail,pass") == {"alpha-good", "beta-tinted"}
    dom = _browser(tmp_path, url + "#style=halftone", "--dump-dom").stdout
    assert "1 of 4 cases shown" in dom


def test_failing_cases_first_missing_apart_last_and_sorting(report, tmp_path):
    out, _, results = report
    url = (out / "index.html").resolve().as_uri()
    dom = _browser(tmp_path, url, "--dump-dom").stdout
    order = [n for n, a in _case_bodies(dom).items()]
    assert order == ["beta-tinted", "delta-broken", "alpha-good", "gamma-missing"]
    assert dom.index('id="missing"') < dom.index('data-name="gamma-missing"')
    dom = _browser(tmp_path, url + "#sort=name", "--dump-dom").stdout
    assert 'data-sorted="name"' in dom  # the inline script ran
    order = [n for n in _case_bodies(dom) if n != "gamma-missing"]
    assert order == ["alpha-good", "beta-tinted", "delta-broken"]
    dom = _browser(tmp_path, url + "#sort=-error", "--dump-dom").stdout
    order = [n for n in _case_bodies(dom) if n != "gamma-missing"]
    compared = [results[n] for n in order]
    assert [r.error for r in compared] == sorted((r.error for r in compared), reverse=True)


def _local_links(page: Path, dom: str) -> list[tuple[str, Path]]:
    """(attribute value, file) of every href/src that is not a fragment of the page itself."""
    base = page.resolve().as_uri()
    out = []
    for _, a in _parse(dom).tags:
        for key in ("href", "src"):
            v = a.get(key)
            if v and not v.startswith("#"):
                u = urlparse(urljoin(base, v))
                assert u.scheme == "file", f"{page.name}: {v!r} leaves the disk"
                out.append((v, Path(unquote(u.path))))
    return out


def test_links_resolve_to_existing_files_in_the_report_and_the_kit(report, tmp_path):
    out, kit, _ = report
    dom = _browser(tmp_path, (out / "index.html").resolve().as_uri(), "--dump-dom").stdout
    links = _local_links(out / "index.html", dom)
    assert len(links) > 20
    missing = [v for v, p in links if not p.exists()]
    assert not missing, f"links to nothing: {missing}"
    case_json = [p for v, p in links if v.endswith("beta-tinted/case.json")]
    assert case_json and case_json[0].samefile(kit / "beta-tinted" / "case.json")
    assert all(not v.startswith("/") for v, _ in links)  # relative: the report can move
    # the case page: its own links, the derived text escaped, the full-size views pixelated
    page = out / "cases" / "beta-tinted" / "case.html"
    dom = _browser(tmp_path, page.resolve().as_uri(), "--dump-dom").stdout
    links = _local_links(page, dom)
    assert not [v for v, p in links if not p.exists()]
    assert any(p.samefile(kit / "beta-tinted" / "case.json") for _, p in links if p.is_file())
    assert "I = &lt;b&gt;n.l&lt;/b&gt; &amp; more" in dom and "<b>n.l</b>" not in dom
    full = [a for t, a in _parse(dom).tags if t == "img" and a.get("src") == "mask.png"]
    assert full and full[0]["class"] == "px" and int(full[0]["width"]) == W * 8


def test_without_chromium_the_tests_fail_with_the_setup_hint(monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(pytest.fail.Exception, match=r"chromium is not installed.*run \.ci/setup"):
        _chromium()
