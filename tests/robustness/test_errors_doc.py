"""docs/errors.md is the catalogue as a table: every case is there, and there are enough cases."""

from __future__ import annotations

import importlib
import pkgutil
from collections import Counter
from pathlib import Path

from .catalogue import CLASSES, ROOT


def _cases():
    package = importlib.import_module(__package__)
    out = []
    for info in pkgutil.iter_modules(package.__path__):
        if info.name.startswith("test_") and info.name != "test_errors_doc":
            out += getattr(importlib.import_module(f"{__package__}.{info.name}"), "CASES", [])
    return out


def test_catalogue_covers_every_class_with_at_least_100_cases():
    cases = _cases()
    assert len(cases) >= 100, len(cases)
    by_class = Counter(c.klass for c in cases)
    assert set(by_class) == set(CLASSES) - {"fuzz"}, by_class  # fuzz: tests of their own
    assert len({c.id for c in cases}) == len(cases), "case ids must be unique across modules"


def test_docs_errors_lists_every_case():
    text = (ROOT / "docs" / "errors.md").read_text(encoding="utf-8")
    missing = [c.id for c in _cases() if f"`{c.id}`" not in text]
    assert not missing, (
        f"docs/errors.md lacks {missing}; regenerate it: "
        "python -m tests.robustness.report --markdown docs/errors.md"
    )
    assert Path(ROOT / "docs" / "errors.md").stat().st_size < 200_000
