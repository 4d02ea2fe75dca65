"""The one place that owns refnpr's numba flags.

Every numba kernel in refnpr is decorated with :func:`njit` or :func:`pnjit` from this module, so
the reference path is compiled the same way everywhere: ``fastmath`` off (IEEE semantics, no
reassociation, so results do not depend on vector width), ``cache=True`` (a warm start does not
recompile), ``error_model="numpy"`` (division by zero gives inf/nan instead of raising inside a
kernel; public functions validate their inputs so that this never reaches an image).

This module imports nothing of refnpr and may be imported by every subpackage.
"""

from __future__ import annotations

import numba

#: Flags of the reference path. ``fastmath`` is off on purpose: see module docstring.
JIT_FLAGS: dict = {"cache": True, "fastmath": False, "nogil": True, "error_model": "numpy"}


def njit(func=None, **overrides):
    """Serial numba kernel with refnpr's flags (``@njit`` or ``@njit(boundscheck=True)``)."""
    flags = {**JIT_FLAGS, **overrides}
    if func is None:
        return lambda f: numba.njit(**flags)(f)
    return numba.njit(**flags)(func)


def pnjit(func=None, **overrides):
    """Parallel numba kernel (``prange``) with refnpr's flags."""
    flags = {**JIT_FLAGS, "parallel": True, **overrides}
    if func is None:
        return lambda f: numba.njit(**flags)(f)
    return numba.njit(**flags)(func)
