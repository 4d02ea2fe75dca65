"""numba's cache saves under refnpr's lock: two processes (here: threads, each with its own
open file description, which ``flock`` treats alike) adding two signatures of one kernel at the
same moment keep both, each naming its own data file."""

from __future__ import annotations

import sys
import threading
import time

import pytest
from numba.core import caching

import refnpr._jit  # noqa: F401  (installs the lock)

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")

_STAMP = (1.0, 100)


def _race(tmp_path, monkeypatch, save) -> caching.IndexDataCacheFile:
    """Two saves whose index reads overlap (each read is held for 0.2 s)."""
    load = caching.IndexDataCacheFile._load_index

    def slow_load(self):
        out = load(self)
        time.sleep(0.2)
        return out

    monkeypatch.setattr(caching.IndexDataCacheFile, "_load_index", slow_load)
    files = [caching.IndexDataCacheFile(str(tmp_path), "kernel-12.py311", _STAMP) for _ in "ab"]
    threads = [
        threading.Thread(target=save, args=(f, ("sig", k), f"code for {k}"))
        for f, k in zip(files, "ab", strict=True)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    monkeypatch.setattr(caching.IndexDataCacheFile, "_load_index", load)
    return files[0]


def _entries(f: caching.IndexDataCacheFile) -> dict:
    return {key: f.load(key) for key in f._load_index()}


def test_concurrent_saves_keep_both_signatures(tmp_path, monkeypatch):
    save = caching.IndexDataCacheFile.save
    assert getattr(save, "refnpr_locked", False)
    f = _race(tmp_path, monkeypatch, save)
    assert _entries(f) == {("sig", "a"): "code for a", ("sig", "b"): "code for b"}


def test_without_the_lock_the_same_race_loses_one(tmp_path, monkeypatch):
    # the control: numba's own save, same interleaving, keeps only one entry
    f = _race(tmp_path, monkeypatch, caching.IndexDataCacheFile.save.__wrapped__)
    assert len(_entries(f)) == 1


def test_a_file_system_without_locks_still_saves(tmp_path, monkeypatch):
    # flock failing (ENOLCK on some network file systems) must not fail the compile
    def no_locks(fd, op):
        raise OSError(37, "No locks available")

    monkeypatch.setattr(refnpr._jit.fcntl, "flock", no_locks)
    f = caching.IndexDataCacheFile(str(tmp_path), "kernel-12.py311", _STAMP)
    f.save(("sig", "a"), "code for a")
    assert _entries(f) == {("sig", "a"): "code for a"}
