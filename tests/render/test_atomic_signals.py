"""Atomic writes and signals: nested writes, handlers set meanwhile, the handler's order, a
signal right after the temporary file is created, and the umask left alone."""

import json
import os
import signal
import stat
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from refnpr import _atomic as image  # the atomic-write machinery (re-exported by refnpr.image)
from refnpr.image import atomic_file

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="POSIX signals")


def _child(code: str, tmp: Path) -> subprocess.CompletedProcess:
    """Run ``code`` (``tmp`` is bound to the directory) in a fresh interpreter, at most 60 s."""
    prelude = f"import os, signal, sys, json\nfrom pathlib import Path\ntmp = Path({str(tmp)!r})\n"
    return subprocess.run(
        [sys.executable, "-c", prelude + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=60,
    )


def _left(tmp: Path) -> list[str]:
    return sorted(p.name for p in tmp.iterdir())


def test_sigterm_in_nested_writes_removes_both_temporaries(tmp_path):
    r = _child(
        """
        from refnpr.image import atomic_file
        with atomic_file(tmp / "a.json", suffix=".json") as a:
            a.write_text("{")
            with atomic_file(tmp / "b.json", suffix=".json") as b:
                b.write_text("{")
                os.kill(os.getpid(), signal.SIGTERM)
                print("survived")
        """,
        tmp_path,
    )
    assert r.returncode == -signal.SIGTERM, (r.returncode, r.stderr)
    assert "survived" not in r.stdout
    assert _left(tmp_path) == []


def test_nested_writes_keep_one_handler_and_restore_it(tmp_path):
    before = signal.getsignal(signal.SIGTERM)
    if before != signal.SIG_DFL:
        pytest.skip("SIGTERM has a handler in this test process")
    with atomic_file(tmp_path / "a.txt") as a:
        outer = signal.getsignal(signal.SIGTERM)
        with atomic_file(tmp_path / "b.txt") as b:
            assert signal.getsignal(signal.SIGTERM) is outer is not signal.SIG_DFL
            assert {str(a), str(b)} <= image._LIVE
            b.write_text("b")
        assert signal.getsignal(signal.SIGTERM) is outer  # the outer block still needs it
        a.write_text("a")
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    assert image._DEPTH == 0 and not image._INSTALLED and not image._LIVE
    assert _left(tmp_path) == ["a.txt", "b.txt"]


def test_a_handler_installed_inside_the_block_is_kept(tmp_path):
    def mine(signum, frame):
        pass

    previous = signal.getsignal(signal.SIGTERM)
    try:
        with atomic_file(tmp_path / "a.txt") as a:
            a.write_text("a")
            signal.signal(signal.SIGTERM, mine)
        assert signal.getsignal(signal.SIGTERM) is mine
        assert not image._INSTALLED
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_the_handler_resets_itself_before_removing_and_re_sending(tmp_path):
    # SIGTERM blocked: the handler's os.kill stays pending, so it raises SystemExit and the
    # child can report what it saw; the pending signal then ends it once unblocked.
    r = _child(
        """
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})  # first: threads inherit it
        from refnpr import _atomic as image
        seen = []
        real_unlink = os.unlink
        def unlink(name, *a, **k):
            seen.append(signal.getsignal(signal.SIGTERM) == signal.SIG_DFL)
            return real_unlink(name, *a, **k)
        os.unlink = unlink
        try:
            with image.atomic_file(tmp / "a.txt") as a:
                a.write_text("a")
                signal.getsignal(signal.SIGTERM)(signal.SIGTERM, None)
        except SystemExit as exc:
            status = exc.code
        print(json.dumps({
            "status": status,
            "default_at_unlink": bool(seen) and all(seen),  # handler, then except
            "default_after": signal.getsignal(signal.SIGTERM) == signal.SIG_DFL,
            "installed": len(image._INSTALLED),
            "left": sorted(p.name for p in tmp.iterdir()),
        }), flush=True)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
        print("survived", flush=True)
        """,
        tmp_path,
    )
    assert r.returncode == -signal.SIGTERM, (r.returncode, r.stderr)
    assert "RecursionError" not in r.stderr and "survived" not in r.stdout
    seen = json.loads(r.stdout.splitlines()[0])
    assert seen == {
        "status": 128 + signal.SIGTERM,
        "default_at_unlink": True,
        "default_after": True,
        "installed": 0,
        "left": [],
    }


def test_a_signal_right_after_the_file_is_created_removes_it(tmp_path):
    r = _child(
        """
        real_open = os.open
        def open_then_signal(name, *a, **k):
            fd = real_open(name, *a, **k)
            if Path(name).name.startswith(".t."):
                os.kill(os.getpid(), signal.SIGTERM)  # handled before open returns
            return fd
        os.open = open_then_signal
        from refnpr.image import atomic_file
        with atomic_file(tmp / "t.json", suffix=".json") as t:
            print("survived")
        """,
        tmp_path,
    )
    assert r.returncode == -signal.SIGTERM, (r.returncode, r.stderr)
    assert "survived" not in r.stdout
    assert _left(tmp_path) == []


def test_the_umask_is_read_without_being_changed(tmp_path, monkeypatch):
    status = Path(image._PROC_STATUS)
    if not status.exists() or "Umask:" not in status.read_text():
        pytest.skip("no Umask line in /proc/self/status")
    umask = os.umask(0o022)
    try:

        def no_umask(mask):
            raise AssertionError("os.umask called while writing")

        monkeypatch.setattr(os, "umask", no_umask)
        with atomic_file(tmp_path / "m.txt") as m:
            m.write_text("m")
        monkeypatch.undo()
        assert stat.S_IMODE((tmp_path / "m.txt").stat().st_mode) == 0o644
    finally:
        os.umask(umask)


def test_the_umask_fallback_where_proc_is_missing(tmp_path, monkeypatch):
    monkeypatch.setattr(image, "_PROC_STATUS", str(tmp_path / "no-such-status"))
    umask = os.umask(0o027)
    try:
        with atomic_file(tmp_path / "m.txt") as m:
            m.write_text("m")
        assert os.umask(0o027) == 0o027  # put back as it was
        assert stat.S_IMODE((tmp_path / "m.txt").stat().st_mode) == 0o640
    finally:
        os.umask(umask)


def test_a_worker_thread_installs_nothing_and_cleans_up_on_error(tmp_path):
    seen: list = []

    def work() -> None:
        try:
            with atomic_file(tmp_path / "w.txt") as w:
                w.write_text("w")
                seen.append(signal.getsignal(signal.SIGTERM))
                raise RuntimeError("boom")
        except RuntimeError as exc:
            seen.append(str(exc))

    before = signal.getsignal(signal.SIGTERM)
    t = threading.Thread(target=work)
    t.start()
    t.join(60)
    assert seen == [before, "boom"]
    assert _left(tmp_path) == [] and not image._LIVE
