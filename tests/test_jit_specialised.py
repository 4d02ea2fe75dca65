"""Kernels specialised to modes (``refnpr._jit.specialised``): one kernel per combination of
mode constants, built once, with the other modes' branches pruned before typing, and cached on
disk apart from each other."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

from refnpr._jit import njit, specialised


@specialised
def _scale_for(mode):
    @njit
    def scale(out, x):
        for i in range(x.shape[0]):
            if mode == 0:
                out[i] = 2.0 * x[i]
            elif mode == 1:
                out[i] = x[i] * x[i]
            else:
                out[i] = x[
                    i
                ].no_such_attribute  # cannot be typed: only pruning lets mode 0, 1 compile

    return scale


def test_each_mode_is_its_own_kernel_built_once():
    a, b = _scale_for(0), _scale_for(1)
    assert a is _scale_for(0) and b is _scale_for(1) and a is not b
    assert set(_scale_for.kernels) >= {(0,), (1,)}
    x = np.array([1.0, 3.0])
    out = np.empty(2)
    a(out, x)
    assert out.tolist() == [2.0, 6.0]
    b(out, x)
    assert out.tolist() == [1.0, 9.0]


def test_the_other_modes_branches_are_not_typed():
    """Mode 2's branch does not type; modes 0 and 1 compile because it is pruned first."""
    x = np.ones(3)
    _scale_for(0)(np.empty(3), x)
    with pytest.raises(Exception, match="no_such_attribute"):
        _scale_for(2)(np.empty(3), x)


def test_concurrent_first_calls_build_one_kernel():
    built = []

    @specialised
    def make(mode):
        built.append(mode)
        return lambda: mode

    got = []
    threads = [threading.Thread(target=lambda: got.append(make(7))) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert built == [7] and len({id(k) for k in got}) == 1


def test_name_and_docstring_are_the_factorys():
    assert _scale_for.__name__ == "_scale_for"
    assert _scale_for.__wrapped__.__name__ == "_scale_for"


_MODULE = """
import numpy as np
from refnpr._jit import njit, specialised


@specialised
def f_for(mode):
    @njit
    def f(x):
        return x + 1.0 if mode == 0 else x * 3.0

    return f
"""

_RUN = """
import sys
sys.path.insert(0, sys.argv[1])
import mod
a, b = mod.f_for(0), mod.f_for(1)
print(a(10.0), b(10.0), sum(a.stats.cache_hits.values()), sum(b.stats.cache_hits.values()))
"""


def test_modes_are_cached_on_disk_apart(tmp_path: pathlib.Path):
    """The closure's values are part of numba's cache key: a second process loads each mode's
    own machine code (a shared key would give mode 1 the code of mode 0)."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "mod.py").write_text(textwrap.dedent(_MODULE))
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    runs = [
        subprocess.run(
            [sys.executable, "-c", _RUN, str(src)], env=env, capture_output=True, text=True
        )
        for _ in range(2)
    ]
    for r in runs:
        assert r.returncode == 0, r.stderr
    assert runs[0].stdout.split() == ["11.0", "30.0", "0", "0"]
    assert runs[1].stdout.split() == ["11.0", "30.0", "1", "1"]
