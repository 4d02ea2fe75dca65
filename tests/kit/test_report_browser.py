"""The ``kit check`` HTML report opens in a real browser (headless Chromium).

Chromium is Debian's ``chromium`` package, installed by ``.ci/setup``. Without it these tests
FAIL (never skip): the report is a deliverable and must be seen to render.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.kit.check import check_kit

W, H = 48, 32


def _chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    pytest.fail(
        "chromium is not installed, so the kit check report cannot be opened in a browser: "
        "run .ci/setup (it installs Debian's chromium package)"
    )


def _browser(tmp_path: Path, url: str, *extra: str) -> subprocess.CompletedProcess:
    cmd = [
        _chromium(),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--hide-scrollbars",
        "--force-device-scale-factor=1",
        "--force-color-profile=srgb",
        f"--user-data-dir={tmp_path / 'chromium-profile'}",
        *extra,
        url,
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, f"chromium failed ({proc.returncode}): {proc.stderr[-2000:]}"
    return proc


def _colours() -> np.ndarray:
    """(H, W, 4) uint8 opaque image in which every pixel has its own colour."""
    y, x = np.mgrid[0:H, 0:W]
    return np.stack([x * 5, y * 7, np.full_like(x, 200), np.full_like(x, 255)], -1).astype(np.uint8)


def _case(root: Path, name: str, png: np.ndarray) -> dict:
    d = root / name
    d.mkdir(parents=True)
    iio.imwrite(d / "expected.png", png)
    case = {
        "name": name,
        "kind": "image",
        "width": W,
        "height": H,
        "spp": 1,
        "background": [1.0, 1.0, 1.0, 1.0],
        "expected": {"png": "expected.png", "linear": "expected.exr"},
        "tolerance": {
            "threshold": 2 / 255,
            "max_frac_over": 0.0005,
            "min_ssim": 0.995,
            "position_deviation": 1,
        },
    }
    (d / "case.json").write_text(json.dumps(case))
    return {"name": name, "kind": "image", "style": "smooth", "case": f"{name}/case.json"}


@pytest.fixture
def report(tmp_path: Path) -> tuple[Path, list]:
    kit, renders = tmp_path / "kit", tmp_path / "renders"
    kit.mkdir()
    renders.mkdir()
    good = _colours()
    other = np.full((H, W, 4), 255, np.uint8)
    other[8:24, 10:30, :3] = (40, 90, 160)
    cases = [
        _case(kit, "alpha-good", good),
        _case(kit, "beta-tinted", other),
        _case(kit, "gamma-missing", other),
    ]
    (kit / "index.json").write_text(
        json.dumps({"format": "refnpr-kit", "version": 1, "refnpr": "test", "cases": cases})
    )
    iio.imwrite(renders / "alpha-good.png", good)
    tinted = other.copy()
    tinted[8:24, 10:30, 0] = 80
    iio.imwrite(renders / "beta-tinted.png", tinted)
    out = tmp_path / "report"
    results = check_kit(kit, renders, report_dir=out)
    assert [r.passed for r in results] == [True, False, False]
    return out, results


def _find_block(shot: np.ndarray, block: np.ndarray) -> list[tuple[int, int]]:
    """Top-left corners where ``block`` (h, w, 3) appears exactly in ``shot``."""
    y0, x0 = 2, 3  # a pixel whose colour occurs once in the block
    ys, xs = np.nonzero(np.all(shot == block[y0, x0], axis=-1))
    hits = []
    for y, x in zip(ys - y0, xs - x0, strict=True):
        if y >= 0 and x >= 0 and y + H <= shot.shape[0] and x + W <= shot.shape[1]:
            if np.array_equal(shot[y : y + H, x : x + W], block):
                hits.append((int(y), int(x)))
    return hits


def test_report_renders_in_headless_chromium(report, tmp_path):
    out, results = report
    shot_path = tmp_path / "shot.png"
    _browser(
        tmp_path,
        (out / "index.html").resolve().as_uri(),
        f"--screenshot={shot_path}",
        "--window-size=1500,900",
    )
    shot = iio.imread(shot_path)[..., :3]
    assert shot.shape[:2] == (900, 1500)
    assert len(np.unique(shot.reshape(-1, 3), axis=0)) > 500  # a page, not a blank frame
    # the reference and the result thumbnails of the passing case appear pixel for pixel
    ref = iio.imread(out / results[0].images["reference"])
    hits = _find_block(shot, ref)
    assert len(hits) == 2, f"expected the reference and result thumbnails, found {hits}"
    assert hits[0][0] == hits[1][0] and hits[0][1] < hits[1][1]  # side by side, in that order
    # the failing case's error mask shows its red pixels
    mask = iio.imread(out / results[1].images["mask"])
    n_red = int(np.all(mask == [255, 0, 0], axis=-1).sum())
    assert n_red > 0
    assert int(np.all(shot == [255, 0, 0], axis=-1).sum()) >= n_red


def test_report_sorts_rows_by_error_in_the_browser(report, tmp_path):
    out, results = report
    url = (out / "index.html").resolve().as_uri()
    dom = _browser(tmp_path, url + "#sort=-error", "--dump-dom").stdout
    assert 'data-sorted="-error"' in dom  # the inline script ran
    order = re.findall(r'<tr class="case (?:pass|fail)" data-name="([^"]+)"', dom)
    by_error = sorted(results, key=lambda r: -r.error)
    assert order[0] == "gamma-missing"  # inf error: missing render
    assert order == [r.name for r in by_error]
    dom = _browser(tmp_path, url + "#sort=name", "--dump-dom").stdout
    order = re.findall(r'<tr class="case (?:pass|fail)" data-name="([^"]+)"', dom)
    assert order == ["alpha-good", "beta-tinted", "gamma-missing"]
    dom = _browser(tmp_path, url + "#sort=-name", "--dump-dom").stdout
    order = re.findall(r'<tr class="case (?:pass|fail)" data-name="([^"]+)"', dom)
    assert order == ["gamma-missing", "beta-tinted", "alpha-good"]


def test_without_chromium_the_tests_fail_with_the_setup_hint(monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(pytest.fail.Exception, match=r"chromium is not installed.*run \.ci/setup"):
        _chromium()
