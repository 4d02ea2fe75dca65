"""The ``kit check`` report without a browser: the numbers it shows (worst pixels, heatmap scale,
tolerance margin) against values worked out by hand on tiny arrays, and the files it writes
(names from the kit escaped, nothing outside the report directory, streaming, FLIP optional).
The pages in a real browser: test_report_browser.py."""

from __future__ import annotations

import gc
import json
import os
import sys
import types
import weakref
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.kit.check import CaseCheck, Visual
from refnpr.kit.diagnose import (
    DIVERGING,
    FRAME_RGB,
    GAP_RGB,
    Flip,
    crop_window,
    diff_scale,
    diverging_rgb,
    flip_error,
    magnified_crop,
    pooled_diff,
    pooled_mask,
    signed_diff,
    signed_diff_heatmap,
    straight_linear,
    straight_srgb,
    tolerance_margin,
    worst_pixels,
)
from refnpr.kit.report import write_report


def _opaque(h: int, w: int, value: float = 0.0) -> np.ndarray:
    a = np.full((h, w, 4), value)
    a[..., 3] = 1.0
    return a


def _linear(v: float) -> float:
    """IEC 61966-2-1 decoding, written out."""
    return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4


# -- worst pixels ------------------------------------------------------------------------------


def test_worst_pixels_failing_first_then_by_difference_then_reading_order():
    ref = _opaque(3, 4, 0.5)
    res = ref.copy()
    res[1, 2, 0] = 1.0  # (x=2, y=1): |d| 0.5, passes
    res[2, 0, 1] = 0.4  # (x=0, y=2): |d| 0.1, fails
    res[0, 3, 2] = 0.6  # (x=3, y=0): |d| 0.1, fails, earlier in reading order
    res[0, 0, 3] = 0.75  # (x=0, y=0): alpha |d| 0.25, passes
    bad = np.zeros((3, 4), bool)
    bad[2, 0] = bad[0, 3] = True
    got = worst_pixels(ref, res, bad=bad)
    assert [(p.x, p.y, p.fails) for p in got] == [
        (3, 0, True),
        (0, 2, True),
        (2, 1, False),
        (0, 0, False),
    ]
    assert [p.diff for p in got] == pytest.approx([0.1, 0.1, 0.5, 0.25])
    assert got[2].reference == (0.5, 0.5, 0.5, 1.0) and got[2].result == (1.0, 0.5, 0.5, 1.0)
    assert len(worst_pixels(ref, res, bad=bad, count=2)) == 2
    # without a verdict: by difference alone; equal images list nothing
    assert [(p.x, p.y) for p in worst_pixels(ref, res)][:2] == [(2, 1), (0, 0)]
    assert worst_pixels(ref, ref.copy()) == []
    # a failing pixel is listed even when it does not differ (a position-tolerance failure)
    only_bad = np.zeros((3, 4), bool)
    only_bad[1, 1] = True
    assert [(p.x, p.y, p.diff) for p in worst_pixels(ref, ref, bad=only_bad)] == [(1, 1, 0.0)]


def test_worst_pixels_validates_its_inputs():
    a = _opaque(3, 4)
    with pytest.raises(ValueError, match=r"reference, result: .*\(3, 4, 4\) and \(3, 3, 4\)"):
        worst_pixels(a, a[:, :3])
    with pytest.raises(ValueError, match=r"bad: expected an \(H, W\) bool array of shape \(3, 4\)"):
        worst_pixels(a, a, bad=np.zeros((4, 3), bool))
    with pytest.raises(ValueError, match="count: expected an integer >= 0, got -1"):
        worst_pixels(a, a, count=-1)


def test_straight_values_and_their_linear_decoding():
    # composited over black at alpha 0.5: colour 0.25 is straight 0.5
    assert straight_srgb((0.25, 0.1, 0.0, 0.5)) == pytest.approx([0.5, 0.2, 0.0, 0.5])
    assert straight_linear((0.25, 0.02, 0.0, 0.5)) == pytest.approx(
        [_linear(0.5), 0.04 / 12.92, 0.0, 0.5]
    )
    assert _linear(0.5) == pytest.approx(0.21404, abs=1e-5)
    assert straight_srgb((0.3, 0.3, 0.3, 0.0)).tolist() == [0.0, 0.0, 0.0, 0.0]


# -- heatmaps ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("max_abs", "scale"),
    [(0.0, 1), (1 / 255, 1), (1.5 / 255, 2), (3 / 255, 4), (16 / 255, 16), (17 / 255, 32),
     (128 / 255, 128), (129 / 255, 255), (1.0, 255)],
)  # fmt: skip
def test_diff_scale_is_the_smallest_power_of_two_levels_holding_the_difference(max_abs, scale):
    assert diff_scale(max_abs) == scale / 255


def test_diff_scale_refuses_nonsense():
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="max_abs: expected a finite number >= 0"):
            diff_scale(bad)


def test_diverging_colours_are_signed_and_grow_with_magnitude():
    ends = diverging_rgb(np.array([-1.0, 0.0, 1.0, -5.0, 5.0]))
    assert ends.tolist() == [
        list(DIVERGING[0][1]),
        list(DIVERGING[2][1]),
        list(DIVERGING[-1][1]),
        list(DIVERGING[0][1]),  # clipped
        list(DIVERGING[-1][1]),
    ]
    t = np.linspace(0, 1, 21)
    up, down = diverging_rgb(t).astype(int), diverging_rgb(-t).astype(int)
    assert np.all(np.diff(up.sum(-1)) >= 0) and np.all(np.diff(down.sum(-1)) >= 0)
    assert np.all(up[1:, 0] > up[1:, 2]) and np.all(down[1:, 2] > down[1:, 0])  # red / blue


def test_signed_heatmap_keeps_the_sign_per_channel():
    ref = _opaque(2, 3, 0.5)
    res = ref.copy()
    res[0, 0, 0] += 4 / 255  # red up: full positive colour at scale 4/255
    res[1, 2, 2] -= 2 / 255  # blue down: half negative
    res[1, 0, 0] += 1 / 255  # R +1 and G -3 at one pixel: G decides the combined map
    res[1, 0, 1] -= 3 / 255
    scale = diff_scale(np.abs(res - ref).max())
    assert scale == 4 / 255
    assert signed_diff(ref, res)[1, 0] == pytest.approx(-3 / 255)
    one = signed_diff_heatmap(ref, res, scale=scale)
    assert one.shape == (2, 3, 3)
    assert one[0, 0].tolist() == list(DIVERGING[-1][1])
    assert one[1, 2].tolist() == diverging_rgb(np.array(-0.5)).tolist()
    assert one[0, 1].tolist() == list(DIVERGING[2][1])
    grid = signed_diff_heatmap(ref, res, scale=scale, per_channel=True)
    assert grid.shape == (2 * 2 + 2, 2 * 3 + 2, 3)  # R G / B A, 2 px apart
    r, g = grid[:2, :3], grid[:2, 5:8]
    b, a = grid[4:6, :3], grid[4:6, 5:8]
    assert r[0, 0].tolist() == list(DIVERGING[-1][1]) and g[0, 0].tolist() == list(DIVERGING[2][1])
    assert b[1, 2].tolist() == diverging_rgb(np.array(-0.5)).tolist()
    want = diverging_rgb(np.array(-0.75)).astype(int)  # -3/255 of 4/255, up to rounding
    assert np.abs(g[1, 0].astype(int) - want).max() <= 1
    assert (a == DIVERGING[2][1]).all() and (grid[2:4] == GAP_RGB).all()
    with pytest.raises(ValueError, match="scale: expected a finite number > 0"):
        signed_diff_heatmap(ref, res, scale=0.0)


# -- the crop and the thumbnails ---------------------------------------------------------------


def test_crop_window_is_centred_and_moved_inside_the_image():
    assert crop_window((100, 80), 40, 50, 24) == (slice(38, 62), slice(28, 52))
    assert crop_window((100, 80), 1, 99, 24) == (slice(76, 100), slice(0, 24))
    assert crop_window((10, 6), 5, 5, 24) == (slice(0, 10), slice(0, 6))


def test_magnified_crop_repeats_pixels_and_frames_the_worst():
    rng = np.random.default_rng(3)
    ref = _opaque(5, 6)
    ref[..., :3] = rng.integers(0, 256, (5, 6, 3)) / 255
    res = ref.copy()
    res[1, 4, 1] = 1.0
    bad = np.zeros((5, 6), bool)
    bad[1, 4] = True
    zoom, side = 4, 3
    img, (rows, cols) = magnified_crop(ref, res, x=4, y=1, scale=1.0, bad=bad, side=side, zoom=zoom)
    assert (rows, cols) == (slice(0, 3), slice(3, 6))
    panel = side * zoom
    assert img.shape == (panel, 4 * panel + 3 * zoom, 3)
    # reference pixel (x=3, y=2) -> the block at (row 2, col 0) of the first panel, unframed
    want = np.rint(ref[2, 3, :3] * 255)
    assert (img[2 * zoom : 3 * zoom, 0:zoom] == want).all()
    # the worst pixel (x=4, y=1) is block (1, 1): its border is the frame, its inside the pixel
    blk = img[zoom : 2 * zoom, zoom : 2 * zoom]
    assert (blk[0] == FRAME_RGB).all() and (blk[:, -1] == FRAME_RGB).all()
    assert (blk[1:-1, 1:-1] == np.rint(ref[1, 4, :3] * 255)).all()
    # the mask panel (the fourth) shows it red, the others green
    m = img[:, 3 * (panel + zoom) :]
    assert (m[zoom + 1 : 2 * zoom - 1, zoom + 1 : 2 * zoom - 1] == [255, 0, 0]).all()
    assert (m[:zoom, :zoom] == [0, 255, 0]).all()
    assert (img[:, panel : panel + zoom] == GAP_RGB).all()
    with pytest.raises(
        ValueError, match=r"x, y: expected a pixel inside the 6x5 image, got \(6, 1\)"
    ):
        magnified_crop(ref, res, x=6, y=1, scale=1.0)


def test_reduced_thumbnails_keep_a_single_failing_pixel():
    bad = np.zeros((5, 5), bool)
    bad[4, 4] = True
    empty = np.zeros((5, 5), bool)
    empty[:2, :2] = True
    empty[:, 2] = True
    thumb = pooled_mask(bad, empty, 2)
    assert thumb.shape == (3, 3, 3)
    assert thumb[2, 2].tolist() == [255, 0, 0]  # the one failing pixel survives
    assert thumb[0, 0].tolist() == [0, 0, 0]  # a block all background
    assert thumb[0, 1].tolist() == [0, 255, 0]  # partly background: passes
    assert int(np.all(thumb == [255, 0, 0], axis=-1).sum()) == 1
    signed = np.zeros((4, 4))
    signed[0, 1], signed[1, 0] = 0.2, -0.3
    signed[3, 3] = 0.1
    assert pooled_diff(signed, 2).tolist() == [[-0.3, 0.0], [0.0, 0.1]]


# -- the tolerance margin ----------------------------------------------------------------------


def _tol(threshold: float, max_frac: float, dev: int) -> dict:
    return {
        "threshold": threshold,
        "max_frac_over": max_frac,
        "min_ssim": 0.9,
        "position_deviation": dev,
    }


def test_margin_threshold_and_fraction_by_hand():
    ref = _opaque(4, 4)  # black, opaque: differences are exact multiples of 1/255
    res = ref.copy()
    res[0, 0, 0] = 3 / 255
    res[2, 3, 1] = 5 / 255
    # nothing may fail: the threshold must cover the 5-level pixel
    m = tolerance_margin(ref, res, _tol(2 / 255, 0.0, 0), ssim=0.95)
    assert m.pass_threshold == 5 / 255
    assert m.frac == 2 / 16 and not m.frac_ok
    assert m.ssim == 0.95 and m.ssim_ok
    # one pixel in 16 may fail: the 3-level pixel must pass
    m = tolerance_margin(ref, res, _tol(2 / 255, 1 / 16, 0), ssim=0.5)
    assert m.pass_threshold == 3 / 255 and not m.ssim_ok
    # both may fail: any threshold passes
    m = tolerance_margin(ref, res, _tol(2 / 255, 2 / 16, 0), ssim=None)
    assert m.pass_threshold == 0.0 and m.frac_ok and m.ssim is None


def test_margin_with_position_deviation_by_hand():
    ref = _opaque(5, 5)
    res = ref.copy()
    ref[:, 1, :3] = 1.0  # a white column at x = 1 ...
    res[:, 2, :3] = 1.0  # ... drawn one pixel to the right
    exact = tolerance_margin(ref, res, _tol(2 / 255, 0.0, 0), ssim=1.0)
    assert exact.frac == 10 / 25 and exact.pass_threshold == 1.0
    moved = tolerance_margin(ref, res, _tol(2 / 255, 0.0, 1), ssim=1.0)
    assert moved.frac == 0.0 and moved.pass_threshold == 0.0 and moved.deviation == 1


def test_margin_needs_a_complete_tolerance():
    a = _opaque(2, 2)
    assert tolerance_margin(a, a, {}, ssim=1.0) is None
    assert tolerance_margin(a, a, {**_tol(0.01, 0.0, 0), "max_frac_over": "auto"}, ssim=1) is None


# -- FLIP --------------------------------------------------------------------------------------


def test_flip_without_the_package_says_not_installed(monkeypatch):
    monkeypatch.setitem(sys.modules, "flip_evaluator", None)  # import raises ImportError
    a = _opaque(4, 4)
    f = flip_error(a, a)
    assert (f.mean, f.error_map, f.note) == (None, None, "not installed")


def test_flip_passes_srgb_colours_over_black_and_keeps_its_map(monkeypatch):
    seen = {}

    def evaluate(reference, test, dynamic_range):
        seen.update(ref=reference, test=test, range=dynamic_range)
        emap = np.zeros(reference.shape, np.float32)
        emap[0, 1] = (1.0, 0.5, 0.0)
        return emap, 0.125, {}

    monkeypatch.setitem(sys.modules, "flip_evaluator", types.SimpleNamespace(evaluate=evaluate))
    ref, res = _opaque(2, 3, 0.25), _opaque(2, 3, 0.75)
    f = flip_error(ref, res)
    assert f.mean == 0.125 and f.note == ""
    assert seen["range"] == "LDR" and seen["ref"].shape == (2, 3, 3)
    assert seen["ref"].dtype == np.float32 and np.all(seen["test"] == 0.75)
    assert f.error_map.dtype == np.uint8 and f.error_map[0, 1].tolist() == [255, 128, 0]

    def broken(*args):
        raise RuntimeError("bad input\nmore")

    monkeypatch.setitem(sys.modules, "flip_evaluator", types.SimpleNamespace(evaluate=broken))
    assert flip_error(ref, res).note == "failed: bad input"


def test_flip_with_the_real_package():
    pytest.importorskip("flip_evaluator", reason="the optional extra 'flip' is not installed")
    ref = _opaque(16, 16, 0.5)
    res = ref.copy()
    res[8, 8, :3] = 0.0
    f = flip_error(ref, res)
    assert 0 < f.mean < 1 and f.error_map.shape == (16, 16, 3)
    assert flip_error(ref, ref) == Flip(0.0, None)


# -- write_report ------------------------------------------------------------------------------


def _visual(h: int = 6, w: int = 8) -> Visual:
    ref = _opaque(h, w, 0.5)
    res = ref.copy()
    res[2, 5, 0] = 0.9
    bad = np.zeros((h, w), bool)
    bad[2, 5] = True
    return Visual(reference=ref, result=res, bad=bad, empty=np.zeros((h, w), bool))


def _check(name: str, **kw) -> CaseCheck:
    tol = {"threshold": 2 / 255, "max_frac_over": 0.0, "min_ssim": 0.9, "position_deviation": 1}
    base = dict(
        kind="image",
        passed=False,
        status="ok",
        message="frac_over_position=0.02 (allowed 0)",
        metrics={"frac_over_position": 1 / 48, "ssim": 0.99, "max_abs": 0.4},
        tolerance=tol,
    )
    return CaseCheck(name, **{**base, **kw})


def _case_json(kit: Path, name: str, **extra) -> None:
    (kit / name).mkdir(parents=True)
    data = {"name": name, "kind": "image", "style": {"name": "toon", "params": {"n": 3}}}
    (kit / name / "case.json").write_text(json.dumps({**data, **extra}))


def test_report_streams_cases_and_keeps_no_arrays(tmp_path):
    kit = tmp_path / "kit"
    kit.mkdir()
    _case_json(kit, "one")
    arrays = []

    def cases():
        for name in ("one", "two", "three"):
            v = _visual()
            arrays.extend(weakref.ref(a) for a in (v.reference, v.result, v.bad, v.empty))
            yield _check(name), v
            del v
            # the report is done with this case before it asks for the next: its files are there
            assert (tmp_path / "rep" / "cases" / name / "crop.png").is_file()

    out = write_report(tmp_path / "rep", cases(), kit_dir=kit, renders_dir=tmp_path)
    gc.collect()
    assert [c.name for c in out] == ["one", "two", "three"]
    assert len(arrays) == 12 and all(r() is None for r in arrays)  # no array outlives its case
    flip = {"flip"} if flip_error(_opaque(1, 1), _opaque(1, 1, 0.5)).mean is not None else set()
    assert set(out[0].images) == {
        "reference", "result", "diff", "diff_channels", "mask", "crop"
    } | flip  # fmt: skip
    crop = iio.imread(tmp_path / "rep" / out[0].images["crop"])
    assert crop.shape[0] == 6 * 8  # the whole 8 x 6 image, magnified 8x


def test_report_escapes_names_and_writes_only_inside_the_report(tmp_path):
    kit, rep = tmp_path / "kit", tmp_path / "rep"
    kit.mkdir()
    hostile = '../../x/<script>alert("1")</script>\x1b[2J'
    cases = [
        (_check(hostile, message="bad \x1b[31m <b>", style='<img src=x onerror="y">'), _visual()),
        (_check("same"), _visual()),
        (_check("same"), _visual()),  # a repeated name keeps its own files
    ]
    out = write_report(rep, iter(cases), kit_dir=kit, renders_dir=tmp_path)
    written = {p.relative_to(tmp_path).parts[0] for p in tmp_path.rglob("*") if p.is_file()}
    assert written == {"rep"}
    assert out[0].images["mask"].startswith("cases/case-0/")
    assert out[1].images["mask"] == "cases/same/mask.png"
    assert out[2].images["mask"] == "cases/same-2/mask.png"
    page = (rep / "index.html").read_text()
    assert "<script>alert" not in page and "<b>" not in page and "\x1b" not in page
    assert "&lt;script&gt;alert(&quot;1&quot;)&lt;/script&gt;\\x1b[2J" in page
    assert 'onerror="y"' not in page and "&lt;img src=x onerror=&quot;y&quot;&gt;" in page
    case_page = (rep / "cases" / "case-0" / "case.html").read_text()
    assert "<script>alert" not in case_page and "not a valid kit name" in case_page


def test_report_links_into_the_kit_and_shows_derived_texts_escaped(tmp_path):
    kit, rep = tmp_path / "k" / "kit", tmp_path / "reports" / "r1"
    kit.mkdir(parents=True)
    _case_json(kit, "good", derived={"toon_shading": "I = n.l <b>\nline two"})
    out = write_report(rep, iter([(_check("good"), _visual())]), kit_dir=kit, renders_dir=kit)
    assert out[0].name == "good"
    page = (rep / "index.html").read_text()
    assert 'href="../../k/kit/good/case.json"' in page
    assert (rep / "../../k/kit/good/case.json").resolve() == (kit / "good" / "case.json").resolve()
    case_page = (rep / "cases" / "good" / "case.html").read_text()
    assert 'href="../../../../k/kit/good/case.json"' in case_page
    assert "I = n.l &lt;b&gt;\nline two" in case_page
    assert 'data-style="toon"' in page


def test_report_does_not_follow_a_case_json_out_of_the_kit(tmp_path):
    kit, rep = tmp_path / "kit", tmp_path / "rep"
    (kit / "evil").mkdir(parents=True)
    secret = tmp_path / "secret.json"
    secret.write_text(json.dumps({"derived": {"x": "SECRET TEXT"}}))
    os.symlink(secret, kit / "evil" / "case.json")
    (kit / "deep").mkdir()
    (kit / "deep" / "case.json").write_text("[" * 100_000)
    cases = [(_check("evil"), _visual()), (_check("deep"), _visual())]
    write_report(rep, iter(cases), kit_dir=kit, renders_dir=tmp_path)
    evil = (rep / "cases" / "evil" / "case.html").read_text()
    assert "SECRET TEXT" not in evil and "leads outside the kit" in evil
    assert "secret.json" not in (rep / "index.html").read_text()
    deep = (rep / "cases" / "deep" / "case.html").read_text()
    assert "nested deeper than" in deep


def test_report_of_cases_that_got_no_arrays(tmp_path):
    checks = [
        (_check("gone", status="missing", message="no render", metrics={}), Visual()),
        (_check("broken", status="kit", message="tolerance: bad", metrics={}), Visual()),
        (
            _check("small", status="size", message="render is 2x2"),
            Visual(reference=_opaque(6, 8, 0.5)),
        ),
    ]
    out = write_report(tmp_path / "rep", iter(checks), kit_dir=tmp_path, renders_dir=tmp_path)
    assert [set(c.images) for c in out] == [set(), set(), {"reference"}]
    page = (tmp_path / "rep" / "index.html").read_text()
    assert '<td id="n-missing">1</td>' in page and '<td id="n-kit">1</td>' in page
    assert '<td id="n-failed">2</td>' in page
    assert (
        page.index('data-name="broken"')
        < page.index('id="missing"')
        < page.index('data-name="gone"')
    )


def test_report_dir_that_is_a_file_is_refused(tmp_path):
    f = tmp_path / "file"
    f.write_text("")
    with pytest.raises(ValueError, match="report_dir: .* is a file; expected a directory"):
        write_report(f, [], kit_dir=tmp_path, renders_dir=tmp_path)
