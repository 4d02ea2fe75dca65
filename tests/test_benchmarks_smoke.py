"""Smoke tests of benchmarks/bench_gbuffer.py: it runs, writes the JSON rows, survives a missing EGL.

No timing is asserted: only that the script works and that llvmpipe (when present) renders the same
view as refnpr, which checks the peer's conventions (GL's bottom-up rows, dFdy pointing up).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "bench_gbuffer.py"
SETS = {"id+depth", "+uv", "+duv", "full"}


def _run(tmp_path: Path, *extra: str, env_extra: dict | None = None) -> tuple[dict, str]:
    out = tmp_path / "bench.json"
    env = {**os.environ, **(env_extra or {})}
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json", str(out), *extra],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(out.read_text()), proc.stdout


def _refnpr_rows(report: dict) -> dict[tuple[str, str], dict]:
    return {(r["mesh"], r["set"]): r for r in report["rows"] if r["engine"] == "refnpr"}


@pytest.mark.slow
def test_quick_run_writes_refnpr_rows_and_gl_agrees(tmp_path):
    report, stdout = _run(tmp_path)
    rows = _refnpr_rows(report)
    assert set(rows) == {(f"icosphere({s})", name) for s in (3, 4) for name in SETS}
    for row in rows.values():
        assert len(row["runs_s"]) == 3
        assert row["median_s"] == sorted(row["runs_s"])[1]
    assert "G-buffer 480x270, median of 3 runs" in stdout
    status = report["meta"]["gl_status"]
    if status.startswith("ok"):
        assert "llvmpipe" in status
        assert len(report["agreement"]) == 2
        for a in report["agreement"]:
            # same view, same conventions: ids agree except at a few edge pixels
            assert a["tri_id_agreement"] > 0.99
            assert a["uv_max_abs_diff"] < 1e-3
            assert a["duv_dy_median_rel_diff"] < 0.05  # would be ~2 with dFdy's sign unflipped
    else:
        assert status.startswith("not available")
        assert f"llvmpipe: {status}" in stdout


@pytest.mark.slow
def test_missing_egl_is_reported_not_fatal(tmp_path):
    # glvnd finds no EGL vendor library -> moderngl cannot create a context
    report, stdout = _run(
        tmp_path,
        "--subdivisions",
        "2",
        "--runs",
        "1",
        "--size",
        "160x90",
        env_extra={"__EGL_VENDOR_LIBRARY_FILENAMES": str(tmp_path / "no-such-vendor.json")},
    )
    assert report["meta"]["gl_status"].startswith("not available")
    assert "llvmpipe: not available" in stdout
    assert set(_refnpr_rows(report)) == {("icosphere(2)", name) for name in SETS}
    assert not [r for r in report["rows"] if r["engine"] == "llvmpipe"]
    assert report["agreement"] == [] and report["ratios"] == []
