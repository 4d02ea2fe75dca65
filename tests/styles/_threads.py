"""Run a script in fresh processes with NUMBA_NUM_THREADS 1 and 2 (tests of thread-count
determinism whose kernels must compile per thread count): the JSON each prints last."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def outputs_per_thread_count(script: str, threads=("1", "2"), timeout: int = 600) -> list:
    """The last stdout line of ``python -c script``, parsed as JSON, per thread count."""
    runs = []
    for n in threads:
        env = dict(os.environ, NUMBA_NUM_THREADS=n)
        proc = subprocess.run(
            [sys.executable, "-c", script],
            capture_output=True,
            text=True,
            env=env,
            cwd=ROOT,
            timeout=timeout,
        )
        assert proc.returncode == 0, proc.stderr[-2000:]
        runs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    return runs
