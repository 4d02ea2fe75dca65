"""Smoke test of benchmarks/bench_halftone.py: it runs and writes its JSON rows (no timing)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_halftone.py"


@pytest.mark.slow
def test_quick_run_writes_pareto_and_temporal_rows(tmp_path):
    out = tmp_path / "h.json"
    proc = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--quick",
            "--sections",
            "pareto,temporal",
            "--json",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    report = json.loads(out.read_text())
    for view in ("teapot-engraving", "sphere-hatching"):
        sec = report["pareto"][view]
        methods = [r["method"] for r in sec["rows"]]
        assert methods[:5] == [
            "binary 1spp",
            "binary 2x2",
            "binary 3x3",
            "binary 4x4",
            "binary 8x8",
        ]
        assert sec["fastest_reaching_4x4_error"] in methods
        assert sec["pareto_front"] and set(sec["pareto_front"]) <= set(methods)
        for r in sec["rows"]:
            assert r["median_s"] == sorted(r["runs_s"])[len(r["runs_s"]) // 2]
            assert 0.0 <= r["mae"] <= r["rmse"] + 1e-12
        temporal = report["temporal"][view]["rows"]
        assert [len(r["flips_per_frame"]) for r in temporal] == [2] * len(temporal)
    assert "fastest method reaching" in proc.stdout
    assert (tmp_path / "h.png").is_file() or "plot skipped" in proc.stdout
