"""refnpr kit diff: cases added, removed and changed (inputs, tolerance, expected, texts) between
two kits; kits without recorded hashes; hostile kits (links out, '..', FIFOs, deep or huge JSON,
escape sequences in names).

Most kits here are synthetic (a case.json and a few bytes per file: the diff never decodes an
image); one test exports two small real kits."""

from __future__ import annotations

import copy
import json
import os
import re
from pathlib import Path

import jsonschema
import pytest

from refnpr.cli import main
from refnpr.kit.content import case_files, case_hashes
from refnpr.kit.diff import diff_kits, read_kit
from refnpr.kit.schema import load_schema


def _case(name: str, **over) -> dict:
    case = {
        "name": name,
        "description": "",
        "kind": "image",
        "width": 16,
        "height": 16,
        "spp": 1,
        "style": {"name": "toon", "params": {"n": 2, "t": 0.5}},
        "objects": [{"name": "m", "mesh": "meshes/m.glb"}],
        "expected": {"png": "expected.png", "linear": "expected.exr"},
        "tolerance": {"threshold": 0.0078, "max_frac_over": 0.0005, "position_deviation": 1},
        "derived": {"shading": "shade per sample"},
    }
    case.update(over)
    return case


def _files(name: str) -> dict[str, bytes]:
    return {
        "meshes/m.glb": f"glb of {name}".encode(),
        "expected.png": f"png of {name}".encode(),
        "expected.exr": f"exr of {name}".encode(),
    }


SPEC = {n: (_case(n), _files(n)) for n in ("alpha", "beta", "gamma")}


def write_kit(root: Path, spec: dict, *, hashes: bool = True, refnpr: str = "0.1.0") -> Path:
    """A kit as refnpr kit export lays it out: index.json (with content hashes unless
    ``hashes`` is False, as kits exported before they were recorded) and per case its
    case.json and files."""
    root.mkdir(parents=True, exist_ok=True)
    entries = []
    for name, (case, files) in spec.items():
        d = root / name
        for rel, data in files.items():
            (d / rel).parent.mkdir(parents=True, exist_ok=True)
            (d / rel).write_bytes(data)
        (d / "case.json").write_text(json.dumps(case, indent=2))
        entry = {"name": name, "kind": case["kind"], "style": "toon", "case": f"{name}/case.json"}
        if hashes:
            entry["files"] = case_files(d)
            entry["hashes"] = case_hashes(case, entry["files"])
        entries.append(entry)
    index = {"format": "refnpr-kit", "version": 1, "refnpr": refnpr, "cases": entries}
    if hashes:
        index["provenance"] = {"refnpr": refnpr, "git_commit": "ab" * 20}
        index["hashes"] = {
            "algorithm": "sha256",
            "groups": ["inputs", "tolerance", "expected", "texts"],
        }
    (root / "index.json").write_text(json.dumps(index, indent=2))
    return root


def _cli(capsys, old: Path, new: Path, *more: str) -> tuple[int, str]:
    rc = main(["kit", "diff", str(old), str(new), *more])
    out = capsys.readouterr()
    return rc, out.out + out.err


# -- what changed ------------------------------------------------------------------------------
def test_identical_kits(tmp_path, capsys):
    old = write_kit(tmp_path / "old", SPEC)
    new = write_kit(tmp_path / "new", SPEC)
    d = diff_kits(old, new)
    assert d.identical and d.status == 0
    assert (d.added, d.removed, d.changed) == ([], [], [])
    assert d.unchanged == ["alpha", "beta", "gamma"]
    rc, out = _cli(capsys, old, new)
    assert rc == 0, out
    assert out.splitlines()[0] == f"old: '{old}': refnpr 0.1.0, git {'ab' * 6}; 3 case(s)"
    assert out.rstrip().endswith("0 added, 0 removed, 0 changed, 3 unchanged: identical")


def test_added_removed_and_what_changed(tmp_path, capsys):
    spec = copy.deepcopy(SPEC)
    del spec["gamma"]
    spec["delta"] = (_case("delta"), _files("delta"))
    spec["alpha"][0]["style"]["params"]["n"] = 3  # an input
    spec["alpha"][1]["meshes/m.glb"] = b"another mesh"  # an input file
    spec["alpha"][1]["expected.png"] = b"another image"  # and its new expected image
    spec["beta"][0]["tolerance"]["threshold"] = 0.01  # tolerance only
    old = write_kit(tmp_path / "old", SPEC)
    new = write_kit(tmp_path / "new", spec)
    d = diff_kits(old, new)
    assert (d.added, d.removed, d.unchanged) == (["delta"], ["gamma"], [])
    by = {c.name: c for c in d.changed}
    assert sorted(by) == ["alpha", "beta"]
    assert by["alpha"].parts == ["inputs", "expected"]
    assert by["alpha"].keys == [("style.params.n", 2, 3)]
    assert by["alpha"].files == {
        "changed": ["expected.png", "meshes/m.glb"],
        "added": [],
        "removed": [],
    }
    assert by["beta"].parts == ["tolerance"]
    assert by["beta"].keys == [("tolerance.threshold", 0.0078, 0.01)]
    assert by["beta"].files == {"changed": [], "added": [], "removed": []}
    assert d.status == 1
    rc, out = _cli(capsys, old, new)
    assert rc == 1
    lines = out.splitlines()
    assert "added (1): delta" in lines and "removed (1): gamma" in lines
    i = lines.index("changed (2):")
    assert lines[i + 1 : i + 7] == [
        "  alpha: inputs, expected images",
        "    style.params.n: 2 -> 3",
        "    files changed: expected.png, meshes/m.glb",
        "  beta: tolerance",
        "    tolerance.threshold: 0.0078 -> 0.01",
        "1 added, 1 removed, 2 changed, 0 unchanged: changed",
    ]


def test_texts_keys_files_and_gbuffer_words(tmp_path, capsys):
    spec = copy.deepcopy(SPEC)
    spec["alpha"][0]["derived"]["shading"] = "shade per sample, then resolve"
    spec["alpha"][0]["description"] = "now described"
    spec["beta"][1]["textures/screen/level_0.exr"] = b"a texture"  # a file added
    del spec["gamma"][1]["expected.exr"]  # a file removed
    spec["gamma"][0]["kind"] = "gbuffer"
    long = "x" * 100
    spec["gamma"][0]["derived"]["shading"] = long
    old_spec = copy.deepcopy(SPEC)
    old_spec["gamma"][0]["kind"] = "gbuffer"
    old_spec["gamma"][0]["derived"]["shading"] = long[:70] + "y" + long[71:]
    d = diff_kits(write_kit(tmp_path / "o", old_spec), write_kit(tmp_path / "n", spec))
    by = {c.name: c for c in d.changed}
    assert by["alpha"].parts == ["texts"]
    assert sorted(k for k, _, _ in by["alpha"].keys) == ["derived.shading", "description"]
    assert by["beta"].parts == ["inputs"] and by["beta"].files["added"] == [
        "textures/screen/level_0.exr"
    ]
    assert by["gamma"].parts == ["expected", "texts"]
    assert by["gamma"].files["removed"] == ["expected.exr"]
    text = d.format()
    assert "  alpha: derived texts" in text
    assert "  gamma: expected arrays, derived texts" in text  # a G-buffer case's words
    assert "derived.shading: text differs from character 70:" in text
    assert "files removed: expected.exr" in text


def test_a_kit_without_hashes_is_compared_file_by_file(tmp_path, capsys):
    spec = copy.deepcopy(SPEC)
    spec["beta"][1]["expected.png"] = b"changed"
    old = write_kit(tmp_path / "old", SPEC, hashes=False, refnpr="0.0.9")
    new = write_kit(tmp_path / "new", spec)
    d = diff_kits(old, new)
    assert [(c.name, c.parts) for c in d.changed] == [("beta", ["expected"])]
    assert d.unchanged == ["alpha", "gamma"]
    assert not d.old.recorded and d.new.recorded
    (note,) = d.notes
    assert "old kit" in note and "records no content hashes" in note and "0.0.9" in note
    rc, out = _cli(capsys, old, write_kit(tmp_path / "same", SPEC, hashes=False))
    assert rc == 0 and "note: old kit" in out and "note: new kit" in out, out
    assert "old: '" in out and "refnpr 0.1.0, provenance unknown" not in out


def test_hashes_that_do_not_match_the_files_give_a_warning(tmp_path):
    old = write_kit(tmp_path / "old", SPEC)
    new = write_kit(tmp_path / "new", SPEC)
    (new / "beta" / "meshes" / "m.glb").write_bytes(b"edited after export")
    d = diff_kits(old, new)
    assert [(c.name, c.parts) for c in d.changed] == [("beta", ["inputs"])]
    (w,) = d.warnings
    assert "case 'beta'" in w and "do not match" in w and "meshes/m.glb" in w


def test_json_output(tmp_path, capsys):
    spec = copy.deepcopy(SPEC)
    spec["beta"][0]["tolerance"]["threshold"] = 0.5
    spec["beta"][0]["objects"] = [{"name": "m", "mesh": "meshes/m.glb", "big": list(range(300))}]
    old, new = write_kit(tmp_path / "o", SPEC), write_kit(tmp_path / "n", spec)
    rc, _ = _cli(capsys, old, new, "--json", str(tmp_path / "diff.json"))
    assert rc == 1
    data = json.loads((tmp_path / "diff.json").read_text())
    assert data["status"] == 1 and data["identical"] is False
    assert data["old"]["provenance"]["git_commit"] == "ab" * 20 and data["old"]["cases"] == 3
    (beta,) = data["changed"]
    assert beta["name"] == "beta" and beta["parts"] == ["inputs", "tolerance"]
    keys = {k["key"]: k for k in beta["keys"]}
    assert keys["tolerance.threshold"] == {"key": "tolerance.threshold", "old": 0.0078, "new": 0.5}
    assert "old" not in keys["objects[0].big"]  # absent in the old kit
    assert isinstance(keys["objects[0].big"]["new"], str)  # a long value, shortened
    assert data["unchanged"] == ["alpha", "gamma"]
    (tmp_path / "d").mkdir()
    rc, out = _cli(capsys, old, new, "--json", str(tmp_path / "d"))
    assert rc == 2 and "--json:" in out and "is a directory" in out


def test_index_with_hashes_validates_against_the_schema(tmp_path):
    kit = write_kit(tmp_path / "k", SPEC)
    index = json.loads((kit / "index.json").read_text())
    v = jsonschema.Draft202012Validator(load_schema("index.schema.json"))
    v.validate(index)
    index["cases"][0]["hashes"]["inputs"] = "md5:0"
    assert not v.is_valid(index)


# -- hostile kits --------------------------------------------------------------------------------
def _entry(kit: Path, i: int, **over) -> None:
    index = json.loads((kit / "index.json").read_text())
    index["cases"][i].update(over)
    (kit / "index.json").write_text(json.dumps(index))


def _secret(tmp: Path) -> Path:
    s = tmp / "outside" / "secret.json"
    s.parent.mkdir(exist_ok=True)
    s.write_text('{"SECRET": "SECRET-VALUE"}')
    return s


def _case_link_out(kit: Path, tmp: Path) -> None:
    outside = tmp / "outside" / "alpha"
    outside.parent.mkdir(exist_ok=True)
    os.rename(kit / "alpha", outside)
    (kit / "alpha").symlink_to(outside)


def _file_link_out(kit: Path, tmp: Path) -> None:
    (kit / "alpha" / "expected.png").unlink()
    (kit / "alpha" / "expected.png").symlink_to(_secret(tmp))


def _case_json_link(kit: Path, tmp: Path) -> None:
    (kit / "alpha" / "case.json").unlink()
    (kit / "alpha" / "case.json").symlink_to(_secret(tmp))


def _index_link(kit: Path, tmp: Path) -> None:
    s = tmp / "outside" / "index.json"
    s.parent.mkdir(exist_ok=True)
    os.rename(kit / "index.json", s)
    (kit / "index.json").symlink_to(s)


def _fifo(kit: Path, tmp: Path) -> None:
    (kit / "alpha" / "expected.exr").unlink()
    os.mkfifo(kit / "alpha" / "expected.exr")  # reading it would block forever


def _sparse_index(kit: Path, tmp: Path) -> None:
    with open(kit / "index.json", "r+b") as f:
        f.truncate(40 << 20)  # 40 MiB (sparse): refused before it is read


def _deep(text: str):
    def make(kit: Path, tmp: Path) -> None:
        (kit / text).write_text("[" * 100_000 + "]" * 100_000)

    return make


def _case_json_text(text: str):
    def make(kit: Path, tmp: Path) -> None:
        (kit / "alpha" / "case.json").write_text(text)

    return make


HOSTILE = {
    "dotdot-case-path": (
        lambda k, t: _entry(k, 0, case="../outside/case.json"),
        r"case 'alpha': 'case' must be DIR/case\.json.*no '\.\.'",
    ),
    "absolute-case-path": (
        lambda k, t: _entry(k, 0, case="/dev/zero"),
        r"case 'alpha': 'case' must be DIR/case\.json",
    ),
    "case-not-a-string": (lambda k, t: _entry(k, 0, case=5), r"'case' must be DIR/case\.json.*5"),
    "case-dir-links-out": (_case_link_out, r"case 'alpha'.*is a symbolic link"),
    "file-links-out": (_file_link_out, r"case 'alpha'.*expected\.png' is a symbolic link"),
    "case-json-links-out": (_case_json_link, r"case 'alpha'.*case\.json' is a symbolic link"),
    "index-links-out": (_index_link, r"index\.json.*symbolic link"),
    "fifo-in-case": (_fifo, r"case 'alpha'.*expected\.exr' is not a regular file"),
    "huge-index": (_sparse_index, r"index\.json.*over the limit"),
    "deep-index": (_deep("index.json"), r"index\.json.*nested deeper than \d+"),
    "deep-case": (_deep("alpha/case.json"), r"case 'alpha'.*nested deeper than \d+"),
    "nan-in-case": (
        _case_json_text('{"name": "alpha", "tolerance": {"threshold": NaN}}'),
        r"case 'alpha'.*not valid JSON.*NaN is not a JSON number",
    ),
    "overflow-in-case": (
        _case_json_text('{"name": "alpha", "width": 1e999}'),
        r"case 'alpha'.*not valid JSON.*1e999 overflows",
    ),
    "duplicate-key-in-case": (
        _case_json_text('{"name": "alpha", "kind": "image", "kind": "gbuffer"}'),
        r"case 'alpha'.*key 'kind' appears twice",
    ),
    "case-json-not-an-object": (
        _case_json_text("[1, 2]"),
        r"case 'alpha': case\.json must be a JSON object",
    ),
    "duplicate-case-names": (
        lambda k, t: _entry(k, 1, name="alpha", case="alpha/case.json"),
        r"case 'alpha' is listed twice",
    ),
    "escape-sequence-name": (
        lambda k, t: _entry(k, 0, name="\x1b[2J\x1b[31mred\u202e"),
        r"cases\[0\]\.name must match.*\\u001b\[2J",
    ),
    "newline-in-name": (
        lambda k, t: _entry(k, 0, name="alpha\n"),
        r'cases\[0\]\.name must match.*"alpha\\n"',
    ),
    "not-a-kit-index": (
        lambda k, t: (k / "index.json").write_text('{"format": "other"}'),
        r"expected \{\"format\": \"refnpr-kit\".*not a refnpr kit",
    ),
    "future-version": (
        lambda k, t: (k / "index.json").write_text('{"format": "refnpr-kit", "version": 2}'),
        r"kit format version 2; this refnpr reads version 1",
    ),
    "missing-case-dir": (
        lambda k, t: _entry(k, 0, case="nosuch/case.json"),
        r"case 'alpha': the kit has no directory 'nosuch'",
    ),
}


@pytest.mark.parametrize("which", sorted(HOSTILE))
def test_hostile_kits_are_refused_clearly(tmp_path, capsys, which):
    make, message = HOSTILE[which]
    old = write_kit(tmp_path / "old", SPEC)
    new = write_kit(tmp_path / "new", SPEC)
    make(new, tmp_path)
    rc, out = _cli(capsys, old, new)
    assert rc == 2, out
    assert "Traceback" not in out
    assert any(re.search(message, line) for line in out.splitlines()), out
    assert "SECRET-VALUE" not in out  # nothing outside the kit was read into the output
    assert "\x1b" not in out and "\u202e" not in out  # escape sequences are escaped
    if which in ("dotdot-case-path", "case-dir-links-out", "file-links-out"):
        assert "added (" not in out and "changed (" not in out  # unreadable is no "change"


def test_a_kit_path_that_is_no_directory(tmp_path, capsys):
    old = write_kit(tmp_path / "old", SPEC)
    rc, out = _cli(capsys, old, tmp_path / "nowhere")
    assert rc == 2 and "new: '" in out and "is not a kit directory (it does not exist)" in out
    with pytest.raises(TypeError, match="old: expected a kit directory path, got int"):
        read_kit(5, label="old")


# -- a real export -----------------------------------------------------------------------------
SUITE = """
[defaults]
width = 24
height = 16

[[case]]
name = "a-toon"
scene = "sphere"
style = { name = "toon", n = 2 }

[[case]]
name = "b-smooth"
scene = "sphere"
style = { name = "smooth" }
"""


def test_two_real_exports(tmp_path, capsys):
    from refnpr.kit import export_kit

    s1 = tmp_path / "s1" / "suite.toml"
    s1.parent.mkdir()
    s1.write_text(SUITE)
    s2 = tmp_path / "s2" / "suite.toml"
    s2.parent.mkdir()
    s2.write_text(
        SUITE.replace("n = 2", "n = 3").replace(
            'style = { name = "smooth" }', 'style = { name = "smooth" }\ntolerance = 0.02'
        )
    )
    old, new, again = tmp_path / "old", tmp_path / "new", tmp_path / "again"
    export_kit(old, suite=s1)
    export_kit(again, suite=s1)
    export_kit(new, suite=s2)
    assert diff_kits(old, again).status == 0  # exports are deterministic
    d = diff_kits(old, new)
    assert [(c.name, c.parts) for c in d.changed] == [
        ("a-toon", ["inputs", "expected"]),
        ("b-smooth", ["tolerance"]),
    ]
    keys = {k: (o, n) for k, o, n in d.changed[0].keys}
    assert keys["style.params.n"] == (2, 3)
    assert d.changed[0].files["changed"] == ["expected.exr", "expected.png"]
    # the old kit as an earlier refnpr wrote it (no provenance, no hashes): the same answer
    index = json.loads((old / "index.json").read_text())
    for e in index["cases"]:
        del e["hashes"], e["files"]
    del index["provenance"], index["hashes"]
    (old / "index.json").write_text(json.dumps(index))
    rc, out = _cli(capsys, old, new)
    assert rc == 1
    assert "note: old kit" in out and "records no content hashes" in out
    assert "  a-toon: inputs, expected images" in out and "  b-smooth: tolerance" in out
