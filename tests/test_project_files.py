"""What research software carries: a licence, a citation file and a changelog that agree with
the package."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import yaml

import refnpr

ROOT = Path(__file__).resolve().parents[1]

#: The papers refnpr implements: (first author's family name, year, title) as docs/ cites them.
PAPERS = {
    ("Veryovka", 2002): "Animation with threshold textures",
    ("Freudenberg", 2002): "Real-Time Halftoning: A Primitive For Non-Photorealistic Shading",
    ("Szécsi", 2020): "Tonal Art Maps with Image Space Strokes",
    ("Barla", 2006): "X-Toon: An Extended Toon Shader",
}


def test_license_is_the_one_pyproject_declares():
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"]
    text = (ROOT / "LICENSE").read_text()
    assert declared == "MIT"
    assert text.startswith("MIT License")
    assert "WITHOUT WARRANTY OF ANY KIND" in text


def test_citation_names_this_version_and_the_four_papers():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0"
    assert cff["type"] == "software"
    assert str(cff["version"]) == refnpr.__version__
    assert cff["license"] == "MIT"
    cited = {
        (ref["authors"][0]["family-names"], ref["year"]): ref["title"] for ref in cff["references"]
    }
    assert cited == PAPERS
    # the titles are those the paper pages of docs/ cite
    docs = " ".join(p.read_text(encoding="utf-8") for p in (ROOT / "docs").glob("*.md"))
    docs = " ".join(docs.split()).lower()
    for title in PAPERS.values():
        assert title.lower() in docs, title


def test_changelog_has_a_section_for_this_version():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    headings = re.findall(r"^## \[([^\]]+)\]", text, flags=re.MULTILINE)
    assert headings[0] == "Unreleased"
    assert refnpr.__version__ in headings
