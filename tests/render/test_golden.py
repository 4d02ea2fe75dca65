"""The golden suite itself (every case must match) and the harness's behaviour."""

import numpy as np
import pytest

from refnpr.golden import DEFAULT_SUITE, check_suite, load_suite, update_suite

SUITE = DEFAULT_SUITE


@pytest.mark.parametrize("case", [c.name for c in load_suite(SUITE)])
def test_golden_case_matches(case, tmp_path):
    (result,) = check_suite(SUITE, only=[case], failure_dir=tmp_path)
    assert result.passed, result.message


_MINI = """
[defaults]
width = 24
height = 16

[[case]]
name = "a"
scene = "sphere"
style = {{ name = "toon", n = {n} }}

[[case]]
name = "g"
kind = "gbuffer"
scene = "sphere"
channels = ["depth", "tri_id"]
"""


def test_missing_golden_fails_never_skips(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(_MINI.format(n=2))
    results = check_suite(suite)
    assert [r.passed for r in results] == [False, False]
    assert "missing golden file" in results[0].message


def test_update_then_check_passes_and_mismatch_writes_images(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(_MINI.format(n=2))
    update_suite(suite, log=lambda *_: None)
    assert all(r.passed for r in check_suite(suite))
    suite.write_text(_MINI.format(n=5))  # the style changed: the image must no longer match
    res = {r.name: r for r in check_suite(suite, failure_dir=tmp_path / "fail")}
    assert not res["a"].passed and res["g"].passed
    for f in ("reference.png", "result.png", "diff.png"):
        assert (tmp_path / "fail" / "a" / f).exists()


def test_gbuffer_mismatch_detected(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(_MINI.format(n=2))
    update_suite(suite, only=["g"], log=lambda *_: None)
    with np.load(tmp_path / "g.npz") as f:
        data = {k: f[k] for k in f.files}
    data["depth"] = data["depth"] * 1.001
    np.savez_compressed(tmp_path / "g.npz", **data)
    (r,) = check_suite(suite, only=["g"])
    assert not r.passed and "depth" in r.message


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[[case]]\nname = 'Bad Name'\nscene = 'sphere'\n", r"'name' must match"),
        ("[[case]]\nname = 'x'\nscene = 'sphere'\nwidht = 3\n", r"case 'x': unknown key 'widht'"),
        ("[defaults]\nwidth = 3\n", r"the suite has no \[\[case\]\] entries"),
        ("[[case]]\nname = 'x'\n", r"case 'x': 'scene' .* is required"),
    ],
)
def test_suite_errors(tmp_path, text, match):
    suite = tmp_path / "suite.toml"
    suite.write_text(text)
    with pytest.raises(ValueError, match=match):
        load_suite(suite)


def test_only_unknown_name(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(_MINI.format(n=2))
    with pytest.raises(ValueError, match=r"only: unknown case names \['zzz'\]"):
        check_suite(suite, only=["zzz"])


def test_include_adds_cases_and_missing_include_fails(tmp_path):
    (tmp_path / "more.toml").write_text("[[case]]\nname = 'b'\nscene = 'sphere'\n")
    suite = tmp_path / "suite.toml"
    suite.write_text("include = ['more.toml']\n" + _MINI.format(n=2))
    assert [c.name for c in load_suite(suite)] == ["a", "g", "b"]
    suite.write_text("include = ['gone.toml']\n" + _MINI.format(n=2))
    with pytest.raises(ValueError, match="include 'gone.toml' does not exist"):
        load_suite(suite)


@pytest.mark.parametrize(
    ("line", "match"),
    [
        ("tolerance = nan", r"case 'x': tolerance: expected a number in \[0.0, 1.0\], got nan"),
        ("tolerance = 'x'", r"case 'x': tolerance: expected a number"),
        ("spp = 0", r"case 'x': spp: expected a positive integer, got 0"),
        ("channels = []", r"case 'x': channels: expected a non-empty list"),
    ],
)
def test_case_values_are_checked(tmp_path, line, match):
    suite = tmp_path / "suite.toml"
    suite.write_text(f"[[case]]\nname = 'x'\nscene = 'sphere'\n{line}\n")
    with pytest.raises(ValueError, match=match):
        load_suite(suite)


def test_include_must_be_a_list(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text("include = 'v.toml'\n[[case]]\nname = 'x'\nscene = 'sphere'\n")
    with pytest.raises(ValueError, match="include must be a list of file names"):
        load_suite(suite)


def test_a_broken_case_does_not_stop_the_others(tmp_path):
    suite = tmp_path / "suite.toml"
    suite.write_text(
        "[[case]]\nname = 'bad'\nscene = 'gone.toml'\nwidth = 8\nheight = 8\n"
        "[[case]]\nname = 'good'\nscene = 'sphere'\nwidth = 8\nheight = 8\n"
    )
    update_suite(suite, only=["good"], log=lambda *_: None)
    (tmp_path / "bad.png").write_bytes((tmp_path / "good.png").read_bytes())
    res = {r.name: r for r in check_suite(suite)}
    assert not res["bad"].passed and "render failed" in res["bad"].message
    assert res["good"].passed


def test_scene_file_paths_are_relative_to_the_suite_in_any_case(tmp_path, monkeypatch):
    from refnpr.golden import scene_case

    suite = tmp_path / "s" / "suite.toml"
    suite.parent.mkdir()
    suite.write_text(
        '[[case]]\nname = "a"\nscene = "Room.TOML"\n[[case]]\nname = "b"\nscene = "m.GLB"\n'
    )
    assert [c.scene for c in load_suite(suite)] == [
        str(tmp_path / "s" / "Room.TOML"),
        str(tmp_path / "s" / "m.GLB"),
    ]
    monkeypatch.chdir(tmp_path)
    assert scene_case("c", "x/Up.Gltf").scene == str(tmp_path / "x" / "Up.Gltf")
    assert scene_case("d", "teapot").scene == "teapot"  # a built-in name stays a name


def test_an_image_too_small_for_ssim_is_judged_by_its_pixels(tmp_path):
    import imageio.v3 as iio

    from refnpr.image import write_png_atomic

    suite = tmp_path / "suite.toml"
    suite.write_text("[[case]]\nname = 'thin'\nscene = 'sphere'\nwidth = 2\nheight = 8\n")
    update_suite(suite, log=lambda *_: None)
    img = iio.imread(tmp_path / "thin.png")
    img[4, 1, 0] = img[4, 1, 0] ^ 1  # one level: within the tolerance
    write_png_atomic(tmp_path / "thin.png", img)
    (r,) = check_suite(suite, failure_dir=tmp_path / "fail")
    assert r.passed, r.message
    assert "ssim=n/a" in r.message


def test_failure_images_are_never_stale(tmp_path):
    import imageio.v3 as iio

    suite = tmp_path / "suite.toml"
    fail = tmp_path / "fail"
    suite.write_text(_MINI.format(n=2))
    update_suite(suite, only=["a"], log=lambda *_: None)
    golden = (tmp_path / "a.png").read_bytes()
    (fail / "other").mkdir(parents=True)  # another case's images: left alone
    (fail / "other" / "result.png").write_bytes(golden)
    suite.write_text(_MINI.format(n=5))
    (r,) = check_suite(suite, only=["a"], failure_dir=fail)
    assert not r.passed and (fail / "a" / "diff.png").exists()
    suite.write_text(_MINI.format(n=2).replace("height = 16", "height = 12"))
    (r,) = check_suite(suite, only=["a"], failure_dir=fail)
    assert not r.passed and r.message.startswith("size:")
    assert sorted(p.name for p in (fail / "a").iterdir()) == ["reference.png", "result.png"]
    assert iio.imread(fail / "a" / "result.png").shape[:2] == (12, 24)
    assert iio.imread(fail / "a" / "reference.png").shape[:2] == (16, 24)
    suite.write_text(_MINI.format(n=2))
    (r,) = check_suite(suite, only=["a"], failure_dir=fail)
    assert r.passed and not (fail / "a").exists()
    assert (fail / "other" / "result.png").read_bytes() == golden
