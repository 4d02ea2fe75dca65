"""Reading untrusted files (a kit, a scene and the files it names): relative paths kept inside
their directory, regular files read with a size cap, and text from a file made safe to print.

Every function raises ``ValueError`` with a message that starts with ``what`` (the role of the
file) and quotes paths and values with ``repr`` (so control characters arrive escaped). The
limits are the caller's. The kit reads its files through these functions
(:mod:`refnpr.kit.check`), the scene readers theirs (:mod:`refnpr.scenes.gltf`,
:mod:`refnpr.scenes.loading`); this module imports nothing else of refnpr.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path, PurePosixPath
from typing import Any

__all__ = ["inside", "printable", "read_regular", "short_repr"]


def printable(text: object) -> str:
    """``str(text)`` with every non-printable character (control characters such as ESC,
    format characters such as the bidi overrides, line separators, lone surrogates) written as
    a Python escape (``\\x1b``, ``\\u202e``); idempotent, so it may be applied more than once."""
    s = str(text)
    if s.isprintable():
        return s
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in s)


def short_repr(value: Any, limit: int = 120) -> str:
    """``repr(value)``, cut to ``limit`` characters (ending in ``...``) where it is longer."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def inside(root: Path, rel: Any, *, what: str, root_name: str, base: Path | None = None) -> Path:
    """The path ``rel`` (relative, ``/``-separated) under ``base``, resolved and inside ``root``.

    Parameters
    ----------
    root : Path
        A resolved directory (``Path.resolve(strict=True)``).
    rel : Any
        The path as the untrusted file gives it, relative to ``base``.
    what : str
        The key that holds it (``"expected.png"``), the start of every message.
    root_name : str
        What ``root`` is (``"the kit"``), for messages.
    base : Path, optional
        A resolved directory inside ``root`` that ``rel`` is relative to (default ``root``).

    Returns
    -------
    Path
        Absolute, with every symbolic link resolved, inside ``root`` (it need not exist).

    Raises
    ------
    ValueError
        ``rel`` is not a non-empty string; is absolute; has a ``..`` component, a backslash or a
        NUL; or resolves outside ``root`` (a symbolic link out, or a link loop).
    """
    if not isinstance(rel, str) or not rel:
        raise ValueError(
            f"{what}: expected a relative file path (a non-empty string), got {short_repr(rel)}"
        )
    if "\x00" in rel or "\\" in rel:
        raise ValueError(
            f"{what}: {short_repr(rel)} holds a NUL or a backslash; use '/' between path parts"
        )
    p = PurePosixPath(rel)
    if p.is_absolute() or (len(rel) > 1 and rel[1] == ":"):
        raise ValueError(
            f"{what}: {short_repr(rel)} is an absolute path; expected a path relative to {root_name}"
        )
    if ".." in p.parts:
        raise ValueError(
            f"{what}: {short_repr(rel)} has a '..' component; expected a path inside {root_name}"
        )
    try:
        resolved = ((root if base is None else base) / p).resolve()
    except (OSError, RuntimeError) as exc:  # a symbolic link loop
        raise ValueError(f"{what}: {short_repr(rel)} cannot be resolved ({exc})") from None
    if not resolved.is_relative_to(root):
        raise ValueError(
            f"{what}: {short_repr(rel)} leads outside {root_name} (to {short_repr(str(resolved))}, "
            "through a symbolic link); files must lie inside it"
        )
    return resolved


def read_regular(path: Path, *, what: str, max_bytes: int, head: int | None = None) -> bytes:
    """The contents of a regular file (at most ``max_bytes`` of it exist), or its first
    ``head`` bytes.

    Devices (``/dev/zero``), FIFOs, sockets and directories are refused before they are
    opened, so a read never blocks or runs forever; the file is opened without following a
    symbolic link and checked again once open.

    Parameters
    ----------
    path : Path
        The file (resolved).
    what : str
        The file as messages name it (``"render 'x.png'"``).
    max_bytes : int
        The largest file read (its size from ``stat``, before it is opened).
    head : int, optional
        Read only the first ``head`` bytes (a header to check before the whole file).

    Returns
    -------
    bytes
        The whole file, or its first ``head`` bytes.

    Raises
    ------
    ValueError
        The file does not exist, is not a regular file, is larger than ``max_bytes`` or
        cannot be read.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ValueError(f"{what} does not exist") from None
    except OSError as exc:
        raise ValueError(f"{what}: cannot read it: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
        raise ValueError(f"{what} is {kind}; expected a regular file")
    if st.st_size > max_bytes:
        raise ValueError(f"{what} has {st.st_size} bytes, more than the {max_bytes} bytes allowed")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise ValueError(f"{what}: cannot open it: {exc.strerror}") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise ValueError(f"{what} is not a regular file; expected a regular file")
        # never ask for more than the file holds (+1 to see growth): read(n) allocates n bytes
        n = min(st.st_size, max_bytes) + 1
        n = n if head is None else min(head, n)
        try:
            data = f.read(n)
        except OSError as exc:
            raise ValueError(f"{what}: cannot read it: {exc.strerror}") from None
    if len(data) > max_bytes:  # the file grew since the stat
        raise ValueError(f"{what} has more than the {max_bytes} bytes allowed")
    return data
