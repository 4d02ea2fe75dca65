"""Files written atomically: a temporary file beside the target, renamed over it when the write
ends, removed on every other exit (exceptions, KeyboardInterrupt, SIGTERM/SIGHUP/SIGINT).

Every file refnpr writes goes through :func:`atomic_file` (re-exported by :mod:`refnpr.image`),
so a target is never partial. This module imports only :mod:`refnpr._memory` and may be imported
by every part of refnpr.
"""

from __future__ import annotations

import os
import secrets
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

from ._memory import read_proc_number

__all__ = ["atomic_file", "check_output_file", "check_parent_writable"]


def check_parent_writable(p: Path, shown: str, what: str) -> None:
    """ValueError naming ``what`` and the path as given (``shown``) unless the nearest existing
    directory above ``p`` is a writable directory (the missing ones below it are created by
    :func:`atomic_file`)."""
    parent = p.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        raise ValueError(
            f"{what}: cannot write {shown!r}: {str(parent)!r} is a file, not a directory"
        )
    if not os.access(parent, os.W_OK):
        raise ValueError(
            f"{what}: cannot write {shown!r} (directory {str(parent)!r} is not writable)"
        )


def check_output_file(path: str | os.PathLike, what: str, suffix: str, note: str = "") -> Path:
    """``path`` as a Path, validated before any work as a file to write: not empty, not a
    directory, ending in ``suffix`` (any case), in a parent directory that exists (or can be
    created) and is writable; else a ValueError naming ``what`` (the parameter or option), the
    path as given and what to give instead (``note`` follows a wrong suffix's message)."""
    shown = os.fspath(path)
    p = Path(path)
    if isinstance(shown, str) and not shown.strip():
        raise ValueError(f"{what}: expected a file name ending in {suffix}, got {shown!r}")
    if isinstance(shown, str) and shown.endswith(("/", os.sep)):
        raise ValueError(
            f"{what}: {shown!r} names a directory (it ends with a slash); give a file name "
            f"ending in {suffix}, such as {shown + 'out' + suffix!r}"
        )
    if p.is_dir():
        raise ValueError(f"{what}: {shown!r} is a directory; give a file name ending in {suffix}")
    if p.suffix.lower() != suffix:
        raise ValueError(
            f"{what}: expected a {suffix} file name, got {shown!r}{note} (such as "
            f"{str(p.with_suffix(suffix))!r})"
        )
    check_parent_writable(p, shown, what)
    return p


#: Signals whose default action ends the process: while an atomic write runs (main thread),
#: they first remove the temporary files (unless a Python handler is installed for them).
_TERMINATING = tuple(
    getattr(signal, n) for n in ("SIGTERM", "SIGHUP", "SIGINT") if hasattr(signal, n)
)

#: Temporary files of the atomic writes under way, in every thread: what the signal handler
#: removes. Under ``_LIVE_LOCK``, re-entrant: the handler runs in the main thread between any
#: two bytecodes, possibly while that thread holds the lock.
_LIVE: set[str] = set()
_LIVE_LOCK = threading.RLock()
#: How many atomic writes of the main thread are open (nested or interleaved blocks): the
#: handlers are installed by the first and restored when this returns to 0.
_DEPTH = 0
#: Signal number -> the handler ours replaced (always ``SIG_DFL``), for those ours was set on.
_INSTALLED: dict[int, Any] = {}
#: Where Linux reports the process's umask; read instead of setting it (see ``_current_umask``).
_PROC_STATUS = "/proc/self/status"


def _on_signal(signum: int, frame: Any) -> None:
    """Temporary handler: put the previous handler back first (so a second signal never re-enters
    here), remove the temporary files, and end the process with the same signal."""
    with suppress(ValueError, OSError):
        signal.signal(signum, _INSTALLED.get(signum) or signal.SIG_DFL)
    got = _LIVE_LOCK.acquire(timeout=1.0)  # a worker holds it for a set operation at most
    try:
        names = tuple(_LIVE)
    finally:
        if got:
            _LIVE_LOCK.release()
    for name in names:
        with suppress(OSError):
            os.unlink(name)
    os.kill(os.getpid(), signum)  # the default action: terminate with this signal
    raise SystemExit(128 + signum)  # reached only if the signal is blocked


def _install() -> None:
    """Set ``_on_signal`` for each terminating signal whose handler is the default one."""
    for signum in _TERMINATING:
        with suppress(ValueError, OSError):
            if signal.getsignal(signum) == signal.SIG_DFL:
                previous = signal.signal(signum, _on_signal)
                _INSTALLED.setdefault(signum, previous)


def _restore() -> None:
    """Put back the handlers ``_on_signal`` replaced, where it is still the one set (a handler
    installed meanwhile by the caller stays). Each is set before it is forgotten, so an
    interrupt in between finds either ours, which still knows the previous one, or that one."""
    for signum, previous in list(_INSTALLED.items()):
        with suppress(ValueError, OSError):
            if signal.getsignal(signum) is _on_signal:
                signal.signal(signum, previous)
        _INSTALLED.pop(signum, None)


@contextmanager
def _signals_remove() -> Iterator[None]:
    """While the block runs (main thread only), a terminating signal whose handler is the
    default one removes the files of ``_LIVE`` first (see :func:`atomic_file`). Blocks nest;
    handlers set from Python (KeyboardInterrupt, a caller's own) are left alone."""
    global _DEPTH
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _DEPTH += 1
    try:
        _install()  # also at inner levels: a handler the caller reset to the default
        yield
    finally:
        _DEPTH -= 1
        if _DEPTH == 0:
            _restore()


def _current_umask() -> int:
    """The process's umask, read from ``/proc/self/status``: setting it, even briefly, would give
    files other threads create meanwhile the wrong mode. Elsewhere, set and restored (to 0o077
    meanwhile, not 0)."""
    umask = read_proc_number(_PROC_STATUS, "Umask:", 8)
    if umask is None:
        umask = os.umask(0o077)
        os.umask(umask)
    return umask


_OPEN_FLAGS = (
    os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
)


def _create_registered(parent: Path, prefix: str, suffix: str) -> str:
    """A new empty file (mode 0600) ``parent/prefix<random>suffix``, registered in ``_LIVE``
    before it is created (so a signal at any point finds it) and unregistered on failure."""
    for _ in range(1000):
        name = os.path.join(parent, f"{prefix}{secrets.token_hex(5)}{suffix}")
        with _LIVE_LOCK:
            _LIVE.add(name)
        try:
            os.close(os.open(name, _OPEN_FLAGS, 0o600))
            return name
        except BaseException as exc:
            with _LIVE_LOCK:
                _LIVE.discard(name)
            if not isinstance(exc, FileExistsError):  # a name already taken: another one
                raise
    raise FileExistsError(f"cannot create a temporary file in {str(parent)!r}: names taken")


@contextmanager
def atomic_file(path: str | os.PathLike, *, suffix: str = "") -> Iterator[Path]:
    """A temporary file beside ``path`` that replaces ``path`` (atomic rename) when the block
    ends normally, and is removed on every other exit. ``path`` is never partial.

    Removed on an exception or KeyboardInterrupt (in every thread), and in the main thread on
    SIGTERM, SIGHUP or SIGINT whose handler is the default one: a temporary handler removes the
    temporary files of all the atomic writes under way and re-sends the signal, so the process
    ends with the conventional status; the previous handlers are restored when the outermost
    block ends, unless the caller replaced ours meanwhile. Worker threads cannot set handlers: a
    signal that ends the process leaves their temporary file unless a main-thread atomic write
    is under way.

    Parameters
    ----------
    path : str or path
        The target; its parent directory is created.
    suffix : str
        Suffix of the temporary file (some writers choose the format by it, ``".npz"``).

    Yields
    ------
    Path
        The temporary file to write (it exists, empty, mode 0600 until the rename, then
        ``0o666`` less the umask).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with _signals_remove():
        tmp = _create_registered(path.parent, f".{path.stem}.", suffix)
        try:
            yield Path(tmp)
            os.chmod(tmp, 0o666 & ~_current_umask())  # mkstemp-like 0600; the usual mode
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        finally:
            with _LIVE_LOCK:
                _LIVE.discard(tmp)
