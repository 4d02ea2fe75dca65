"""The comparison tool a backend uses against the golden images."""

import json
import re

import numpy as np
import pytest

from refnpr.compare import compare_dirs, compare_images, format_table, load_image
from refnpr.image import write_png_atomic


def _img(seed: int, shape=(24, 32)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.integers(0, 256, shape + (4,), dtype=np.uint8)
    a[..., 3] = 255
    return a


def test_identical_images_have_zero_error():
    a = _img(0).astype(float) / 255
    m = compare_images(a, a, name="x")
    assert (m.max_abs, m.rmse, m.frac_over) == (0.0, 0.0, 0.0)
    assert m.ssim == pytest.approx(1.0)


def test_metrics_against_naive_computation():
    a = _img(1).astype(float) / 255
    b = a.copy()
    b[3, 4, 0] = 1.0 - b[3, 4, 0]  # one pixel flipped in red
    b[10, 10, :3] += 1 / 255  # one pixel off by one code value (under tolerance)
    b = np.clip(b, 0, 1)
    m = compare_images(a, b, tolerance=2 / 255)
    diff = np.abs(b - a)
    assert m.max_abs == pytest.approx(diff.max())
    assert m.rmse == pytest.approx(np.sqrt((diff**2).mean()))
    assert m.frac_over == pytest.approx(1 / (24 * 32))
    assert m.ssim < 1.0


def test_an_image_holding_nan_or_inf_fails_naming_the_first_pixel():
    a = _img(2).astype(float) / 255
    b = a.copy()
    b[5, 7, 1] = np.nan
    b[9, 2, 0] = np.inf
    m = compare_images(a, b, name="x")
    assert m.status == "nonfinite" and not m.passes(max_frac_over=1.0, min_ssim=0.0)
    assert "the candidate holds 2 NaN or infinite value(s), the first at pixel (x=7, y=5)" in (
        m.message
    )
    assert compare_images(b, a).message.startswith("the reference holds 2")
    assert m.as_dict()["max_abs"] is None


def test_compare_dirs_reports_missing_and_size(tmp_path):
    ref, cand, out = tmp_path / "ref", tmp_path / "cand", tmp_path / "out"
    write_png_atomic(ref / "same.png", _img(2))
    write_png_atomic(ref / "absent.png", _img(3))
    write_png_atomic(ref / "small.png", _img(4))
    write_png_atomic(cand / "same.png", _img(2))
    write_png_atomic(cand / "small.png", _img(4, (12, 16)))
    results = {m.name: m for m in compare_dirs(ref, cand, out_dir=out)}
    assert results["same"].status == "ok" and results["same"].max_abs == 0
    assert results["absent"].status == "missing"
    assert results["small"].status == "size"
    assert (out / "same.diff.png").exists()
    report = json.loads((out / "report.json").read_text())
    assert {r["name"] for r in report} == {"same", "absent", "small"}
    assert "absent" in format_table(list(results.values()))


def test_a_broken_link_as_candidate_is_unreadable_not_missing(tmp_path):
    """A candidate that is a symbolic link to nothing is there (the backend wrote a link) but
    cannot be read: reported as such, naming the link's target, not as "no candidate"."""
    ref, cand = tmp_path / "ref", tmp_path / "cand"
    write_png_atomic(ref / "a.png", _img(2))
    cand.mkdir()
    (cand / "a.png").symlink_to(tmp_path / "renders" / "a.png")
    (m,) = compare_dirs(ref, cand)
    assert m.status == "unreadable" and "symbolic link to" in m.message, m
    assert "renders/a.png" in m.message and "No such file" in m.message
    (cand / "a.png").unlink()
    (cand / "a.png").symlink_to("a.png")  # a loop
    (m,) = compare_dirs(ref, cand)
    assert m.status == "unreadable" and "too many levels of symbolic links" in m.message.lower()


def test_rgb_and_gray_pngs_load_as_rgba(tmp_path):
    write_png_atomic(tmp_path / "g.png", np.full((2, 3), 128, np.uint8))
    g = load_image(tmp_path / "g.png")
    assert (
        g.shape == (2, 3, 4) and np.all(g[..., 3] == 1) and g[0, 0, 0] == pytest.approx(128 / 255)
    )


def test_not_a_directory(tmp_path):
    with pytest.raises(ValueError, match="candidate_dir: .* is not a directory"):
        compare_dirs(tmp_path, tmp_path / "nope")


def test_a_threshold_of_k_levels_accepts_every_difference_of_k_levels():
    """Float64 puts |33/255 - 31/255| an ulp above 2/255 for 65 of the 254 pairs; a difference
    of k 8-bit levels must match a threshold of k/255 whatever the two values are, and one
    level more must not (refnpr.compare and the kit's position-tolerant compare alike)."""
    from refnpr.kit.verdict import position_tolerant_mismatch

    levels = np.arange(256)
    for k in (1, 2, 3):
        lo = levels[: 256 - k]
        a = np.ones((1, lo.size, 4))
        a[..., :3] = lo[None, :, None] / 255
        b, c = a.copy(), a.copy()
        b[..., :3] = (lo[None, :, None] + k) / 255
        c[..., :3] = (lo[None, :, None] + k - 1) / 255
        assert compare_images(a, b, tolerance=k / 255).frac_over == 0.0
        assert compare_images(a, b, tolerance=(k - 1) / 255).frac_over == 1.0
        assert not position_tolerant_mismatch(a, b, threshold=k / 255, deviation=0).any()
        assert position_tolerant_mismatch(a, b, threshold=(k - 1) / 255, deviation=0).all()
        assert not position_tolerant_mismatch(a, c, threshold=(k - 1) / 255, deviation=0).any()


@pytest.mark.parametrize("where", ["ref", "cand", "ref/sub", "cand/x/y"])
def test_out_dir_inside_a_compared_directory_is_refused(tmp_path, where, capsys):
    from refnpr.cli import main

    ref, cand = tmp_path / "ref", tmp_path / "cand"
    write_png_atomic(ref / "a.png", _img(5))
    write_png_atomic(cand / "a.png", _img(6))
    with pytest.raises(ValueError, match=r"out_dir: .* inside the (reference|candidate) dir"):
        compare_dirs(ref, cand, out_dir=tmp_path / where)
    assert main(["compare", str(ref), str(cand), "--out", str(tmp_path / where)]) == 2
    assert "--out: " in capsys.readouterr().err
    assert sorted(p.name for p in ref.rglob("*")) == ["a.png"]
    assert sorted(p.name for p in cand.rglob("*")) == ["a.png"]


@pytest.mark.parametrize(
    ("json_arg", "match"),
    [
        ("ref/a.png", r"--json: expected a \.json file name, got '.*ref/a\.png'"),
        ("r.txt", r"--json: expected a \.json file name"),
    ],
)
def test_json_must_be_a_json_file(tmp_path, json_arg, match, capsys):
    from refnpr.cli import main

    ref, cand = tmp_path / "ref", tmp_path / "cand"
    write_png_atomic(ref / "a.png", _img(5))
    write_png_atomic(cand / "a.png", _img(5))
    before = (ref / "a.png").read_bytes()
    assert main(["compare", str(ref), str(cand), "--json", str(tmp_path / json_arg)]) == 2
    assert re.search(match, capsys.readouterr().err)
    assert (ref / "a.png").read_bytes() == before
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a.png", "a.png", "cand", "ref"]


def test_an_empty_json_name_is_refused(tmp_path, capsys):
    from refnpr.cli import main

    ref, cand = tmp_path / "ref", tmp_path / "cand"
    write_png_atomic(ref / "a.png", _img(5))
    write_png_atomic(cand / "a.png", _img(5))
    assert main(["compare", str(ref), str(cand), "--json", ""]) == 2
    assert "--json: expected a file name ending in .json, got ''" in capsys.readouterr().err


@pytest.mark.parametrize("shape", [(1, 1), (1, 9), (2, 9), (9, 2)])
def test_ssim_of_an_image_too_small_for_its_window_is_not_judged(tmp_path, shape, capsys):
    from refnpr.cli import main

    a = _img(7, shape)
    b = a.copy()
    b[0, 0, 0] = a[0, 0, 0] ^ 1  # one level: within the tolerance
    m = compare_images(a / 255, b / 255, name="x")
    assert np.isnan(m.ssim) and m.frac_over == 0.0
    assert m.passes(max_frac_over=0.0, min_ssim=0.99)
    assert m.as_dict()["ssim"] is None
    assert format_table([m]).splitlines()[1].endswith("    n/a")
    assert compare_images(a / 255, a / 255).ssim == 1.0  # identical: 1 at any size
    far = b.copy()
    far[0, 0, :3] = 255 - a[0, 0, :3]
    assert not compare_images(a / 255, far / 255).passes(max_frac_over=0.0, min_ssim=0.0)
    ref, cand = tmp_path / "ref", tmp_path / "cand"
    write_png_atomic(ref / "t.png", a)
    write_png_atomic(cand / "t.png", b)
    out = tmp_path / "m.json"
    assert main(["compare", str(ref), str(cand), "--json", str(out), "--min-ssim", "0.99"]) == 0
    assert "n/a" in capsys.readouterr().out
    assert json.loads(out.read_text())[0]["ssim"] is None  # strict JSON: no NaN
