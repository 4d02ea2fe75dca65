"""The gallery: one image per paper (and the TAM/TAMISS pair) from golden cases.

Oracles: the golden suite (every entry is an image case of it, one per paper), a direct
``render`` of the same case (the gallery writes exactly that picture) and the PNG decoder.
"""

from __future__ import annotations

import re
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.cli import main as cli_main
from refnpr.gallery import (
    GALLERY,
    GalleryEntry,
    build_gallery,
    compact_pixels,
    default_suite,
    gallery_markdown,
)
from refnpr.golden import load_suite
from refnpr.render import render
from refnpr.scenes import load_scene
from refnpr.styles import style_from_spec

ROOT = Path(__file__).resolve().parents[1]


def test_one_entry_per_paper_plus_the_tam_tamiss_pair():
    cases = {c.name: c for c in load_suite(default_suite())}
    assert default_suite() == ROOT / "refnpr" / "suite" / "suite.toml"
    prefixes = [e.case.split("-")[0] for e in GALLERY]
    assert sorted(set(prefixes)) == ["halftone", "tamiss", "veryovka", "xtoon"]
    styles = set()
    for e in GALLERY:
        case = cases[e.case]
        style = style_from_spec(case.style or load_scene(case.scene).style)
        styles.add(style.base.name if style.name == "contoured" else style.name)
    assert {"tam", "tamiss", "threshold", "halftone", "xtoon"} <= styles
    assert len({e.file for e in GALLERY}) == len(GALLERY)
    assert all(cases[e.case].kind == "image" for e in GALLERY)


def test_build_writes_the_cases_renders(tmp_path):
    cases = {c.name: c for c in load_suite(default_suite())}
    entry = next(e for e in GALLERY if e.file == "xtoon")
    lines = []
    paths = build_gallery(tmp_path / "g", (64, 48), entries=[entry], log=lines.append)
    assert paths == [tmp_path / "g" / "xtoon.png"] and len(lines) == 1
    got = iio.imread(paths[0])
    case = cases[entry.case]
    want = render(case.scene, case.style, 64, 48, case.spp).to_srgb8()
    assert got.shape[:2] == (48, 64)
    rgba = got if got.ndim == 3 and got.shape[2] == 4 else None
    if rgba is None:  # compacted: expand back as a decoder would
        rgb = got[..., None].repeat(3, -1) if got.ndim == 2 else got
        rgba = np.concatenate([rgb, np.full(got.shape[:2] + (1,), 255, np.uint8)], axis=-1)
    np.testing.assert_array_equal(rgba, want)


@pytest.mark.parametrize("grey", [True, False])
@pytest.mark.parametrize("opaque", [True, False])
def test_compact_pixels_is_lossless(grey, opaque):
    rng = np.random.default_rng(1)
    rgba = rng.integers(0, 256, (9, 11, 4), dtype=np.uint8)
    if grey:
        rgba[..., 1] = rgba[..., 2] = rgba[..., 0]
    if opaque:
        rgba[..., 3] = 255
    out = compact_pixels(rgba)
    assert out.ndim == (2 if grey and opaque else 3)
    channels = 1 if out.ndim == 2 else out.shape[2]
    assert channels == (1 if grey else 3) + (0 if opaque else 1)
    colour = out if out.ndim == 2 else out[..., : 1 if grey else 3]
    colour = colour.reshape(9, 11, -1)
    np.testing.assert_array_equal(np.broadcast_to(colour, (9, 11, 3)), rgba[..., :3])
    with pytest.raises(ValueError, match=r"rgba: expected \(H, W, 4\) uint8"):
        compact_pixels(rgba[..., :3])


def test_markdown_table_links_every_image_with_its_figure():
    md = gallery_markdown("docs/images/gallery")
    for e in GALLERY:
        assert f"(docs/images/gallery/{e.file}.png)" in md
        assert e.case in md and e.caption in md
    rows = md.splitlines()
    assert all(re.fullmatch(r"\|.*\|", r) for r in rows)
    assert rows[1] == "|---|---|---|"  # three thumbnails a row
    assert sum(r.count("![") for r in rows) == len(GALLERY)


def test_committed_gallery_is_small_and_complete():
    out = ROOT / "docs" / "images" / "gallery"
    for e in GALLERY:
        path = out / f"{e.file}.png"
        assert path.is_file(), f"{path} missing: run python -m refnpr.gallery {out}"
        assert path.stat().st_size < 100_000
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for e in GALLERY:
        assert f"docs/images/gallery/{e.file}.png" in readme


def test_errors_name_the_parameter(tmp_path):
    with pytest.raises(ValueError, match=r"size: expected \(width, height\)"):
        build_gallery(tmp_path, (0, 10))
    bad = GalleryEntry("no-such-case", "x", "p", "c")
    with pytest.raises(ValueError, match="golden cases \\['no-such-case'\\] are not in"):
        build_gallery(tmp_path, entries=[bad])
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="out_dir: .* is a file"):
        build_gallery(tmp_path / "f", entries=GALLERY[:1])


def main(argv):
    return cli_main(["gallery", *argv])


def test_main_renders_and_prints_the_table(tmp_path, capsys):
    assert main([str(tmp_path / "m"), "--size", "48x36", "--only", "xtoon", "--markdown"]) == 0
    assert [p.name for p in (tmp_path / "m").iterdir()] == ["xtoon.png"]
    assert iio.imread(tmp_path / "m" / "xtoon.png").shape[:2] == (36, 48)
    out = capsys.readouterr().out
    assert f"({(tmp_path / 'm').as_posix()}/xtoon.png)" in out
    assert main([str(tmp_path / "n"), "--only", "nope"]) == 2
    assert "--only: unknown gallery entries ['nope']" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([str(tmp_path), "--size", "bad"])
    assert "--size: expected WxH" in capsys.readouterr().err
