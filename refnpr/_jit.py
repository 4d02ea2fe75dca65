"""The one place that owns refnpr's numba flags.

Every numba kernel in refnpr is decorated with :func:`njit` or :func:`pnjit` from this module, so
the reference path is compiled the same way everywhere: ``fastmath`` off (IEEE semantics, no
reassociation, so results do not depend on vector width), ``cache=True`` (a warm start does not
recompile), ``error_model="numpy"`` (division by zero gives inf/nan instead of raising inside a
kernel; public functions validate their inputs so that this never reaches an image).

Where numba finds no writable cache directory (``NUMBA_CACHE_DIR``, ``__pycache__`` beside the
source, the user-wide cache under ``HOME``: a read-only install with an unwritable home) it
raises "cannot cache function ...: no locator available" when a kernel is decorated, that is at
import. Then the kernel is cached in a private directory under :func:`tempfile.gettempdir`
instead, and where that is not writable either it is compiled without caching, with one warning.

This module imports nothing of refnpr and may be imported by every subpackage.
"""

from __future__ import annotations

import os
import stat
import tempfile
import warnings

import numba
from numba.core import config as _numba_config

#: Flags of the reference path. ``fastmath`` is off on purpose: see module docstring.
JIT_FLAGS: dict = {"cache": True, "fastmath": False, "nogil": True, "error_model": "numpy"}


def fallback_cache_dir() -> str | None:
    """A private, writable numba cache directory under the temporary directory, or None.

    ``<tempdir>/refnpr-numba-<uid>``, created with mode 0700; an existing one is used only if
    this user owns it and nobody else can write to it (numba's cache files are pickles), and
    only in a temporary directory that others cannot rename entries of (sticky, like /tmp, or
    not writable by others).
    """
    uid = os.getuid() if hasattr(os, "getuid") else 0
    path = os.path.join(tempfile.gettempdir(), f"refnpr-numba-{uid}")
    try:
        parent = os.stat(os.path.dirname(path))
        shared = parent.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
        if shared and not parent.st_mode & stat.S_ISVTX and parent.st_uid != uid:
            return None  # others could swap the directory after the checks below
        os.makedirs(path, mode=0o700, exist_ok=True)
        st = os.lstat(path)
        if not stat.S_ISDIR(st.st_mode) or st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            return None
        if hasattr(os, "getuid") and st.st_uid != uid:
            return None
        tempfile.TemporaryFile(dir=path).close()
    except OSError:
        return None
    return path


#: Whether the no-cache warning was given (once per process, not once per kernel).
_WARNED: list[bool] = []
#: Where kernels went when numba had no cache locator: the fallback directory, or "" (uncached).
FALLBACK: list[str] = []


def _no_locator(exc: RuntimeError) -> bool:
    return "no locator available" in str(exc)


def _jit(func, flags: dict):
    try:
        return numba.njit(**flags)(func)
    except RuntimeError as exc:
        if not (flags.get("cache") and _no_locator(exc)):
            raise
    path = fallback_cache_dir()
    if path is not None:
        saved = _numba_config.CACHE_DIR
        _numba_config.CACHE_DIR = path  # read once, when the dispatcher picks its locator
        try:
            kernel = numba.njit(**flags)(func)
            if path not in FALLBACK:
                FALLBACK.append(path)
            return kernel
        except RuntimeError as exc:
            if not _no_locator(exc):
                raise
        finally:
            _numba_config.CACHE_DIR = saved
    if "" not in FALLBACK:
        FALLBACK.append("")
    if not _WARNED:
        _WARNED.append(True)
        warnings.warn(
            "refnpr: no writable numba cache directory (__pycache__, NUMBA_CACHE_DIR, ~/.cache, "
            f"{tempfile.gettempdir()}); kernels are compiled on every start. Set NUMBA_CACHE_DIR "
            "to a writable directory to cache them.",
            RuntimeWarning,
            stacklevel=3,
        )
    return numba.njit(**{**flags, "cache": False})(func)


def njit(func=None, **overrides):
    """Serial numba kernel with refnpr's flags (``@njit`` or ``@njit(boundscheck=True)``)."""
    flags = {**JIT_FLAGS, **overrides}
    if func is None:
        return lambda f: _jit(f, flags)
    return _jit(func, flags)


def pnjit(func=None, **overrides):
    """Parallel numba kernel (``prange``) with refnpr's flags."""
    flags = {**JIT_FLAGS, "parallel": True, **overrides}
    if func is None:
        return lambda f: _jit(f, flags)
    return _jit(func, flags)
