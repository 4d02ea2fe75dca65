"""Sphinx configuration of refnpr's documentation site.

Build (warnings are errors, cross-references checked)::

    .venv/bin/python -m sphinx -W --keep-going -n -b html docs docs/_build/html

External links (needs a network; not part of CI)::

    .venv/bin/python -m sphinx -b linkcheck docs docs/_build/linkcheck

What is generated on every build, so that nothing is listed by hand:

- the API reference: ``autosummary`` walks the package ``refnpr`` recursively (every public
  module, i.e. every module whose name does not start with ``_``), and ``automodule`` documents
  each module's public names (its ``__all__`` where it has one) from their numpy-style docstrings;
  stubs are written to ``docs/_generated/api`` (ignored by git);
- the notebooks: ``notebooks/*.ipynb`` are copied to ``docs/_generated/notebooks`` and rendered
  with their stored outputs (never executed);
- the guides: every ``docs/*.md`` that is not a paper's page joins the index's "Guides" list;
- the gallery (``refnpr.gallery.GALLERY``) and the command line reference
  (``refnpr.cli.build_parser``, through sphinx-argparse).
"""

from __future__ import annotations

import ast
import filecmp
import importlib
import importlib.util
import pkgutil
import re
import shutil
import sys
import types
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx.pycode import ModuleAnalyzer

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
GENERATED = DOCS / "_generated"
sys.path.insert(0, str(ROOT))  # the checkout's refnpr, also when it is not installed

import refnpr  # noqa: E402

project = "refnpr"
author = "refnpr contributors"
copyright = "refnpr contributors, MIT licence"
release = version = refnpr.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx.ext.mathjax",
    "myst_nb",
    "sphinxarg.ext",
]

root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints"]
templates_path = ["_templates"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}

html_theme = "furo"
html_title = f"refnpr {release}"
html_static_path: list[str] = []

# -- API reference ------------------------------------------------------------------------------
autosummary_generate = False  # the module pages are written below (_write_api_pages)
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_typehints_format = "short"
autoclass_content = "both"
numpydoc_show_class_members = False  # autodoc documents the members
numpydoc_xref_param_type = False  # types are prose ("(H, W, 3) float32"), not names
numpydoc_class_members_toctree = False

# Names outside refnpr cannot be resolved offline (no intersphinx), and private modules (``_x``)
# are not documented; every other cross-reference must resolve.
nitpick_ignore_regex = [
    (r"py:.*", r"(?!refnpr(\.|$)).*"),
    (r"py:.*", r"refnpr(\.\w+)*\._\w*(\..*)?"),
]

# -- Markdown and notebooks ---------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
nb_execution_mode = "off"  # the notebooks are shown with their stored outputs
nb_merge_streams = True
suppress_warnings = [
    "myst.header",  # the existing pages start at "#" and may skip a level further down
    "mystnb.unknown_mime_type",  # widget state of ipywidgets outputs
]

#: The pages of the papers refnpr implements, in the index's order.
PAPERS = ["veryovka", "halftone", "xtoon", "tamiss", "lit"]
#: The site's own pages (not guides).
SITE_PAGES = {"index", "api", "cli", "gallery", "notebooks"}


def _sync_notebooks() -> None:
    """Copy ``notebooks/*.ipynb`` into the source tree (only files that changed), dropping stale
    copies, so the notebook pages always match the repository's notebooks."""
    src, dst = ROOT / "notebooks", GENERATED / "notebooks"
    dst.mkdir(parents=True, exist_ok=True)
    wanted = {p.name: p for p in src.glob("*.ipynb")}
    for old in dst.glob("*.ipynb"):
        if old.name not in wanted:
            old.unlink()
    for name, path in wanted.items():
        target = dst / name
        if not target.exists() or not filecmp.cmp(path, target, shallow=False):
            shutil.copyfile(path, target)


_sync_notebooks()


# -- API reference pages ------------------------------------------------------------------------
def _public_modules() -> list[str]:
    """``refnpr`` and every module below it whose dotted name has no part starting with ``_``."""
    names = ["refnpr"]
    for info in pkgutil.walk_packages(refnpr.__path__, "refnpr.", onerror=_import_failed):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _import_failed(name: str) -> None:
    raise ImportError(
        f"the API reference cannot import {name}: install refnpr[docs] and its extras"
    )


def _home(obj: object, member: str, public: list[str]) -> str | None:
    """The public module whose page documents ``obj``, exported elsewhere as ``member``: its
    ``__module__`` for classes and functions of public modules, else the deepest public module
    whose ``__all__`` binds ``member`` to the same object (None: no public module does)."""
    home, qual = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if isinstance(home, str) and home in public and qual == member:
        return home
    holders = [
        m
        for m in public
        if member in getattr(importlib.import_module(m), "__all__", ())
        and getattr(importlib.import_module(m), member, None) is obj
    ]
    return max(holders, key=len) if holders else None


def _assigned(name: str) -> list[str]:
    """Public names a module's own source binds by assignment at its top level."""
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.origin or not spec.origin.endswith(".py"):
        return []
    tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
    names = []
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            for target in targets:
                elts = target.elts if isinstance(target, ast.Tuple) else [target]
                names += [t.id for t in elts if isinstance(t, ast.Name) and t.id[0] != "_"]
    return names


def _api_page(name: str, modules: list[str]) -> str:
    """The reStructuredText of one module's page: its docstring and every public name it defines
    (``__all__`` or not), the names of its ``__all__`` that live in private modules, a table of
    the names it re-exports from public modules, and a table of its submodules. Only the root
    package's page is in the site's toctree; the others are reached from their package's page
    (a navigation tree of every module costs furo a third of the build)."""
    mod = importlib.import_module(name)
    lines = [name, "=" * len(name), "", f".. automodule:: {name}"]
    lines += [
        "   :members:",
        "   :undoc-members:",
        "   :ignore-module-all:",
        "   :show-inheritance:",
    ]
    lines.append("")
    elsewhere: list[str] = []
    assigned = _assigned(name)
    commented = {key for (cls, key) in ModuleAnalyzer.for_module(name).find_attr_docs() if not cls}
    for member in assigned:  # values autodoc skips: no doc comment, or a foreign class's instance
        obj = getattr(mod, member, None)
        own = type(obj).__module__ == "builtins" or type(obj).__module__.startswith("refnpr.")
        plain = not isinstance(obj, (type, types.ModuleType, types.FunctionType))
        if own and plain and member not in commented:
            lines += [f".. autodata:: {name}.{member}", ""]
    for member in getattr(mod, "__all__", ()):
        obj = getattr(mod, member)
        if isinstance(obj, types.ModuleType) or member in assigned:
            continue
        home = _home(obj, member, modules)
        if home == name and getattr(obj, "__module__", None) == name and member[0] != "_":
            continue  # automodule documents it
        if home is not None and home != name:
            elsewhere.append(f"{home}.{member}")
            continue
        kind = "class" if isinstance(obj, type) else "function" if callable(obj) else "data"
        lines += [f".. auto{kind}:: {name}.{member}", ""]
    if elsewhere:
        lines += [
            ".. rubric:: Imported from its modules",
            "",
            ".. currentmodule:: None",
            "",
            ".. autosummary::",
            "   :nosignatures:",
            "",
            *(f"   ~{target}" for target in elsewhere),
            "",
            f".. currentmodule:: {name}",
            "",
        ]
    children = [m for m in modules if m.rpartition(".")[0] == name]
    if children:
        lines += [
            ".. rubric:: Modules",
            "",
            ".. currentmodule:: None",
            "",
            ".. autosummary::",
            "",
            *(f"   {child}" for child in children),
            "",
        ]
    if name != "refnpr":
        lines[:0] = [":orphan:", ""]  # reached from its package's page, not the site's toctree
    return "\n".join(lines)


def _write_api_pages() -> None:
    """``_generated/api/<module>.rst`` for every public module (unchanged files are not touched,
    so incremental builds stay incremental; pages of removed modules are deleted)."""
    out = GENERATED / "api"
    out.mkdir(parents=True, exist_ok=True)
    modules = _public_modules()
    wanted = {f"{m}.rst": _api_page(m, modules) for m in modules}
    for old in out.glob("*.rst"):
        if old.name not in wanted:
            old.unlink()
    for file, text in wanted.items():
        path = out / file
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


_write_api_pages()


def _guides() -> list[str]:
    return sorted(
        p.stem for p in DOCS.glob("*.md") if p.stem not in SITE_PAGES and p.stem not in PAPERS
    )


def _index_toctrees(app, docname: str, source: list[str]) -> None:
    """Fill the index's placeholders with the papers, the guides and the notebooks."""
    if docname != "index":
        return
    notebooks = sorted(p.stem for p in (GENERATED / "notebooks").glob("*.ipynb"))
    lists = {
        "<!-- papers -->": PAPERS,
        "<!-- guides -->": _guides(),
        "<!-- notebooks -->": [f"_generated/notebooks/{n}" for n in notebooks],
    }
    text = source[0]
    for marker, names in lists.items():
        text = text.replace(marker, "\n".join(names))
    source[0] = text


class GalleryDirective(Directive):
    """``refnpr-gallery`` (in a MyST page): one figure per :data:`refnpr.gallery.GALLERY` entry, read from
    ``docs/images/gallery/<file>.png`` (a missing image is an error)."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from refnpr.gallery import GALLERY

        env = self.state.document.settings.env
        lines: list[str] = []
        for entry in GALLERY:
            image = DOCS / "images" / "gallery" / f"{entry.file}.png"
            if not image.is_file():
                raise self.error(
                    f"gallery image {image} is missing: run "
                    "`refnpr gallery docs/images/gallery` to render it"
                )
            env.note_dependency(str(image))
            lines += [  # MyST: the directive is used in docs/gallery.md
                f"```{{figure}} /images/gallery/{entry.file}.png",
                f":alt: {entry.paper}",
                "",
                f"**{entry.paper}**: {entry.caption} (golden case `{entry.case}`)",
                "```",
                "",
            ]
        container = nodes.container(classes=["refnpr-gallery"])
        self.state.nested_parse(StringList(lines, source="refnpr.gallery"), 0, container)
        return [container]


_INLINE_LITERAL = re.compile(r"(``.+?``)")
_GRID_BORDER = re.compile(r"^\+[-=+]+\+$")


def _escape_bars(app, what, name, obj, options, lines: list[str]) -> None:
    """Docstrings write absolute values and norms as plain text (``|grad v|``, ``|n . v|^r``),
    which reStructuredText would read as substitutions: escape ``|`` outside inline literals,
    literal blocks and grid tables."""
    literal_indent: int | None = None
    previous = ""
    in_grid = False
    for i, line in enumerate(lines):
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        in_grid = bool(stripped) and (in_grid or bool(_GRID_BORDER.match(stripped)))
        if in_grid:
            continue
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if previous.rstrip().endswith("::") and not stripped:
            literal_indent = len(previous) - len(previous.lstrip())
        if stripped and not stripped.startswith(">>>") and "|" in line:
            parts = _INLINE_LITERAL.split(line)
            lines[i] = "".join(
                p if k % 2 else re.sub(r"(?<!\\)\|", r"\\|", p) for k, p in enumerate(parts)
            )
        if stripped:
            previous = line


#: What Python writes for a NamedTuple: each field's docstring and that of the generated
#: ``__new__`` (the class's own docstring describes the fields).
_NAMEDTUPLE_FIELD = re.compile(r"Alias for field number \d+")
_NAMEDTUPLE_NEW = re.compile(r"Create new instance of \w+\(.*\)")


def _drop_generated_docstrings(app, what, name, obj, options, lines: list[str]) -> None:
    """Drop the docstrings no one wrote: a module constant without a doc comment
    (``LIGHT_POINT = 1``) shows its value, not its built-in type's docstring (``int([x]) ->
    integer ...``), and a NamedTuple shows its own docstring without the generated ``__new__``'s
    "Create new instance of ..." appended (``autoclass_content = "both"``)."""
    if what in ("data", "attribute") and type(obj).__module__ == "builtins":
        words = [ln.strip() for ln in (type(obj).__doc__ or "").splitlines() if ln.strip()]
        if words and [ln.strip() for ln in lines if ln.strip()] == words:
            lines.clear()
    if what == "class":
        while lines and not lines[-1].strip():
            lines.pop()
        if lines and _NAMEDTUPLE_NEW.fullmatch(lines[-1].strip()):
            lines.pop()


def _skip_namedtuple_fields(app, what, name, obj, skip, options):
    """A NamedTuple's fields are not listed again as members (the class's docstring and
    signature give them; their own docstrings say "Alias for field number N")."""
    if what == "class" and _NAMEDTUPLE_FIELD.fullmatch((getattr(obj, "__doc__", "") or "").strip()):
        return True
    return None


def _resolve_reexport(app, env, node, contnode):
    """A reference to a name by the package that re-exports it (``refnpr.scenes.Scene``, or
    ``Scene`` inside ``refnpr.scenes``) resolves to its documentation in its own module."""
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"]
    candidates = [target]
    if node.get("py:module") and not target.startswith("refnpr."):
        candidates.insert(0, f"{node['py:module']}.{target}")
    domain = env.get_domain("py")
    for candidate in candidates:
        if not candidate.startswith("refnpr."):
            continue
        try:
            obj = pkgutil.resolve_name(candidate)
        except (ImportError, AttributeError, ValueError):
            continue
        home, qual = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
        if isinstance(home, str) and isinstance(qual, str):
            canonical = f"{home}.{qual}"
        else:
            canonical = _same_object(domain, candidate)
        if canonical is None or canonical == candidate:
            continue
        node = node.deepcopy()
        node["reftarget"] = canonical
        found = domain.resolve_any_xref(env, node["refdoc"], app.builder, canonical, node, contnode)
        if found:
            return found[0][1]
    return None


def _same_object(domain, candidate: str) -> str | None:
    """A documented name, other than ``candidate``, of the value ``candidate`` names."""
    try:
        obj = pkgutil.resolve_name(candidate)
    except (ImportError, AttributeError, ValueError):
        return None
    last = candidate.rpartition(".")[2]
    for name in domain.objects:
        if name != candidate and name.endswith("." + last):
            try:
                if pkgutil.resolve_name(name) is obj:
                    return name
            except (ImportError, AttributeError, ValueError):
                continue
    return None


def setup(app) -> dict:
    app.connect("source-read", _index_toctrees)
    app.connect("autodoc-process-docstring", _drop_generated_docstrings, priority=50)
    app.connect("autodoc-skip-member", _skip_namedtuple_fields)
    app.connect("autodoc-process-docstring", _escape_bars, priority=100)
    app.connect("missing-reference", _resolve_reexport)
    app.add_directive("refnpr-gallery", GalleryDirective)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
