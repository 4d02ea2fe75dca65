"""Smoke test of benchmarks/bench_tamiss.py: it runs and writes its JSON (no time is asserted)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_tamiss.py"


@pytest.mark.slow
def test_quick_run_writes_every_section(tmp_path):
    out = tmp_path / "tamiss.json"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    report = json.loads(out.read_text())
    assert [r["target_strokes"] for r in report["phases"]] == [62, 250, 1000]
    for row in report["phases"]:
        assert set(row["median_s"]) == {"gather", "aggregate", "fit", "extrude", "raster", "total"}
        assert 0 < row["fit_share"] < 1 and row["strokes"] > 0
    assert report["hash"] and all(len(r["frames"]) == 3 for r in report["hash"])
    jit = report["jitter"]["results"]
    assert set(jit) == {"none", "average4"} and all(v["samples"] > 0 for v in jit.values())
    assert "TAMISS phases" in proc.stdout and "Stroke jitter" in proc.stdout


@pytest.mark.slow
def test_quick_options_section_writes_every_variant(tmp_path):
    out = tmp_path / "tamiss.json"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--sections", "options", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    opts = json.loads(out.read_text())["options"]
    assert set(opts["sequences"]) == {"tamiss_knot_orbit", "knot_4deg"}
    for res in opts["sequences"].values():
        assert {"tam", "default", "per-frame fits (paper)", "average_frames=4 plain"} <= set(res)
        assert res["per-frame fits (paper)"]["time_ratio"] == 1.0
        for label, v in res.items():
            assert v["E"] > 0 and v["E_over_D"] > 0 and v["frame_s_interleaved"] > 0
            assert ("jitter_mean_px" in v) == (label != "tam")
            if label != "tam":  # the ink and its floor of exactly carried strokes
                assert v["floor_E_over_D"] > 0 and v["ink_E_over_D"] > 0
        # plain averaging lags the surface, averaging along the motion does not
        assert res["average_frames=4 plain"]["lag_px"] > 2 * abs(res["default"]["lag_px"])
    assert "TAMISS jitter options" in proc.stdout
