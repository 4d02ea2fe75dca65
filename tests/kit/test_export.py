"""refnpr kit export: layout, schema, exact matrices, expected images, resolved params, errors."""

from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import jsonschema
import numpy as np
import pytest

from refnpr import __version__
from refnpr.cli import main
from refnpr.golden import SUITE_DIR, load_suite
from refnpr.kit import export_kit
from refnpr.kit.schema import load_schema
from refnpr.kit.styles import unresolved

from .conftest import REPO, SUITE, read_exr

GOLDEN = SUITE_DIR


def _walk_strings(value, key=""):
    """(key, string) for every string in JSON data, with the key it sits under."""
    if isinstance(value, str):
        yield key, value
    elif isinstance(value, list):
        for v in value:
            yield from _walk_strings(v, key)
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _walk_strings(v, k)


# -- the whole suite (session fixture) --------------------------------------------------------
def test_every_suite_case_exports(kit_export_errors, kit_cases):
    assert kit_export_errors == {}
    names = {c.name for c in load_suite(SUITE)}
    assert set(kit_cases) == names


def test_every_case_and_the_index_validate_against_the_schema(kit_dir, kit_cases):
    case_v = jsonschema.Draft202012Validator(load_schema("case.schema.json"))
    index_v = jsonschema.Draft202012Validator(load_schema("index.schema.json"))
    # the kit carries the schema it was written with
    assert json.loads((kit_dir / "case.schema.json").read_text()) == load_schema()
    index = json.loads((kit_dir / "index.json").read_text())
    index_v.validate(index)
    assert index["format"] == "refnpr-kit" and index["version"] == 1
    bad = {}
    for name, data in kit_cases.items():
        errors = [f"{list(e.absolute_path)}: {e.message[:160]}" for e in case_v.iter_errors(data)]
        if errors:
            bad[name] = errors[:3]
    assert bad == {}


def test_the_schema_rejects_broken_cases(kit_cases):
    import copy

    v = jsonschema.Draft202012Validator(load_schema("case.schema.json"))
    good = kit_cases["default-render"]
    assert v.is_valid(good)
    breakages = {
        "no camera": lambda d: d.pop("camera"),
        "3x4 matrix": lambda d: d["camera"]["view_matrix"].pop(),
        "unknown kind": lambda d: d.update(kind="video"),
        "light without direction": lambda d: d["lights"][0].pop("direction"),
        "texture without levels": lambda d: d["textures"][next(iter(d["textures"]))].pop("levels"),
        "image case without position_deviation": lambda d: d["tolerance"].pop("position_deviation"),
        "image case with a null style": lambda d: d.update(style=None),
        "mesh outside meshes/": lambda d: d["objects"][0].update(mesh="../teapot.glb"),
    }
    for what, breaks in breakages.items():
        bad = copy.deepcopy(good)
        breaks(bad)
        assert not v.is_valid(bad), what


def test_every_file_named_in_a_case_exists_and_matches_its_entry(kit_dir, kit_cases):
    missing = []
    for name, data in kit_cases.items():
        d = kit_dir / name
        files = [o["mesh"] for o in data["objects"]]
        for frame in data.get("frames") or []:
            files += [o["mesh"] for o in frame.get("objects", [])]
        for role, tex in data["textures"].items():
            assert tex["file"] == tex["levels"][0], (name, role)
            files += tex["levels"]
            level0 = d / tex["file"]
            if level0.is_file():
                arr = read_exr(level0) if tex["dtype"] == "float32" else iio.imread(level0)
                assert list(arr.shape) == tex["shape"], (name, role)
                assert str(arr.dtype) == tex["dtype"], (name, role)
        exp = data["expected"]
        if data["kind"] == "image":
            files += [exp["png"], exp["linear"]]
        else:
            files += [c["file"] for c in exp["channels"].values()]
        missing += [f"{name}/{f}" for f in files if not (d / f).is_file()]
    assert missing == []


def test_expected_png_is_the_golden_file_and_matches_the_linear_exr(kit_dir, kit_cases):
    from refnpr.image import Image

    mismatched = []
    for name, data in kit_cases.items():
        if data["kind"] != "image":
            continue
        png = (kit_dir / name / "expected.png").read_bytes()
        assert png == (GOLDEN / f"{name}.png").read_bytes(), name
        rgba = read_exr(kit_dir / name / "expected.exr")
        assert rgba.dtype == np.float32 and rgba.shape == (data["height"], data["width"], 4)
        same = np.array_equal(Image(rgba).to_srgb8(), iio.imread(kit_dir / name / "expected.png"))
        assert same == data["expected"]["linear_matches_png"], name
        if not same:
            mismatched.append(name)
    # a mismatch means refnpr/suite/<name>.png is stale (refnpr golden --check fails on it too)
    assert mismatched == []


def test_style_params_are_fully_resolved(kit_cases):
    """Nothing a backend needs is left for refnpr to resolve: no "auto" or preset names (each
    style module's own ``unresolved`` check), and every texture role a param names exists."""
    problems = {}
    for name, data in kit_cases.items():
        if data["style"] is None:
            continue
        found = unresolved(data["style"]["name"], data["style"]["params"])
        for key, value in _walk_strings(data["style"]["params"]):
            if (key == "role" or key.endswith("_role")) and value not in data["textures"]:
                found.append(f"{key} = {value!r}: no such texture")
        if found:
            problems[name] = found
    assert problems == {}


def test_every_texture_is_referenced_from_params_by_role(kit_cases):
    """spec: textures the style samples are listed under "textures" and referenced from params
    by role, so a backend knows which file a parameter means (a preset name such as "gravel"
    left in params instead of the role is data only refnpr can resolve)."""
    unreferenced = {}
    for name, data in kit_cases.items():
        if data["style"] is None:
            continue
        strings = {v for _, v in _walk_strings(data["style"]["params"])}
        missing = [role for role in data["textures"] if role not in strings]
        if missing:
            unreferenced[name] = missing
    assert unreferenced == {}


def test_no_value_needs_refnpr_to_read(kit_cases):
    """No Python reprs, module paths or NaN stand in for data."""
    bad = []
    for name, data in kit_cases.items():
        for key, value in _walk_strings({k: data[k] for k in ("style", "objects", "textures")}):
            if value.startswith("<") or "refnpr." in value or "object at 0x" in value:
                bad.append((name, key, value[:80]))
    assert bad == []


def test_cameras_and_lights_are_exactly_refnprs(kit_cases):
    from refnpr.scenes import load_scene

    cases = {c.name: c for c in load_suite(SUITE)}
    for name in ("default-render", "room-smooth", "gbuffer-default"):
        data, case = kit_cases[name], cases[name]
        scene = load_scene(case.scene)
        cam = data["camera"]
        assert np.array_equal(np.array(cam["view_matrix"]), scene.camera.view_matrix())
        assert np.array_equal(
            np.array(cam["projection_matrix"]),
            scene.camera.projection_matrix(case.width, case.height),
        )
        assert cam["eye"] == list(scene.camera.eye) and cam["fov_y"] == scene.camera.fov_y
        assert data["background"] == list(scene.background)
        assert len(data["lights"]) == len(scene.lights)
        first = 0
        for k, (obj, entry) in enumerate(zip(scene.objects, data["objects"], strict=True)):
            assert entry["mesh_id"] == k and entry["first_tri_id"] == first
            assert entry["material"]["shininess"] == obj.material.shininess
            first += len(obj.world_mesh().faces)


def test_multi_frame_cases_carry_every_frames_camera(kit_cases):
    """Flow detail (X-Toon Fig. 6) reads the previous frame's camera: the case lists both."""
    cases = {c.name: c for c in load_suite(SUITE)}
    flow = [
        n
        for n, d in kit_cases.items()
        if (d["style"] or {}).get("params", {}).get("detail") == "flow"
    ]
    assert flow, "the suite has flow cases (xtoon-fig6-*)"
    for name in flow:
        data, case = kit_cases[name], cases[name]
        frames = data["frames"]
        assert [f["frame"] for f in frames] == [0, 1]
        assert frames[-1]["camera"] == data["camera"]  # the last frame is the expected one
        prev = case.style["prev_camera"]  # as the suite gives it
        for key in ("eye", "target"):
            assert frames[0]["camera"][key] == list(map(float, prev[key])), (name, key)
        assert frames[0]["camera"]["fov_y"] == prev["fov_y"]
        assert (
            frames[0]["camera"]["view_matrix"]
            == data["style"]["params"]["prev_camera"]["view_matrix"]
        )


def test_image_case_tolerance_and_sample_positions(kit_cases):
    data = kit_cases["default-render"]  # spp 4
    assert data["sample_positions"] == [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]]
    tol = data["tolerance"]
    assert tol["threshold"] == pytest.approx(2 / 255) and tol["position_deviation"] == 1
    g = kit_cases["gbuffer-default"]
    assert g["style"] is None and g["resolve"] is None
    assert g["tolerance"]["discrete"] == {"tri_id": {"max_pixels": 0}}
    # expected = refnpr on the kit's float32 meshes; golden = on the float64 originals: same
    # triangles everywhere, float channels apart by float32 rounding only
    frac = g["expected"]["golden_frac_over"]
    assert set(frac) == set(g["channels"]) and frac["tri_id"] == 0.0
    assert max(frac.values()) < 0.005
    assert g["raster_options"]["texture_size"] == [256, 256]
    with np.load(GOLDEN / "gbuffer-default.npz") as z:
        for ch, entry in g["expected"]["channels"].items():
            assert entry["dtype"] == str(z[ch].dtype)
    assert set(g["channels"]) == set(g["expected"]["channels"])


# -- small exports (their own directories) ----------------------------------------------------
def test_export_only_writes_those_cases_and_reexport_replaces_atomically(tmp_path):
    out = export_kit(tmp_path, suite=SUITE, only=["sphere-toon3"])
    assert out == [tmp_path / "sphere-toon3" / "case.json"]
    stale = tmp_path / "sphere-toon3" / "textures" / "stale.txt"
    stale.parent.mkdir(parents=True)
    stale.write_text("left from an older export")
    export_kit(tmp_path, suite=SUITE, only=["sphere-toon3"])
    assert not stale.exists()  # the case directory was replaced whole
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "case.schema.json",
        "index.json",
        "index.schema.json",
        "sphere-toon3",
    ]  # no temporary directories left
    index = json.loads((tmp_path / "index.json").read_text())
    (entry,) = index["cases"]
    assert {k: entry[k] for k in ("name", "kind", "style", "case")} == {
        "name": "sphere-toon3",
        "kind": "image",
        "style": "toon",
        "case": "sphere-toon3/case.json",
    }
    assert set(entry) == {"name", "kind", "style", "case", "hashes", "files"}


def test_a_failing_case_leaves_the_previous_export_whole(tmp_path, monkeypatch):
    import refnpr.kit.export as ex

    export_kit(tmp_path, suite=SUITE, only=["sphere-toon3"])
    before = (tmp_path / "sphere-toon3" / "case.json").read_bytes()

    def broken(style, scene, case_dir, **size):
        (case_dir / "textures").mkdir()
        (case_dir / "textures" / "half-written.exr").write_bytes(b"partial")
        raise ValueError("style exporter failed")

    monkeypatch.setattr(ex, "export_style", broken)
    with pytest.raises(ValueError, match="case 'sphere-toon3': style exporter failed"):
        export_kit(tmp_path, suite=SUITE, only=["sphere-toon3"])
    assert (tmp_path / "sphere-toon3" / "case.json").read_bytes() == before
    assert not (tmp_path / "sphere-toon3" / "textures").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_export_refuses_a_file_and_unknown_names(tmp_path):
    f = tmp_path / "kit"
    f.write_text("not a directory")
    with pytest.raises(ValueError, match="exists and is not a directory"):
        export_kit(f, suite=SUITE, only=["sphere-toon3"])
    with pytest.raises(ValueError, match=r"unknown case names \['sphere-ton3'\].*sphere-toon3"):
        export_kit(tmp_path / "k", suite=SUITE, only=["sphere-ton3"])
    with pytest.raises(TypeError, match="only: expected a list"):
        export_kit(tmp_path / "k", suite=SUITE, only="sphere-toon3")
    with pytest.raises(ValueError, match="does not exist"):
        export_kit(tmp_path / "k", suite=tmp_path / "missing.toml")


def test_cli_kit_export(tmp_path, capsys):
    args = ["kit", "export", str(tmp_path / "k"), "--suite", str(SUITE), "--only", "sphere-toon3"]
    assert main([*args, "-q"]) == 0
    out = capsys.readouterr().out.splitlines()
    # first the refnpr that exports and the suite it exports (the packaged one: SUITE is it)
    assert out[0].startswith(f"refnpr {__version__}, git "), out[0]
    assert f"suite {str(SUITE.absolute())!r} (the suite installed with refnpr)" in out[0]
    assert out[1:] == [f"exported 1 case(s) to {tmp_path / 'k'}"]
    assert (tmp_path / "k" / "sphere-toon3" / "case.json").is_file()
    (tmp_path / "f").write_text("x")
    assert main(["kit", "export", str(tmp_path / "f"), "--suite", str(SUITE)]) == 2
    err = capsys.readouterr().err
    assert "refnpr kit export: error: dir:" in err and "not a directory" in err


def test_cli_kit_check_passes_refnprs_own_render_and_fails_a_missing_one(tmp_path, capsys):
    kit = tmp_path / "k"
    export_kit(kit, suite=SUITE, only=["sphere-toon3", "gbuffer-default"])
    renders = tmp_path / "r"
    (renders / "gbuffer-default").mkdir(parents=True)
    (renders / "sphere-toon3.png").write_bytes((kit / "sphere-toon3" / "expected.png").read_bytes())
    for f in (kit / "gbuffer-default" / "expected").iterdir():
        (renders / "gbuffer-default" / f.name).write_bytes(f.read_bytes())
    assert main(["kit", "check", str(kit), str(renders), "--json", str(tmp_path / "m.json")]) == 0
    assert json.loads((tmp_path / "m.json").read_text())
    (renders / "sphere-toon3.png").unlink()
    assert main(["kit", "check", str(kit), str(renders)]) == 1
    assert "sphere-toon3" in capsys.readouterr().out


def test_style_vertex_attributes_go_to_the_glb(tmp_path):
    """StyleExport.vertex_attributes become '_NAME' glTF attributes (read back with trimesh)."""
    import trimesh

    from refnpr.kit.scene_export import objects_entry
    from refnpr.scenes import load_scene

    scene = load_scene("sphere")
    n = len(scene.world_meshes()[0].positions)
    extra = np.random.default_rng(1).random((n, 3))
    objs = objects_entry(scene, tmp_path, {0: {"abstract_normal": extra}})
    assert objs[0]["attributes"] == {"_ABSTRACT_NORMAL": "abstract_normal"}
    with open(tmp_path / objs[0]["mesh"], "rb") as f:
        kw = trimesh.exchange.gltf.load_glb(f)
    geom = next(iter(kw["geometry"].values()))
    assert np.array_equal(geom["vertex_attributes"]["_ABSTRACT_NORMAL"], extra.astype(np.float32))
    with pytest.raises(ValueError, match=r"object indices \[3\] do not exist"):
        objects_entry(scene, tmp_path, {3: {"x": extra}})


def test_golden_tolerance_keys(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(
        '[[case]]\nname = "a"\nscene = "sphere"\nposition_deviation = 2\n'
        '[[case]]\nname = "b"\nscene = "sphere"\nkind = "gbuffer"\ndiscrete_max_pixels = 3\n'
    )
    a, b = load_suite(suite)
    assert (a.position_deviation, a.discrete_max_pixels) == (2, 0)
    assert (b.position_deviation, b.discrete_max_pixels) == (1, 3)
    suite.write_text('[[case]]\nname = "a"\nscene = "sphere"\nposition_deviation = -1\n')
    with pytest.raises(ValueError, match=r"position_deviation: expected an integer in \[0, 16\]"):
        load_suite(suite)
    suite.write_text('[[case]]\nname = "a"\nscene = "sphere"\ndiscrete_max_pixels = 1.5\n')
    with pytest.raises(ValueError, match="discrete_max_pixels: expected an integer"):
        load_suite(suite)


def test_write_texture_levels(tmp_path):
    from refnpr.kit.textures import write_texture_levels

    rng = np.random.default_rng(0)
    f = [rng.random((8, 4, 3)).astype(np.float32), rng.random((4, 2, 3)).astype(np.float32)]
    opts = dict(wrap="repeat", orientation="row 0 = v 0", used_for="test")
    e = write_texture_levels(tmp_path, "screen", f, encoding="linear", filter="per_level", **opts)
    assert e["levels"] == ["textures/screen/level_0.exr", "textures/screen/level_1.exr"]
    assert e["shape"] == [8, 4, 3] and e["dtype"] == "float32"
    for rel, a in zip(e["levels"], f, strict=True):
        assert np.array_equal(read_exr(tmp_path / rel), a)  # exact float32
    u8 = rng.integers(0, 256, (5, 7), dtype=np.uint8)
    e = write_texture_levels(
        tmp_path, "ink", [u8], encoding="srgb", filter="nearest", **{**opts, "wrap": "clamp"}
    )
    assert e["file"] == "textures/ink/level_0.png"
    assert np.array_equal(iio.imread(tmp_path / e["file"]), u8)
    opts = dict(encoding="linear", filter="linear", orientation="o", used_for="u")
    with pytest.raises(ValueError, match="wrap: expected one of"):
        write_texture_levels(tmp_path, "x", f, wrap="mirror", **opts)
    with pytest.raises(TypeError, match="mixed dtypes"):
        write_texture_levels(tmp_path, "x", [f[0], u8], wrap="repeat", **opts)
    with pytest.raises(ValueError, match="role: expected a name"):
        write_texture_levels(tmp_path, "Bad Role", f, wrap="repeat", **opts)


def test_unresolved_detects_auto():
    from refnpr.kit.styles import _generic

    assert _generic.unresolved({"specular": True, "n": 2}) == []
    assert _generic.unresolved({"a": {"b": ["x", "auto"]}}) == ["params.a.b[1] = 'auto'"]
    # the contour layer is checked whatever the style module's own check says
    found = unresolved("toon", {"contours": {"width": "auto"}})
    assert "params.contours.width = 'auto'" in found


# -- provenance and content hashes ------------------------------------------------------------
def test_index_records_provenance_and_the_hashes_of_the_files(tmp_path):
    import numba

    from refnpr.kit.content import GROUPS, canonical_json, case_hashes, digest
    from refnpr.kit.provenance import git_commit

    export_kit(tmp_path, suite=SUITE, only=["sphere-toon3", "gbuffer-default"])
    index = json.loads((tmp_path / "index.json").read_text())
    jsonschema.Draft202012Validator(load_schema("index.schema.json")).validate(index)
    prov = index["provenance"]
    assert prov["refnpr"] == __version__ == index["refnpr"]
    assert prov["numpy"] == np.__version__ and prov["numba"] == numba.__version__
    assert prov["git_commit"] == git_commit(REPO)  # this checkout's HEAD (None without .git)
    assert prov["platform"] and prov["machine"] and prov["python"]
    assert prov["suite"]["packaged"] is True and prov["suite"]["path"] == "refnpr/suite/suite.toml"
    assert index["hashes"] == {"algorithm": "sha256", "groups": list(GROUPS)}
    for entry in index["cases"]:
        d = tmp_path / entry["name"]
        on_disk = sorted(str(p.relative_to(d)) for p in d.rglob("*") if p.is_file())
        assert sorted(entry["files"]) == on_disk
        for rel, h in entry["files"].items():
            assert h == digest((d / rel).read_bytes()), rel
        case = json.loads((d / "case.json").read_text())
        assert entry["hashes"] == case_hashes(case, entry["files"])
        # the tolerance digest is the canonical JSON of the tolerance object, nothing else
        assert entry["hashes"]["tolerance"] == digest(canonical_json(case["tolerance"]))
    g = next(e for e in index["cases"] if e["name"] == "gbuffer-default")
    expected = {f for f in g["files"] if f.startswith("expected/")}
    assert expected and all(f.endswith(".npy") for f in expected)


def test_cases_kept_from_an_earlier_export_keep_their_provenance(tmp_path):
    from refnpr.kit.content import case_files

    export_kit(tmp_path, suite=SUITE, only=["sphere-toon3"])
    index = json.loads((tmp_path / "index.json").read_text())
    older = {**index["provenance"], "refnpr": "0.0.9", "git_commit": None}
    index["provenance"] = older  # as if an older refnpr had exported sphere-toon3
    (tmp_path / "index.json").write_text(json.dumps(index))
    export_kit(tmp_path, suite=SUITE, only=["vase-toon"])
    entries = {e["name"]: e for e in json.loads((tmp_path / "index.json").read_text())["cases"]}
    assert entries["sphere-toon3"]["provenance"] == older
    assert "provenance" not in entries["vase-toon"]  # the index's own provenance
    # the kept case's hashes are carried over, and are those of its files
    kept = entries["sphere-toon3"]
    assert kept["files"] == case_files(tmp_path / "sphere-toon3")
    assert kept["hashes"] == index["cases"][0]["hashes"]
    # ... unless its entry no longer describes it: then they are computed again
    index = json.loads((tmp_path / "index.json").read_text())
    index["cases"][0]["hashes"]["inputs"] = "sha256:" + "0" * 64
    index["cases"][0]["files"]["extra.bin"] = "sha256:" + "0" * 64
    (tmp_path / "index.json").write_text(json.dumps(index))
    export_kit(tmp_path, suite=SUITE, only=["vase-toon"])
    entries = {e["name"]: e for e in json.loads((tmp_path / "index.json").read_text())["cases"]}
    assert entries["sphere-toon3"]["hashes"] == kept["hashes"]
    assert entries["sphere-toon3"]["files"] == kept["files"]
    # re-exported now: the entry's own provenance goes
    export_kit(tmp_path, suite=SUITE, only=["sphere-toon3"])
    index = json.loads((tmp_path / "index.json").read_text())
    assert all("provenance" not in e for e in index["cases"])
    # an index that cannot be read: what exported the cases kept is unknown (null)
    (tmp_path / "index.json").write_text("[" * 100_000)
    export_kit(tmp_path, suite=SUITE, only=["vase-toon"])
    entries = {e["name"]: e for e in json.loads((tmp_path / "index.json").read_text())["cases"]}
    assert entries["sphere-toon3"]["provenance"] is None
    assert "provenance" not in entries["vase-toon"]


def test_git_commit_is_read_from_dot_git_without_git(tmp_path):
    from refnpr.kit.provenance import git_commit

    sha, other = "0123456789abcdef0123456789abcdef01234567", "f" * 40
    repo = tmp_path / "repo"
    git = repo / ".git"
    (git / "refs" / "heads").mkdir(parents=True)
    assert git_commit(repo) is None  # no HEAD
    (git / "HEAD").write_text("ref: refs/heads/main\n")
    assert git_commit(repo) is None  # an unborn branch
    (git / "packed-refs").write_text(f"# pack-refs with: peeled\n{other} refs/heads/main\n")
    assert git_commit(repo) == other
    (git / "refs" / "heads" / "main").write_text(sha + "\n")  # a loose ref wins
    assert git_commit(repo) == sha
    (git / "HEAD").write_text(other + "\n")  # detached
    assert git_commit(repo) == other
    for junk in ("ref: refs/../../etc/passwd", "ref: HEAD", "not a commit", "\x00" * 10):
        (git / "HEAD").write_text(junk)
        assert git_commit(repo) is None, junk
    # a worktree: .git is a file naming the git directory, whose commondir holds the refs
    wt = tmp_path / "wt"
    wt.mkdir()
    wt_git = git / "worktrees" / "wt"
    wt_git.mkdir(parents=True)
    (wt / ".git").write_text(f"gitdir: {wt_git}\n")
    (wt_git / "HEAD").write_text("ref: refs/heads/main\n")
    (wt_git / "commondir").write_text("../..\n")
    assert git_commit(wt) == sha
    assert git_commit(tmp_path / "nowhere") is None


def test_the_installed_suite_is_read_only_and_fails_into_the_temporary_directory(
    monkeypatch, tmp_path
):
    import os
    import tempfile

    import refnpr.golden as golden

    assert golden.DEFAULT_SUITE == golden.SUITE_DIR / "suite.toml"
    assert golden.DEFAULT_SUITE.is_file() and golden.is_packaged_suite(SUITE)
    # from a checkout: failure images beside the suite, --update allowed
    assert golden.source_checkout() == REPO
    assert golden.default_failure_dir(golden.DEFAULT_SUITE) == golden.SUITE_DIR / "_failures"
    golden.check_writable_suite(golden.DEFAULT_SUITE)
    # installed from a wheel: the package's golden files are not to be rewritten
    monkeypatch.setattr(golden, "source_checkout", lambda: None)
    monkeypatch.setattr(tempfile, "gettempdir", lambda: str(tmp_path))
    fail = golden.default_failure_dir(golden.DEFAULT_SUITE)
    assert fail == tmp_path / f"refnpr-golden-failures-{os.getuid()}"
    assert fail.is_dir() and (fail.stat().st_mode & 0o777) == 0o700  # made private
    assert golden.default_failure_dir(golden.DEFAULT_SUITE) == fail  # and reused
    # in the shared temporary directory, a link someone else put there is not followed
    fail.rmdir()
    fail.symlink_to(tmp_path / "elsewhere-dir")
    with pytest.raises(ValueError, match="is not a directory of yours"):
        golden.default_failure_dir(golden.DEFAULT_SUITE)
    with pytest.raises(ValueError, match="installed with refnpr.*--suite COPY/suite.toml"):
        golden.update_suite(golden.DEFAULT_SUITE, only=["sphere-toon3"])
    other = Path(tempfile.gettempdir()) / "elsewhere" / "suite.toml"
    assert golden.default_failure_dir(other) == other.parent / "_failures"
    golden.check_writable_suite(other)  # any other suite may be updated


# -- cases of the user's own scenes -----------------------------------------------------------
def _user_glb(path):
    import trimesh

    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.icosphere(2), node_name="ball")
    scene.add_geometry(
        trimesh.creation.box(),
        node_name="box",
        transform=trimesh.transformations.translation_matrix([1.6, 0.0, -0.5]),
    )
    scene.export(path)
    return path


def test_a_case_of_your_own_gltf_scene_is_exported_like_a_suite_case(tmp_path):
    import warnings

    from refnpr.kit.check import check_kit
    from refnpr.render import render
    from refnpr.scenes import load_scene

    glb = _user_glb(tmp_path / "model.glb")
    kit = tmp_path / "kit"
    args = ["kit", "export", str(kit), "--scene", str(glb), "--style", "smooth", "-q"]
    assert main([*args, "--size", "48x36"]) == 0
    case = json.loads((kit / "model-smooth" / "case.json").read_text())
    assert (case["width"], case["height"], case["spp"]) == (48, 36, 1)
    assert case["style"]["name"] == "smooth"
    assert case["expected"]["png_from_golden"] is False
    assert case["tolerance"]["threshold"] == pytest.approx(2 / 255)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        want = render(load_scene(glb), "smooth", 48, 36, 1).to_srgb8()
    np.testing.assert_array_equal(iio.imread(kit / "model-smooth" / "expected.png"), want)
    index = json.loads((kit / "index.json").read_text())
    assert [c["name"] for c in index["cases"]] == ["model-smooth"]
    assert "suite" not in index["provenance"]
    # a second case of the same scene joins the kit; a backend rendering both passes
    own = ["kit", "export", str(kit), "--scene", str(glb), "--name", "ball-toon", "--style", "toon"]
    assert main([*own, "--param", "n=3", "-q"]) == 0
    renders = tmp_path / "renders"
    renders.mkdir()
    for name in ("model-smooth", "ball-toon"):
        (renders / f"{name}.png").write_bytes((kit / name / "expected.png").read_bytes())
    results = check_kit(kit, renders)
    assert [r.passed for r in results] == [True, True]


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--only", "default-toon"], "--scene: export either a case of your own scene or suite"),
        (["--name", "Bad Name"], "name: expected a case name matching"),
        (["--spp", "0"], "spp: expected a positive integer"),
    ],
)
def test_own_scene_export_errors(tmp_path, capsys, extra, match):
    glb = _user_glb(tmp_path / "model.glb")
    assert main(["kit", "export", str(tmp_path / "k"), "--scene", str(glb), *extra]) == 2
    assert match in capsys.readouterr().err


def test_style_options_need_a_scene(tmp_path, capsys):
    assert main(["kit", "export", str(tmp_path / "k"), "--style", "toon"]) == 2
    assert "--style: only with --scene FILE" in capsys.readouterr().err


def test_a_suite_file_may_name_a_gltf_scene(tmp_path):
    _user_glb(tmp_path / "model.glb")
    (tmp_path / "suite.toml").write_text(
        '[[case]]\nname = "mine"\nscene = "model.glb"\nstyle = { name = "smooth" }\n'
        "width = 40\nheight = 30\n"
    )
    [case] = load_suite(tmp_path / "suite.toml")
    assert case.scene == str((tmp_path / "model.glb").resolve())
    written = export_kit(tmp_path / "kit", suite=tmp_path / "suite.toml", log=None)
    assert [p.parent.name for p in written] == ["mine"]


def _textured_glb(path, texel_rgb):
    """A quad .glb whose baseColorTexture (8 x 8 RGB) repeats 2.5 times, beside a ball without."""
    import trimesh
    from PIL import Image as PILImage

    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
    quad = trimesh.Trimesh(pos, [[0, 1, 2], [0, 2, 3]], process=False)
    quad.visual = trimesh.visual.TextureVisuals(
        uv=(pos[:, :2] + 1.0) / 2.0 * 2.5, image=PILImage.fromarray(texel_rgb)
    )
    scene = trimesh.Scene()
    scene.add_geometry(quad, node_name="quad")
    scene.add_geometry(
        trimesh.creation.icosphere(1, radius=0.4),
        node_name="ball",
        transform=trimesh.transformations.translation_matrix([0.0, 0.0, 0.6]),
    )
    scene.export(path)
    return path


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("style", ["smooth", "toon"])
def test_colour_maps_are_exported_with_their_levels_roles_and_text(tmp_path, style):
    from refnpr.kit.styles._albedo import COLOR_TEXTURE
    from refnpr.scenes import load_scene
    from refnpr.styles.albedo import color_pyramid

    texels = np.random.default_rng(3).integers(0, 256, (8, 8, 3), dtype=np.uint8)
    glb = _textured_glb(tmp_path / "q.glb", texels)
    kit = tmp_path / "kit"
    assert main(["kit", "export", str(kit), "--scene", str(glb), "--style", style, "-q"]) == 0
    case = json.loads((kit / f"q-{style}" / "case.json").read_text())
    jsonschema.validate(case, load_schema())
    names = [o["name"] for o in case["objects"]]
    roles = case["style"]["params"]["color_texture"]
    assert roles == [("color_0" if n == "quad" else None) for n in names]
    quad = case["objects"][names.index("quad")]["material"]
    ball = case["objects"][names.index("ball")]["material"]
    assert "images[0]@sha256:" in quad["color_texture"] and "color_texture" not in ball
    assert {"uv", "duv_dx", "duv_dy"} <= set(case["channels"])
    assert case["derived"]["color_texture"] == COLOR_TEXTURE
    entry = case["textures"]["color_0"]
    assert entry["filter"] == "linear_mipmap_linear" and entry["wrap"] == "repeat"
    pyr = color_pyramid(load_scene(glb).objects[names.index("quad")].material.color_texture)
    assert len(entry["levels"]) == len(pyr.levels)
    for rel, level in zip(entry["levels"], pyr.levels, strict=True):
        np.testing.assert_array_equal(read_exr(kit / f"q-{style}" / rel), level)
    # docs/kit.md quotes the text a backend codes from
    lines = (REPO / "docs" / "kit.md").read_text(encoding="utf-8").splitlines()
    doc = " ".join(" ".join(ln.removeprefix("> ") for ln in lines).split())
    assert " ".join(COLOR_TEXTURE.split()) in doc
