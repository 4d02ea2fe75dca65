"""Each declared style's parameter table in ``docs/`` is the one its declaration generates
(``refnpr styles NAME --markdown``), so the docs say what the code takes."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from refnpr.styles import get_style_class, list_styles
from refnpr.styles._declare import DOCS_MARK, markdown_table
from refnpr.styles.contours import CONTOURS

DOCS = Path(__file__).resolve().parents[1] / "docs"
DECLARED = [n for n in list_styles() if get_style_class(n).PARAMS is not None]
#: Declarations that are not a style's (their tables are in the docs too).
LAYERS = {"contours": CONTOURS}


def _block(name: str) -> str | None:
    """The table between ``<!-- parameters: NAME -->`` and the end mark, in any doc."""
    pattern = re.compile(
        rf"<!-- parameters: {re.escape(name)} -->\n.*?\n\n(.*?){re.escape(DOCS_MARK)}", re.S
    )
    for path in sorted(DOCS.glob("*.md")):
        m = pattern.search(path.read_text(encoding="utf-8"))
        if m:
            return m.group(1)
    return None


def test_some_styles_are_declared():
    assert "xtoon" in DECLARED


@pytest.mark.parametrize("name", DECLARED)
def test_docs_table_is_the_declarations(name):
    block = _block(name)
    assert block is not None, f"no '<!-- parameters: {name} -->' table in docs/*.md"
    assert block == markdown_table(get_style_class(name).PARAMS), (
        f"docs table of {name!r} is out of date: paste `refnpr styles {name} --markdown`"
    )


@pytest.mark.parametrize("name", sorted(LAYERS))
def test_docs_table_of_a_layer_is_its_declarations(name):
    block = _block(name)
    assert block is not None, f"no '<!-- parameters: {name} -->' table in docs/*.md"
    assert block == markdown_table(LAYERS[name])
