"""Banded kernels (``refnpr._jit.banded``): a serial nogil body over contiguous bands on threads.

Every parallel kernel of refnpr is one (numba's ``prange`` lowering doubled the cold start), so
these tests pin the contract the kernels rely on: the bands tile the loop exactly, every band
runs, the result does not depend on the thread count or the number of bands, errors surface
after every band has finished, and a forked child gets a working pool of its own.
"""

from __future__ import annotations

import ast
import multiprocessing
import os
import pathlib
import re
import subprocess
import sys
import threading
import time
from contextlib import contextmanager

import numba
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from refnpr._jit import BANDS_PER_THREAD, Banded, band_bounds, banded, njit, run_bands


@contextmanager
def _threads(k):
    saved = numba.get_num_threads()
    numba.set_num_threads(k)
    try:
        yield
    finally:
        numba.set_num_threads(saved)


ROOT = pathlib.Path(__file__).resolve().parents[1]


@banded("out")
def _scaled_rows(lo, hi, out, x, k):
    for i in range(lo, hi):
        for j in range(x.shape[1]):
            out[i, j] = np.float32(np.float64(x[i, j]) * k + 0.1 * i)


@banded(lambda out, *_: out.shape[0])
def _mark(lo, hi, out):
    for i in range(lo, hi):
        out[i] += 1


@given(st.integers(0, 10_000), st.integers(1, 64))
def test_bounds_tile_the_range(n, parts):
    bounds = band_bounds(n, parts)
    assert len(bounds) == max(1, min(parts, n))
    assert bounds[0][0] == 0 and bounds[-1][1] == n
    for i in range(len(bounds) - 1):
        assert bounds[i][1] == bounds[i + 1][0]
    sizes = [b - a for a, b in bounds]
    assert max(sizes) - min(sizes) <= 1


@pytest.mark.parametrize("n", [0, 1, 2, 3, 17, 1000])
@pytest.mark.parametrize("parts", [1, 2, 3, 8])
def test_every_index_once(n, parts):
    out = np.zeros(n, dtype=np.int64)
    run_bands(_mark.body, n, (out,), parts)
    assert np.array_equal(out, np.ones(n, dtype=np.int64))


def test_same_bits_for_any_thread_count_and_banding():
    rng = np.random.default_rng(3)
    x = rng.standard_normal((257, 33)).astype(np.float32)
    want = np.empty_like(x)
    for i in range(x.shape[0]):  # the loop, naively
        for j in range(x.shape[1]):
            want[i, j] = np.float32(np.float64(x[i, j]) * 1.7 + 0.1 * i)
    saved = numba.get_num_threads()
    try:
        for threads in range(1, numba.config.NUMBA_NUM_THREADS + 1):
            numba.set_num_threads(threads)
            out = np.full_like(x, np.nan)
            _scaled_rows(out, x, 1.7)
            assert out.tobytes() == want.tobytes(), threads
    finally:
        numba.set_num_threads(saved)
    for parts in (1, 2, 5, 300):
        out = np.full_like(x, np.nan)
        Banded(_scaled_rows.body, _scaled_rows.count, parts)(out, x, 1.7)
        assert out.tobytes() == want.tobytes(), parts


def test_bands_run_concurrently_on_threads():
    """With two bands the second runs on a pool thread while the caller runs the first."""
    seen = []
    barrier = threading.Barrier(2, timeout=20)

    def body(lo, hi):
        seen.append((lo, hi, threading.current_thread().name))
        barrier.wait()  # deadlocks (BrokenBarrierError) unless both bands run at once

    run_bands(body, 10, (), parts=2)
    assert sorted(s[:2] for s in seen) == [(0, 5), (5, 10)]
    assert len({s[2] for s in seen}) == 2


def test_threads_take_bands_in_turn():
    """Dynamic scheduling: while one thread is held up in a slow band, the other takes all the
    rest, so a busy part of an image does not leave a thread idle."""
    ran = []

    def body(lo, hi):
        if lo == 0:
            time.sleep(0.3)
        ran.append((lo, threading.current_thread().name))

    with _threads(min(2, numba.config.NUMBA_NUM_THREADS)):  # the caller and one pool thread
        run_bands(body, 80, (), parts=8)
    assert sorted(lo for lo, _ in ran) == [0, 10, 20, 30, 40, 50, 60, 70]
    slow = next(name for lo, name in ran if lo == 0)
    assert [lo for lo, name in ran if name == slow] == [0]
    assert len({name for _, name in ran}) == 2


def test_default_banding_is_several_bands_per_thread():
    seen = []

    def body(lo, hi):
        seen.append((lo, hi))

    k = numba.config.NUMBA_NUM_THREADS  # every thread this process may use
    with _threads(k):
        run_bands(body, 1000, ())
    bands = k * BANDS_PER_THREAD if k > 1 else 1
    assert sorted(seen) == band_bounds(1000, bands)
    with _threads(1):
        seen.clear()
        run_bands(body, 1000, ())
    assert seen == [(0, 1000)]


def test_error_in_a_band_after_all_bands_finish():
    done = []

    def body(lo, hi):
        if lo == 0:
            raise ValueError("band 0 failed")
        done.append(lo)

    with pytest.raises(ValueError, match="band 0 failed"):
        run_bands(body, 40, (), parts=4)
    assert sorted(done) == [10, 20, 30]


def test_count_by_unknown_argument_name_is_refused():
    with pytest.raises(TypeError, match="no argument 'rows'"):

        @banded("rows")
        def _k(lo, hi, out):
            pass


def test_public_name_and_docstring_are_the_kernels():
    assert _scaled_rows.__name__ == "_scaled_rows"
    assert _scaled_rows.py_func is _scaled_rows.body.py_func
    assert "banded kernel" in repr(_scaled_rows)


def _child(q):
    out = np.zeros(100, dtype=np.int64)
    _mark(out)
    q.put(int(out.sum()))


def test_forked_child_has_its_own_pool():
    _mark(np.zeros(10, dtype=np.int64))  # the parent's pool exists
    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("no fork on this platform")
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_child, args=(q,))
    p.start()
    p.join(60)
    assert p.exitcode == 0
    assert q.get(timeout=5) == 100


def _parallel_functions(text: str) -> set[str]:
    """Functions (nested ones included: kernels built by factories) that ask for numba's
    parallel lowering (``parallel=True``) or loop over ``prange``."""
    found = set()
    for node in ast.walk(ast.parse(text)):
        if not isinstance(node, ast.FunctionDef):
            continue
        deco = " ".join(ast.unparse(d) for d in node.decorator_list)
        body = ast.unparse(node)
        if "parallel=True" in deco or re.search(r"\bprange\(", body):
            found.add(node.name)
    return found


def test_no_kernel_uses_numba_parallel_lowering():
    """``prange`` / ``parallel=True`` compile about twice as long (cold start): every
    parallel kernel of the package is banded (the last, TAMISS's ``raster_strips``, since its
    banded build measured as fast: benchmarks/README.md, "Specialised kernels")."""
    seen = {}
    for path in sorted((ROOT / "refnpr").rglob("*.py")):
        rel = str(path.relative_to(ROOT))
        found = _parallel_functions(path.read_text())
        if found:
            seen[rel] = found
    assert seen == {}


def test_njit_body_releases_the_gil():
    assert _scaled_rows.body.targetoptions.get("nogil") is True
    assert njit(lambda x: x).targetoptions.get("nogil") is True


def test_openmp_threads_wait_passively_unless_the_user_says_otherwise():
    """The spinning OpenMP workers of the prange kernels would take a core from the banded ones."""
    code = "import os, refnpr; print(os.environ['OMP_WAIT_POLICY'])"
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert run.stdout.strip() == "PASSIVE", run.stderr
    env["OMP_WAIT_POLICY"] = "ACTIVE"
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert run.stdout.strip() == "ACTIVE", run.stderr
