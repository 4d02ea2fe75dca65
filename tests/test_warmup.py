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
    names = []
    def on_start(self, ev):
        L.n += 1
        L.names.append(ev.data["dispatcher"].py_func.__module__)
    def on_end(self, ev):
        pass

event.register("numba:compile", L())
from refnpr.render import render
from refnpr.warmup import warm
ROWS = [("sphere", "toon"), ("teapot", "xtoon"), ("sphere", "smooth")]
if sys.argv[1] == "warm":
    warm([("default", None)])
elif sys.argv[1] == "warm-parallel":
    times = warm(ROWS, jobs=2)
    assert list(times) == [f"{scene} / {style} spp {spp}{extra}" for scene, style in ROWS
                           for spp, extra in ((1, ""), (4, " + contours"))], list(times)
elif sys.argv[1] == "render-parallel":
    for scene, style in ROWS:
        render(scene, style, 80, 45, 1)
        render(scene, {"name": style, "contours": True}, 80, 45, 4)
else:
    render("default", None, 96, 54, 4)
print(json.dumps(L.names if sys.argv[1] == "warm-parallel" else L.n))
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


def test_parallel_warmup_leaves_nothing_to_compile(tmp_path):
    # jobs=2: the sphere's rows (toon, smooth) in one spawned worker, the teapot's X-Toon in
    # the other. The listener sees this process's compiles only: none means the work went to
    # the workers, and a fresh process compiling nothing means they cached every kernel
    cache = str(tmp_path / "numba-cache")
    assert _compiles("warm-parallel", cache) == []
    assert _compiles("render-parallel", cache) == 0


def test_warm_reports_each_render_and_rejects_bad_rows():
    times = warm([("sphere", "toon")])
    assert list(times) == ["sphere / toon spp 1", "sphere / toon spp 4 + contours"]
    assert all(t > 0 for t in times.values())
    with pytest.raises(TypeError, match="rows: expected a sequence of"):
        warm("default")
    with pytest.raises(TypeError, match="rows: expected a sequence of"):
        warm([("default",)])
    with pytest.raises(ValueError, match=r"jobs: expected an integer in \[1, 64\], got 0"):
        warm([("sphere", "toon")], jobs=0)
    with pytest.raises(TypeError, match="jobs: expected an integer, got str"):
        warm([("sphere", "toon")], jobs="2")
