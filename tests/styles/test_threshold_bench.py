"""Smoke test of benchmarks/bench_veryovka.py: the Pareto bookkeeping and a quick run that writes
its JSON (no time is asserted)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_veryovka.py"


def _bench():
    spec = importlib.util.spec_from_file_location("bench_veryovka", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_pareto_front_keeps_only_undominated_methods():
    rows = [
        {"method": "a", "time_s": 1.0, "mae": 0.10},
        {"method": "b", "time_s": 2.0, "mae": 0.05},
        {"method": "c", "time_s": 3.0, "mae": 0.06},  # slower and worse than b
        {"method": "d", "time_s": 0.5, "mae": 0.20},
    ]
    assert _bench().pareto_front(rows) == ["a", "b", "d"]


@pytest.mark.slow
def test_quick_tone_and_temporal_sections_write_json(tmp_path):
    out = tmp_path / "v.json"
    assert _bench().main(["--quick", "--sections", "tone,temporal", "--json", str(out)]) == 0
    report = json.loads(out.read_text())
    tone = report["tone"]
    assert tone["lines uniform analytic"]["max_abs_error"] < 0.02
    assert tone["lines (paper eq. 8)"]["max_abs_error"] > 0.03
    flips = report["temporal"]["plane"]["flips"]
    assert max(flips["floored"]) > 3 * max(flips["multiscale"])
