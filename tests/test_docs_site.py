"""The documentation site (docs/conf.py) builds with warnings as errors and opens in a browser.

One build (the documented command, into a temporary directory) serves every test here; the
pages are read back through headless Chromium (Debian's ``chromium``, installed by
``.ci/setup``), so what is checked is the DOM a reader gets. Without Sphinx (the extra
``docs``) or Chromium these tests FAIL: the site is a deliverable.
"""

from __future__ import annotations

import inspect
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import refnpr

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.slow


def _chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    pytest.fail("chromium is not installed: run .ci/setup (it installs Debian's chromium)")


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("docs")
    html = tmp / "html"
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-q", "-b", "html"]
    cmd += ["-d", str(tmp / "doctrees"), str(ROOT / "docs"), str(html)]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert proc.returncode == 0, (
        f"the documentation site does not build ({proc.returncode}):\n{proc.stderr[-6000:]}"
    )
    return html


def _dom(site: Path, page: str, tmp_path: Path) -> str:
    """The page's DOM after Chromium loaded it (scripts run)."""
    path = site / page
    assert path.is_file(), f"{page} was not built"
    cmd = [
        _chromium(),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        f"--user-data-dir={tmp_path / 'chromium-profile'}",
        "--dump-dom",
        path.resolve().as_uri(),
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, f"chromium failed ({proc.returncode}): {proc.stderr[-2000:]}"
    assert "<body" in proc.stdout, f"chromium returned no page for {page}"
    return proc.stdout


def test_index_links_every_part(site, tmp_path):
    dom = _dom(site, "index.html", tmp_path)
    assert "<title>refnpr" in dom
    for href in ("veryovka.html", "_generated/notebooks/veryovka.html", "gallery.html"):
        assert f'href="{href}' in dom, href
    assert 'href="cli.html' in dom and 'href="api.html' in dom


def test_api_page_of_render_lists_its_parameters(site, tmp_path):
    dom = _dom(site, "_generated/api/refnpr.render.html", tmp_path)
    assert 'id="refnpr.render.render"' in dom
    section = dom.split('id="refnpr.render.render"', 1)[1].split('<dl class="py ', 1)[0]
    section = section.split("Parameters", 1)[1].split("Returns", 1)[0]
    listed = {
        n.strip() for s in re.findall(r"<strong>([^<]+)</strong>", section) for n in s.split(",")
    }
    for name in inspect.signature(refnpr.render).parameters:
        assert name in listed, f"parameter {name} is not documented (listed: {sorted(listed)})"


def test_cli_page_lists_kit_check(site, tmp_path):
    dom = _dom(site, "cli.html", tmp_path)
    assert 'id="refnpr-kit-check"' in dom
    assert "kit check" in dom and "--report" in dom


def test_paper_and_notebook_pages_render(site, tmp_path):
    paper = _dom(site, "veryovka.html", tmp_path)
    assert "Threshold textures (Veryovka 2002)" in paper
    assert paper.count("<img") >= 5  # the paper's figures beside the renders
    notebook = _dom(site, "_generated/notebooks/veryovka.html", tmp_path)
    assert "Animation with threshold textures" in notebook
    assert "<img" in notebook  # a stored output (plots are PNG outputs of the notebook)
    gallery = _dom(site, "gallery.html", tmp_path)
    from refnpr.gallery import GALLERY

    assert gallery.count("<img") >= len(GALLERY)


def test_everyday_names_resolve_and_are_documented(site):
    from sphinx.util.inventory import InventoryFile

    with open(site / "objects.inv", "rb") as f:
        inventory = InventoryFile.load(f, "", lambda base, uri: uri)
    documented = {name for entries in inventory.values() for name in entries}
    root_page = (site / "_generated/api/refnpr.html").read_text(encoding="utf-8")
    assert "refnpr.__version__" in documented
    for name in refnpr.__all__:
        obj = getattr(refnpr, name)  # resolves
        if name == "__version__":
            continue
        canonical = f"{obj.__module__}.{obj.__qualname__}"
        assert canonical in documented, f"refnpr.{name} ({canonical}) is not in the API reference"
        assert f'href="{canonical.rsplit(".", 1)[0]}.html#{canonical}"' in root_page or (
            f'href="#{canonical}"' in root_page
        ), f"the page of refnpr does not link {name}"


def test_every_module_page_is_reached_from_the_root_page(site):
    """The module pages are outside the site's toctree: each package page's table of modules
    links them, so every page must be reached by following those links from ``refnpr``."""
    api = site / "_generated" / "api"
    pages = {p.name for p in api.glob("refnpr*.html")}
    seen, todo = set(), ["refnpr.html"]
    while todo:
        page = todo.pop()
        if page in seen:
            continue
        seen.add(page)
        html = (api / page).read_text(encoding="utf-8")
        todo += [h for h in re.findall(r'href="(refnpr[\w.]*\.html)[#"]', html) if h in pages]
    assert len(pages) > 100 and seen == pages, sorted(pages - seen)


#: Docstrings nobody wrote: Python's for a NamedTuple's fields and ``__new__``, and those of the
#: built-in types, shown for constants without a doc comment.
GENERATED_DOCSTRINGS = [
    "Alias for field number",
    "Create new instance of",
    "int([x]) -&gt; integer",
    "str(object=&#39;&#39;)",
    "Built-in immutable sequence",
    "dict() -&gt; new empty dictionary",
    "Convert a string or number to a floating point number",
    "Build an immutable unordered collection",
]


def test_api_pages_hold_no_generated_docstrings(site):
    found = [
        f"{page.name}: {text}"
        for page in sorted((site / "_generated" / "api").glob("*.html"))
        for text in GENERATED_DOCSTRINGS
        if text in page.read_text(encoding="utf-8")
    ]
    assert not found, found


def test_import_refnpr_stays_lazy():
    code = "import sys, refnpr; print(sorted(m for m in sys.modules if m.startswith('refnpr.')))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", f"import refnpr imported {out.stdout.strip()}"


def test_render_is_the_function_whatever_was_imported_first():
    code = (
        "import refnpr.render, refnpr.explore, refnpr.sequence, refnpr; "
        "from refnpr.render import render; from refnpr.explore import explore; "
        "print(refnpr.render is render, refnpr.explore is explore)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "True"]
