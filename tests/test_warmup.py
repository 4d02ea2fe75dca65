"""``refnpr.warmup``: after it, a render of the same kind compiles nothing (fresh processes,
an empty numba cache directory of their own)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from refnpr.warmup import warm

_COUNT = r"""
import json, sys
from numba.core import event

class L(event.Listener):
    n = 0
    def on_start(self, ev):
        L.n += 1
    def on_end(self, ev):
        pass

event.register("numba:compile", L())
from refnpr.render import render
from refnpr.warmup import warm
if sys.argv[1] == "warm":
    warm([("default", None)])
else:
    render("default", None, 96, 54, 4)
print(json.dumps(L.n))
"""


def _compiles(mode: str, cache: str) -> int:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    proc = subprocess.run(
        [sys.executable, "-c", _COUNT, mode], env=env, capture_output=True, text=True, timeout=900
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_after_warmup_the_default_render_compiles_nothing(tmp_path):
    cache = str(tmp_path / "numba-cache")
    assert _compiles("warm", cache) > 0  # an empty cache: the warm-up itself compiles
    assert _compiles("render", cache) == 0


def test_warm_reports_each_render_and_rejects_bad_rows():
    times = warm([("sphere", "toon")])
    assert list(times) == ["sphere / toon spp 1", "sphere / toon spp 4 + contours"]
    assert all(t > 0 for t in times.values())
    with pytest.raises(TypeError, match="rows: expected a sequence of"):
        warm("default")
    with pytest.raises(TypeError, match="rows: expected a sequence of"):
        warm([("default",)])
