"""The benchmark scripts other than bench_gbuffer run and write their JSON (never timed here)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(script: str, *args: str, tmp_path: Path) -> dict:
    out = tmp_path / "out.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / script), *args, "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(out.read_text())


def test_bench_frame_quick_writes_a_row_per_style_and_spp(tmp_path):
    report = _run(
        "bench_frame.py",
        "--quick",
        "--styles",
        "toon",
        "--spp",
        "1",
        "--sections",
        "frame",
        tmp_path=tmp_path,
    )
    assert [(r["style"], r["spp"], r["engine"]) for r in report["rows"]] == [("toon", 1, "render")]
    assert report["rows"][0]["ratio"] > 0


def test_bench_memory_small_run_reports_peak_and_needed(tmp_path):
    report = _run("bench_memory.py", "--size", "160x90", "--spp", "4", tmp_path=tmp_path)
    (row,) = report["rows"]
    assert "error" not in row, row.get("error")
    assert row["peak_bytes"] >= row["baseline_bytes"] > 0
    assert row["needed_bytes"] >= row["gbuffer_bytes"] > 0


@pytest.mark.parametrize("sequence", ["xtoon_flow"])
def test_bench_coherence_quick_runs_one_sequence(tmp_path, sequence):
    report = _run("bench_coherence.py", "--quick", "--sequences", sequence, tmp_path=tmp_path)
    assert report["rows"] and all(r["sequence"] == sequence for r in report["rows"])
