"""``refnpr kit check``: verdicts, the position-tolerant compare, G-buffer cases, report, JSON.

Most tests use a tiny kit written here by hand (``tiny_kit``: two image cases and one G-buffer
case following /docs/kit.md's layout) so that each test can damage one render on purpose; the
``kit_dir`` session fixture (the whole exported suite, tests/kit/conftest.py) proves that
refnpr's own renders pass and that a shifted one fails.
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.golden import SUITE_DIR
from refnpr.image import linear_to_srgb
from refnpr.kit.check import CaseCheck, check_kit, position_tolerant_mismatch, run

THRESHOLD = 2.0 / 255


# -- a hand-made kit ---------------------------------------------------------------------------


def _write_exr(path: Path, rgba: np.ndarray) -> None:
    import OpenEXR

    ch = {n: np.ascontiguousarray(rgba[..., i].astype(np.float32)) for i, n in enumerate("RGBA")}
    path.parent.mkdir(parents=True, exist_ok=True)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, ch) as f:
        f.write(str(path))


def _disc_linear(w: int, h: int) -> np.ndarray:
    """(h, w, 4) float32 linear RGBA: a shaded disc and a one-pixel line on opaque white."""
    y, x = np.mgrid[0:h, 0:w] + 0.5
    img = np.ones((h, w, 4), dtype=np.float32)
    r = np.hypot(x - 0.45 * w, y - 0.5 * h)
    inside = r < 0.3 * h
    shade = np.clip(0.2 + 0.8 * (x / w), 0, 1)
    img[inside, 0] = shade[inside]
    img[inside, 1] = 0.1
    img[inside, 2] = 1.0 - shade[inside]
    img[3, 2:-2, :3] = 0.0  # a thin dark line
    return img


def _gradient_linear(w: int, h: int) -> np.ndarray:
    """(h, w, 4) float32: a smooth gradient with a transparent corner (alpha 0)."""
    y, x = np.mgrid[0:h, 0:w] + 0.5
    img = np.stack([x / w, y / h, 0.5 * np.ones_like(x), np.ones_like(x)], axis=-1)
    img[: h // 3, : w // 3, 3] = 0.0
    return img.astype(np.float32)


def _srgb8(lin: np.ndarray) -> np.ndarray:
    out = np.empty(lin.shape, dtype=np.uint8)
    out[..., :3] = np.rint(linear_to_srgb(lin[..., :3]) * 255)
    out[..., 3] = np.rint(np.clip(lin[..., 3], 0, 1) * 255)
    return out


def _image_case(root: Path, name: str, lin: np.ndarray, background, deviation: int = 1) -> dict:
    d = root / name
    d.mkdir(parents=True)
    iio.imwrite(d / "expected.png", _srgb8(lin))
    _write_exr(d / "expected.exr", lin)
    h, w = lin.shape[:2]
    case = {
        "name": name,
        "description": "hand-made test case",
        "kind": "image",
        "width": w,
        "height": h,
        "spp": 1,
        "background": list(background),
        "style": {"name": "smooth", "params": {}},
        "expected": {"png": "expected.png", "linear": "expected.exr"},
        "tolerance": {
            "threshold": THRESHOLD,
            "max_frac_over": 0.0005,
            "min_ssim": 0.995,
            "position_deviation": deviation,
            "compare_on": "srgb8 composited over black by alpha, as refnpr.compare",
        },
    }
    (d / "case.json").write_text(json.dumps(case))
    return {"name": name, "kind": "image", "style": "smooth", "case": f"{name}/case.json"}


def _gbuffer_arrays(w: int, h: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(7)
    tri = rng.integers(0, 50, size=(h, w)).astype(np.int32)
    tri[:, : w // 4] = -1
    depth = (1.0 + rng.random((h, w))).astype(np.float32)
    depth[tri < 0] = np.inf
    normal = rng.normal(size=(h, w, 3)).astype(np.float32)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    normal[tri < 0] = 0.0
    return {"tri_id": tri, "depth": depth, "normal": normal}


def _gbuffer_case(root: Path, name: str, arrays: dict[str, np.ndarray]) -> dict:
    d = root / name
    (d / "expected").mkdir(parents=True)
    chans = {}
    for ch, a in arrays.items():
        np.save(d / "expected" / f"{ch}.npy", a)
        chans[ch] = {"file": f"expected/{ch}.npy", "dtype": str(a.dtype), "shape": list(a.shape)}
    h, w = arrays["tri_id"].shape
    case = {
        "name": name,
        "kind": "gbuffer",
        "width": w,
        "height": h,
        "spp": 1,
        "style": None,
        "expected": {"channels": chans, "format": "npy"},
        "tolerance": {"rtol": 1e-5, "atol": 1e-6, "discrete": {"tri_id": {"max_pixels": 2}}},
    }
    (d / "case.json").write_text(json.dumps(case))
    return {"name": name, "kind": "gbuffer", "style": None, "case": f"{name}/case.json"}


@pytest.fixture
def tiny_kit(tmp_path: Path) -> Path:
    root = tmp_path / "kit"
    root.mkdir()
    cases = [
        _image_case(root, "disc", _disc_linear(40, 30), [1, 1, 1, 1]),
        _image_case(root, "gradient", _gradient_linear(32, 24), [0, 0, 0, 0]),
        _gbuffer_case(root, "gbuf", _gbuffer_arrays(20, 16)),
    ]
    index = {"format": "refnpr-kit", "version": 1, "refnpr": "test", "cases": cases}
    (root / "index.json").write_text(json.dumps(index))
    return root


def _perfect_renders(kit: Path, out: Path, *, exr: bool = False) -> Path:
    """What a perfect backend writes: expected images/channels under the render names."""
    out.mkdir(parents=True, exist_ok=True)
    index = json.loads((kit / "index.json").read_text())
    for c in index["cases"]:
        case_dir = kit / Path(c["case"]).parent
        case = json.loads((kit / c["case"]).read_text())
        if case["kind"] == "image":
            shutil.copy(case_dir / case["expected"]["png"], out / f"{c['name']}.png")
            if exr:
                shutil.copy(case_dir / case["expected"]["linear"], out / f"{c['name']}.exr")
        else:
            (out / c["name"]).mkdir(exist_ok=True)
            for ch, e in case["expected"]["channels"].items():
                shutil.copy(case_dir / e["file"], out / c["name"] / f"{ch}.npy")
    return out


def _by_name(results: list[CaseCheck]) -> dict[str, CaseCheck]:
    return {r.name: r for r in results}


def _args(kit, renders, report=None, json_path=None) -> argparse.Namespace:
    return argparse.Namespace(
        kit_dir=str(kit), renders_dir=str(renders), report=report, json=json_path
    )


# -- verdicts on the hand-made kit -------------------------------------------------------------


def test_perfect_renders_pass(tiny_kit, tmp_path, capsys):
    renders = _perfect_renders(tiny_kit, tmp_path / "renders", exr=True)
    results = check_kit(tiny_kit, renders)
    assert [r.name for r in results] == ["disc", "gradient", "gbuf"]
    assert all(r.passed and r.status == "ok" for r in results), [r.message for r in results]
    disc = _by_name(results)["disc"].metrics
    assert disc["max_abs"] == 0 and disc["frac_over_position"] == 0 and disc["ssim"] == 1.0
    assert disc["linear_max_abs"] == 0 and disc["linear_frac_over"] == 0
    assert run(_args(tiny_kit, renders)) == 0
    assert "3 cases: 3 passed, 0 failed" in capsys.readouterr().out


def _edit_png(path: Path, fn) -> None:
    iio.imwrite(path, fn(iio.imread(path)))


def test_shift_by_three_pixels_fails_shift_by_one_is_position_tolerated(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    original = iio.imread(renders / "disc.png")
    iio.imwrite(renders / "disc.png", np.roll(original, 1, axis=1))
    one = _by_name(check_kit(tiny_kit, renders))["disc"]
    assert one.metrics["frac_over"] > 0.01  # the plain per-pixel compare sees the shift
    assert one.metrics["frac_over_position"] == 0.0  # N = 1 absorbs it
    iio.imwrite(renders / "disc.png", np.roll(original, 3, axis=1))
    three = _by_name(check_kit(tiny_kit, renders))
    assert not three["disc"].passed and three["disc"].status == "ok"
    assert three["disc"].metrics["frac_over_position"] > 0.0005
    assert "frac_over_position=" in three["disc"].message
    assert three["gradient"].passed and three["gbuf"].passed  # one bad case hides nothing
    assert run(_args(tiny_kit, renders)) == 1


def test_tinted_render_fails(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")

    def tint(a):
        b = a.astype(np.float64)
        b[..., 0] *= 0.9
        return np.rint(b).astype(np.uint8)

    _edit_png(renders / "gradient.png", tint)
    r = _by_name(check_kit(tiny_kit, renders))["gradient"]
    assert not r.passed
    assert r.metrics["frac_over_position"] > 0.5
    assert r.metrics["max_abs"] > 20 / 255 and r.metrics["ssim"] < 1.0


def test_dropped_thin_line_fails_although_the_cts_one_sided_test_accepts_it(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")

    def erase_line(a):
        a = a.copy()
        a[3, 2:-2] = a[5, 2:-2]  # the rows next to the line are background
        return a

    _edit_png(renders / "disc.png", erase_line)
    r = _by_name(check_kit(tiny_kit, renders))["disc"]
    assert r.metrics["frac_over_position_cts"] == 0.0  # every result pixel has a match nearby
    assert r.metrics["frac_over_position"] == pytest.approx(36 / 1200)  # the line's pixels
    assert not r.passed


@pytest.mark.parametrize(
    ("damage", "status", "match"),
    [
        ("missing", "missing", "no render"),
        ("garbage", "unreadable", "cannot read"),
        ("size", "size", "is 39x30, the case is 40x30"),
    ],
)
def test_missing_unreadable_and_wrong_size_renders_fail(tiny_kit, tmp_path, damage, status, match):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    target = renders / "disc.png"
    if damage == "missing":
        target.unlink()
    elif damage == "garbage":
        target.write_bytes(b"not a png at all")
    else:
        _edit_png(target, lambda a: a[:, :-1])
    results = _by_name(check_kit(tiny_kit, renders))
    assert not results["disc"].passed and results["disc"].status == status
    assert match in results["disc"].message
    assert results["gradient"].passed
    assert run(_args(tiny_kit, renders)) == 1


def test_bad_exr_fails_the_case_and_linear_metrics_see_a_difference(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r", exr=True)
    lin = _disc_linear(40, 30)
    lin[10:12, 10:12, 1] += 0.25
    _write_exr(renders / "disc.exr", lin)
    r = _by_name(check_kit(tiny_kit, renders))["disc"]
    assert r.passed  # the PNG decides; the EXR metrics are reported
    assert r.metrics["linear_max_abs"] == pytest.approx(0.25, abs=1e-6)
    assert r.metrics["linear_frac_over"] == pytest.approx(4 / 1200)
    (renders / "disc.exr").write_bytes(b"\x76\x2f\x31\x01garbage")
    r = _by_name(check_kit(tiny_kit, renders))["disc"]
    assert not r.passed and r.status == "unreadable" and "disc.exr" in r.message
    assert r.metrics["frac_over_position"] == 0.0  # the PNG's metrics are kept


def test_transparent_pixels_compare_by_coverage(tiny_kit, tmp_path):
    """A colour change where alpha is 0 is invisible (composited over black); alpha is not."""
    renders = _perfect_renders(tiny_kit, tmp_path / "r")

    def recolour_transparent(a):
        a = a.copy()
        a[:8, :10, :3] = 255 - a[:8, :10, :3]
        return a

    _edit_png(renders / "gradient.png", recolour_transparent)
    assert _by_name(check_kit(tiny_kit, renders))["gradient"].passed

    def uncover(a):
        a = a.copy()
        a[:8, :10, 3] = 255
        return a

    _edit_png(renders / "gradient.png", uncover)
    assert not _by_name(check_kit(tiny_kit, renders))["gradient"].passed


# -- G-buffer cases ----------------------------------------------------------------------------


def _gb(renders: Path, ch: str) -> Path:
    return renders / "gbuf" / f"{ch}.npy"


def test_gbuffer_discrete_channel_exact_except_max_pixels(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    tri = np.load(_gb(renders, "tri_id"))
    tri2 = tri.copy()
    tri2[5, 10] += 1
    tri2[6, 11] += 1
    np.save(_gb(renders, "tri_id"), tri2)
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert r.passed and r.channels["tri_id"]["bad_pixels"] == 2
    tri2[7, 12] += 1
    np.save(_gb(renders, "tri_id"), tri2)
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert not r.passed and r.channels["tri_id"]["bad_pixels"] == 3
    assert "tri_id: 3 bad pixel(s) (allowed 2)" in r.message


def test_gbuffer_float_channels_by_rtol_atol_and_nonfinite_pattern(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    depth = np.load(_gb(renders, "depth"))
    within = np.where(np.isfinite(depth), depth * (1 + 4e-6), depth).astype(np.float32)
    np.save(_gb(renders, "depth"), within)
    assert _by_name(check_kit(tiny_kit, renders))["gbuf"].passed
    beyond = depth.copy()
    beyond[8, 12] *= 1 + 1e-3
    np.save(_gb(renders, "depth"), beyond)
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert not r.passed and r.channels["depth"]["bad_pixels"] == 1
    beyond[9, 12] *= 1 + 1e-3
    np.save(_gb(renders, "depth"), beyond)
    case = json.loads((tiny_kit / "gbuf" / "case.json").read_text())
    n_finite = int(np.isfinite(depth).sum())
    case["tolerance"]["max_frac_over"] = 2 / n_finite  # two bad samples of depth allowed
    (tiny_kit / "gbuf" / "case.json").write_text(json.dumps(case))
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert r.passed and r.channels["depth"]["frac_bad"] == pytest.approx(2 / n_finite)
    beyond[10, 12] *= 1 + 1e-3
    np.save(_gb(renders, "depth"), beyond)
    assert not _by_name(check_kit(tiny_kit, renders))["gbuf"].passed
    case["tolerance"]["max_frac_over"] = 0.0
    (tiny_kit / "gbuf" / "case.json").write_text(json.dumps(case))
    pattern = depth.copy()
    pattern[0, 0] = 5.0  # was inf (an empty pixel)
    np.save(_gb(renders, "depth"), pattern)
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert not r.passed and r.channels["depth"]["nonfinite_mismatch"] == 1
    normal = np.load(_gb(renders, "normal"))
    np.save(_gb(renders, "depth"), depth)
    normal[3, 7, 2] += 0.01
    np.save(_gb(renders, "normal"), normal)
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert not r.passed and r.channels["normal"]["bad_pixels"] == 1
    assert r.channels["normal"]["max_abs"] == pytest.approx(0.01, rel=1e-3)


def test_gbuffer_missing_channel_wrong_shape_and_missing_case(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    _gb(renders, "normal").unlink()
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert r.status == "channels" and "['normal']" in r.message
    np.save(_gb(renders, "normal"), np.zeros((16, 20, 2), np.float32))
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert r.status == "size" and "(16, 20, 2)" in r.message
    shutil.rmtree(renders / "gbuf")
    r = _by_name(check_kit(tiny_kit, renders))["gbuf"]
    assert r.status == "missing" and not r.passed


# -- the position-tolerant compare against a naive loop ----------------------------------------


def _naive_no_match(a, b, thr, n):
    h, w = a.shape[:2]
    out = np.ones((h, w), dtype=bool)
    for y in range(h):
        for x in range(w):
            for yy in range(max(0, y - n), min(h, y + n + 1)):
                for xx in range(max(0, x - n), min(w, x + n + 1)):
                    if (
                        max(abs(float(a[y, x, c]) - float(b[yy, xx, c])) for c in range(a.shape[2]))
                        <= thr
                    ):
                        out[y, x] = False
    return out


@pytest.mark.parametrize("n", [0, 1, 2])
@pytest.mark.parametrize("seed", [1, 2])
def test_position_tolerant_compare_matches_a_naive_loop(n, seed):
    rng = np.random.default_rng(seed)
    h, w = 9, 13
    ref = rng.integers(0, 4, size=(h, w, 4)) / 255.0  # few levels: many near matches
    res = ref.copy()
    noisy = rng.random((h, w)) < 0.4
    res[noisy] = rng.integers(0, 6, size=(int(noisy.sum()), 4)) / 255.0
    thr = 1.5 / 255
    one_sided = _naive_no_match(res, ref, thr, n)
    both = one_sided | _naive_no_match(ref, res, thr, n)
    got_cts = position_tolerant_mismatch(ref, res, threshold=thr, deviation=n, symmetric=False)
    got = position_tolerant_mismatch(ref, res, threshold=thr, deviation=n)
    np.testing.assert_array_equal(got_cts, one_sided)
    np.testing.assert_array_equal(got, both)
    assert 0 < both.sum() < both.size  # the case exercises both outcomes


def test_position_tolerant_compare_validates_its_inputs():
    a = np.zeros((4, 5, 4))
    with pytest.raises(ValueError, match=r"deviation: expected an integer >= 0.*-1"):
        position_tolerant_mismatch(a, a, threshold=0.01, deviation=-1)
    with pytest.raises(ValueError, match=r"reference, result: .*\(4, 5, 4\) and \(4, 4, 4\)"):
        position_tolerant_mismatch(a, a[:, :4], threshold=0.01, deviation=1)
    with pytest.raises(ValueError, match="threshold: expected a finite number"):
        position_tolerant_mismatch(a, a, threshold=float("nan"), deviation=1)


# -- report and JSON ---------------------------------------------------------------------------


def test_report_images_and_json(tiny_kit, tmp_path):
    """The report gets every case (the checker streams them; the report's own tests pin its
    pages) and the JSON its summary; a case without a render comes last, with its reference."""
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    _edit_png(renders / "disc.png", lambda a: np.roll(a, 3, axis=1))
    (renders / "gradient.png").unlink()
    report, js = tmp_path / "report", tmp_path / "out" / "check.json"
    got = check_kit(tiny_kit, renders, report_dir=report, json_path=js)
    assert [r.name for r in got] == ["disc", "gbuf", "gradient"]  # missing last
    results = _by_name(got)
    disc = results["disc"]
    assert {"reference", "result", "mask"} <= set(disc.images)
    mask = iio.imread(report / disc.images["mask"])
    red = np.all(mask == [255, 0, 0], axis=-1)
    black = np.all(mask == [0, 0, 0], axis=-1)
    green = np.all(mask == [0, 255, 0], axis=-1)
    assert (red | black | green).all() and red.any() and black.any() and green.any()
    assert red.mean() == pytest.approx(disc.metrics["frac_over_position"])
    ref_png = iio.imread(report / disc.images["reference"])
    np.testing.assert_array_equal(ref_png, iio.imread(tiny_kit / "disc" / "expected.png")[..., :3])
    assert "mask" in results["gbuf"].images and "reference" in results["gradient"].images
    page = (report / "index.html").read_text()
    assert "cases/disc/mask.png" in page
    doc = json.loads(js.read_text())
    assert doc["summary"] == {
        "cases": 3,
        "passed": 1,
        "failed": 1,
        "missing": 1,
        "missing_policy": "fail",
    }
    assert doc["selection"] == {"only": None, "styles": None}
    rows = {c["name"]: c for c in doc["cases"]}
    assert rows["gradient"]["status"] == "missing" and rows["gradient"]["error"] is None
    assert rows["disc"]["metrics"]["frac_over_position"] == disc.metrics["frac_over_position"]
    assert rows["gbuf"]["channels"]["tri_id"]["kind"] == "discrete"
    assert rows["disc"]["style"] == "smooth" and rows["gbuf"]["style"] == "gbuffer"


def test_clear_errors_for_a_directory_that_is_not_a_kit(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    with pytest.raises(
        ValueError, match=r"kit_dir: .*nowhere.* is not a directory \(it does not exist\)"
    ):
        check_kit(tmp_path / "nowhere", renders)
    with pytest.raises(ValueError, match="has no index.json; export a kit"):
        check_kit(renders, renders)
    with pytest.raises(ValueError, match=r"renders_dir: .* is not a directory \(it is a file\)"):
        check_kit(tiny_kit, renders / "disc.png")
    with pytest.raises(ValueError, match="json_path: .* is a directory"):
        check_kit(tiny_kit, renders, json_path=tmp_path)
    (tiny_kit / "index.json").write_text(
        json.dumps({"format": "refnpr-kit", "version": 2, "cases": []})
    )
    with pytest.raises(ValueError, match="kit format version 2; this refnpr reads version 1"):
        check_kit(tiny_kit, renders)


def test_a_broken_case_json_fails_that_case_only(tiny_kit, tmp_path):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    case = json.loads((tiny_kit / "disc" / "case.json").read_text())
    case["tolerance"]["max_frac_over"] = "auto"
    (tiny_kit / "disc" / "case.json").write_text(json.dumps(case))
    results = _by_name(check_kit(tiny_kit, renders))
    assert results["disc"].status == "kit" and "tolerance.max_frac_over" in results["disc"].message
    assert results["gradient"].passed


# -- partial backends: --only, --styles, --missing ---------------------------------------------


def test_only_checks_the_named_cases_and_unknown_names_list_the_kit(tiny_kit, tmp_path, capsys):
    from refnpr.cli import main

    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    (renders / "gradient.png").unlink()
    assert [r.name for r in check_kit(tiny_kit, renders, only=["gbuf", "disc"])] == ["disc", "gbuf"]
    assert main(["kit", "check", str(tiny_kit), str(renders), "--only", "disc", "gbuf"]) == 0
    assert "2 cases: 2 passed, 0 failed" in capsys.readouterr().out
    with pytest.raises(ValueError) as info:
        check_kit(tiny_kit, renders, only=["dsic", "nope"])
    msg = str(info.value)
    assert "only: unknown case names 'dsic' (did you mean disc?), 'nope'; " in msg
    assert "the kit has 3 case names: disc, gradient, gbuf" in msg
    assert main(["kit", "check", str(tiny_kit), str(renders), "--only", "dsic"]) == 2
    assert "unknown case names 'dsic'" in capsys.readouterr().err
    with pytest.raises(TypeError, match="only: expected a list of names, got 'disc'"):
        check_kit(tiny_kit, renders, only="disc")


def test_styles_come_from_case_json(tiny_kit, tmp_path, capsys):
    from refnpr.cli import main

    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    case = json.loads((tiny_kit / "gradient" / "case.json").read_text())
    case["style"] = {"name": "toon", "params": {}}  # index.json still says "smooth"
    (tiny_kit / "gradient" / "case.json").write_text(json.dumps(case))
    smooth = check_kit(tiny_kit, renders, styles=["smooth"])
    assert [(r.name, r.style) for r in smooth] == [("disc", "smooth")]
    both = check_kit(tiny_kit, renders, styles=["toon", "gbuffer"])
    assert [(r.name, r.style) for r in both] == [("gradient", "toon"), ("gbuf", "gbuffer")]
    assert [
        r.name for r in check_kit(tiny_kit, renders, only=["disc", "gbuf"], styles=["smooth"])
    ] == ["disc"]
    with pytest.raises(ValueError, match="no case of the kit is both in --only and of --styles"):
        check_kit(tiny_kit, renders, only=["disc"], styles=["toon"])
    with pytest.raises(
        ValueError, match=r"styles: unknown styles 'smoth' \(did you mean smooth\?\); the kit has"
    ):
        check_kit(tiny_kit, renders, styles=["smoth"])
    argv = ["kit", "check", str(tiny_kit), str(renders), "--styles", "xtoon"]
    assert main(argv) == 2
    assert "the kit has 3 styles: gbuffer, smooth, toon" in capsys.readouterr().err


def test_missing_renders_are_listed_last_and_counted(tiny_kit, tmp_path, capsys):
    from refnpr.cli import main

    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    (renders / "disc.png").unlink()
    results = check_kit(tiny_kit, renders)
    assert [(r.name, r.status) for r in results] == [
        ("gradient", "ok"),
        ("gbuf", "ok"),
        ("disc", "missing"),
    ]
    argv = ["kit", "check", str(tiny_kit), str(renders)]
    assert main(argv) == 1
    out = capsys.readouterr().out.splitlines()
    listed = out.index("missing: 1 case(s) without a render (each fails):")
    assert out[listed + 1].split() == ["disc", "no", "render", "'disc.png'"]
    assert max(i for i, line in enumerate(out) if line.startswith(("gradient", "gbuf"))) < listed
    assert out[-1] == "3 cases: 2 passed, 0 failed, 1 missing (failing; --missing skip skips them)"
    js = tmp_path / "m.json"
    assert main([*argv, "--missing", "skip", "--json", str(js)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "missing: 1 case(s) without a render (skipped):" in out
    assert out[-1] == "3 cases: 2 passed, 0 failed, 1 missing (skipped)"
    summary = json.loads(js.read_text())["summary"]
    assert summary == {"cases": 3, "passed": 2, "failed": 0, "missing": 1, "missing_policy": "skip"}
    _edit_png(renders / "gradient.png", lambda a: 255 - a)  # a real failure still fails
    assert main([*argv, "--missing", "skip"]) == 1
    assert "3 cases: 1 passed, 1 failed, 1 missing (skipped)" in capsys.readouterr().out
    with pytest.raises(ValueError, match="missing: expected 'fail' or 'skip', got 'ignore'"):
        check_kit(tiny_kit, renders, missing="ignore")


# -- the whole exported suite (the kit_dir session fixture) ------------------------------------


GOLDEN = SUITE_DIR


def _golden_renders(kit: Path, out: Path) -> tuple[Path, int]:
    """refnpr's own renders as a backend would write them: refnpr/suite/<case>.png for image cases;
    G-buffer cases keep the kit's expected channels (refnpr's rasterization of the kit's
    float32 geometry, which refnpr/suite/<case>.npz, made from float64 meshes, is not). Returns the
    number of image cases taken from refnpr/suite/."""
    _perfect_renders(kit, out)
    taken = 0
    for c in json.loads((kit / "index.json").read_text())["cases"]:
        png = GOLDEN / f"{c['name']}.png"
        if c["kind"] == "image" and png.is_file():
            shutil.copy(png, out / png.name)
            taken += 1
    return out, taken


def test_refnpr_own_renders_pass_the_whole_kit_and_a_shifted_one_fails(kit_dir, tmp_path):
    renders, taken = _golden_renders(Path(kit_dir), tmp_path / "r")
    results = check_kit(kit_dir, renders, report_dir=tmp_path / "report")
    assert taken == sum(r.kind == "image" for r in results)  # each has its golden PNG
    failed = [(r.name, r.status, r.message) for r in results if not r.passed]
    assert not failed
    assert any(r.kind == "gbuffer" for r in results) and any(r.kind == "image" for r in results)
    assert all(r.metrics.get("frac_over_position", 0.0) == 0.0 for r in results)
    assert (tmp_path / "report" / "index.html").is_file()
    # shift one image case by 3 pixels: with a position deviation below 3 it must fail
    victim = next(r for r in results if r.kind == "image" and r.tolerance["position_deviation"] < 3)
    _edit_png(renders / f"{victim.name}.png", lambda a: np.roll(a, 3, axis=1))
    again = _by_name(check_kit(kit_dir, renders))
    assert not again[victim.name].passed
    assert [n for n, r in again.items() if not r.passed] == [victim.name]


def test_cli_kit_check_exit_status_report_and_json(tiny_kit, tmp_path, capsys):
    from refnpr.cli import main

    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    report, js = tmp_path / "rep", tmp_path / "m.json"
    argv = ["kit", "check", str(tiny_kit), str(renders), "--report", str(report), "--json", str(js)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "3 cases: 3 passed, 0 failed" in out and str(report / "index.html") in out
    assert json.loads(js.read_text())["summary"]["failed"] == 0
    (renders / "gradient.png").rename(renders / "gradient-typo.png")
    assert main(argv) == 1
    out = capsys.readouterr().out
    assert "no render" in out and "not compared: gradient-typo.png" in out
    assert main(["kit", "check", str(tmp_path / "nope"), str(renders)]) == 2
    assert "kit_dir: " in capsys.readouterr().err


def test_a_case_under_3_px_is_judged_without_ssim(tmp_path, capsys):
    """SSIM needs a 3x3 window: a 2x2 case whose render differs within the threshold passes on
    the position-tolerant fraction alone (SSIM n/a in the table, the message and the report's
    margin), and a difference over the threshold still fails it."""
    from refnpr.cli import main

    kit = tmp_path / "kit"
    kit.mkdir()
    index = {"format": "refnpr-kit", "version": 1, "refnpr": "test"}
    index["cases"] = [_image_case(kit, "tiny", _gradient_linear(2, 2), [0, 0, 0, 0])]
    (kit / "index.json").write_text(json.dumps(index))
    renders = _perfect_renders(kit, tmp_path / "r")
    _edit_png(renders / "tiny.png", lambda a: np.where(a > 0, a - 1, a + 1))  # 1/255: within
    r = _by_name(check_kit(kit, renders))["tiny"]
    assert np.isnan(r.metrics["ssim"]) and r.metrics["frac_over_position"] == 0.0
    assert r.passed and "ssim=n/a (not judged" in r.message
    report = tmp_path / "rep"
    assert main(["kit", "check", str(kit), str(renders), "--report", str(report)]) == 0
    row = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("tiny "))
    assert row.split()[-1] == "n/a"
    page = (report / "index.html").read_text()
    assert 'class="ok" data-criterion="min_ssim"' in page and "not judged" in page
    _edit_png(renders / "tiny.png", lambda a: 255 - a)  # far over the threshold
    assert not _by_name(check_kit(kit, renders))["tiny"].passed


def _set_tolerance(kit: Path, name: str, **changes) -> None:
    path = kit / name / "case.json"
    case = json.loads(path.read_text())
    case["tolerance"].update(changes)
    path.write_text(json.dumps(case))


def test_flip_decides_only_where_a_case_says_so(tiny_kit, tmp_path):
    """FLIP is reported by the report; with ``tolerance.max_flip`` it also decides the case."""
    pytest.importorskip("flip_evaluator")  # the `flip` extra (in the test extra)
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    # a render every other criterion lets pass: thresholds opened, a visible blotch of error
    png = iio.imread(renders / "gradient.png").astype(np.int16)
    png[4:20, 4:28, :3] += 40
    iio.imwrite(renders / "gradient.png", np.clip(png, 0, 255).astype(np.uint8))
    _set_tolerance(tiny_kit, "gradient", max_frac_over=1.0, min_ssim=-1.0)
    by_name = {r.name: r for r in check_kit(tiny_kit, renders)}
    assert by_name["gradient"].passed and "flip" not in by_name["gradient"].metrics
    _set_tolerance(tiny_kit, "gradient", max_flip=0.01)
    r = {r.name: r for r in check_kit(tiny_kit, renders)}["gradient"]
    assert not r.passed and r.metrics["flip"] > 0.01 and "flip=" in r.message
    _set_tolerance(tiny_kit, "gradient", max_flip=1.0)
    assert {r.name: r for r in check_kit(tiny_kit, renders)}["gradient"].passed
    _set_tolerance(tiny_kit, "disc", max_flip=0.0)  # identical images: FLIP 0 passes 0
    assert {r.name: r for r in check_kit(tiny_kit, renders)}["disc"].passed


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan"), True, "0.1"])
def test_max_flip_out_of_range_fails_the_case(tiny_kit, tmp_path, value):
    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    path = tiny_kit / "disc" / "case.json"
    text = path.read_text().replace(
        '"compare_on"', f'"max_flip": {json.dumps(value)}, "compare_on"'
    )
    path.write_text(text.replace("NaN", "NaN"))
    r = {r.name: r for r in check_kit(tiny_kit, renders)}["disc"]
    assert not r.passed and r.status == "kit"
    assert "tolerance.max_flip: expected a finite number in [0, 1]" in r.message


def test_max_flip_without_the_package_is_a_clear_case_failure(tiny_kit, tmp_path, monkeypatch):
    import sys

    renders = _perfect_renders(tiny_kit, tmp_path / "r")
    _set_tolerance(tiny_kit, "disc", max_flip=0.05)
    monkeypatch.setitem(sys.modules, "flip_evaluator", None)  # import fails
    r = {r.name: r for r in check_kit(tiny_kit, renders)}["disc"]
    assert not r.passed and r.status == "flip"
    assert "pip install 'refnpr[flip]'" in r.message
