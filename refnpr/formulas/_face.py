"""A per-sample formula written once: its scalar device function and its numpy face.

Every per-sample formula of refnpr is one scalar function, compiled by numba
(:func:`refnpr._jit.njit`), that the style kernels call for each sample. Its public numpy face
validates and broadcasts arrays and then calls that same scalar function at every element, so
the function a property test exercises is the function that renders::

    @njit
    def _detail_orientation(n_dot_v, r):
        return min(abs(n_dot_v), 1.0) ** r  # sec. 3.2

    @face(_detail_orientation)
    def detail_orientation(n_dot_v, r):
        ...  # validation
        return elementwise(detail_orientation.scalar, dt, c, r)

    detail_orientation.scalar  # the device function; kernels bind it to a module name

:func:`elementwise` builds, once per scalar function, a numba loop that reads each argument
at element ``i`` (an array: its element; a tuple of arrays: a tuple of their elements, a
vector; anything else: itself), calls the scalar function and stores its value (a number, or a
tuple of numbers in the last axis). The loop is cached on disk under the scalar function's
module and name, keyed on the scalar function's source file like every refnpr kernel
(:func:`refnpr._jit.dependency_files`), so editing a formula's body changes its numpy face and
every kernel that calls it alike.

Arithmetic is float64: float arrays are converted to float64 before the loop (the kernels
compute in float64 from float32 G-buffers) and the result is cast to the face's dtype
(float32 in -> float32 out).
"""

from __future__ import annotations

import threading
import types
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from numba import types as nbtypes
from numba.extending import overload

from refnpr._jit import njit, readonly

__all__ = ["face", "elementwise", "Whole"]


class Whole(NamedTuple):
    """An array argument of :func:`elementwise` passed whole to every element (a texture), not
    broadcast and read element by element."""

    value: np.ndarray


def face(scalar: Any) -> Callable[[Callable], Callable]:
    """Decorator: the decorated numpy function is the face of ``scalar`` (``f.scalar``)."""

    def deco(func: Callable) -> Callable:
        func.scalar = scalar
        return func

    return deco


# ---------------------------------------------------------------------- the generic loop


def _at(a, i):  # noqa: ARG001  (numba typing stand-in; see the overload)
    """Argument ``a`` at element ``i`` (numba only)."""
    raise NotImplementedError


def _put(out, i, r):  # noqa: ARG001
    """Store the value ``r`` of element ``i`` (numba only)."""
    raise NotImplementedError


def _generated(source: str, name: str) -> Callable:
    scope = {"_at": _at, "__name__": __name__}
    exec(source, scope)  # noqa: S102  (a fixed template: the arity is the only variable)
    return scope[name]


@overload(_at)
def _at_impl(a, i):
    if isinstance(a, nbtypes.BaseNamedTuple):  # a record, or a Whole array: passed whole
        if a.instance_class is Whole:
            return lambda a, i: a.value
        return lambda a, i: a
    if isinstance(a, nbtypes.Array):
        return lambda a, i: a[i]
    if isinstance(a, nbtypes.BaseTuple) and all(isinstance(t, nbtypes.Array) for t in a):
        items = ", ".join(f"a[{k}][i]" for k in range(len(a)))
        return _generated(f"def at(a, i):\n    return ({items},)\n", "at")
    return lambda a, i: a


@overload(_put)
def _put_impl(out, i, r):
    if isinstance(r, nbtypes.BaseTuple):
        body = "".join(f"    out[i, {k}] = r[{k}]\n" for k in range(len(r)))
        return _generated(f"def put(out, i, r):\n{body}", "put")

    def put(out, i, r):
        out[i] = r

    return put


def _alloc(r, n):  # noqa: ARG001
    """An empty result array of ``n`` elements for values like ``r`` (numba only)."""
    raise NotImplementedError


@overload(_alloc)
def _alloc_impl(r, n):
    if isinstance(r, nbtypes.BaseTuple):
        k = len(r)
        return lambda r, n: np.empty((n, k), dtype=np.float64)
    if isinstance(r, nbtypes.Boolean):
        return lambda r, n: np.empty(n, dtype=np.bool_)
    if isinstance(r, nbtypes.Integer):
        return lambda r, n: np.empty(n, dtype=np.int64)
    return lambda r, n: np.empty(n, dtype=np.float64)


def _loop_code(arity: int) -> types.CodeType:
    """The loop over ``n`` elements calling ``f`` with ``arity`` arguments, each read at the
    element (written out: numba cannot inline a scalar function called with ``*args``)."""
    code = _CODES.get(arity)
    if code is None:
        call = ", ".join(f"_at(args[{k}], i)" for k in range(arity))
        first = call.replace("i)", "0)")
        source = (
            "def elementwise(args, n):\n"
            f"    out = _alloc(f({first}), n)\n"
            "    for i in range(n):\n"
            f"        _put(out, i, f({call}))\n"
            "    return out\n"
        )
        scope: dict = {}
        exec(compile(source, __file__, "exec"), scope)  # noqa: S102  (a fixed template)
        code = _CODES[arity] = scope["elementwise"].__code__
    return code


_CODES: dict[int, types.CodeType] = {}
_LOOPS: dict[tuple[int, int], Any] = {}
_LOCK = threading.Lock()


def _loop_of(scalar: Any, arity: int) -> Any:
    """The compiled loop calling ``scalar`` with ``arity`` arguments (built once, kept)."""
    key = (id(scalar), arity)
    loop = _LOOPS.get(key)
    if loop is not None:
        return loop[0]
    with _LOCK:
        loop = _LOOPS.get(key)
        if loop is None:
            py = scalar.py_func
            scope = {**globals(), "f": scalar}
            func = types.FunctionType(_loop_code(arity), scope, "elementwise")
            func.__qualname__ = f"elementwise.{py.__module__}.{py.__qualname__}"
            func.__module__ = __name__
            loop = _LOOPS[key] = (njit(func), scalar)  # keeps scalar alive with its id
    return loop[0]


def elementwise(scalar: Any, dtype: Any, *args: Any, compute: Any = np.float64) -> np.ndarray:
    """``scalar`` at every element of the broadcast arguments, as an array of ``dtype``.

    Parameters
    ----------
    scalar : numba function
        The formula's device function (``f.scalar``).
    dtype : numpy dtype
        The result's dtype (float32 or float64 for float results).
    *args
        ``scalar``'s arguments in order. A numpy array is broadcast with the other arrays and
        read element by element (float arrays in ``compute``); a plain tuple of arrays is a
        vector, read as a tuple of its components' elements; anything else (a Python number, a
        bool, a tuple of numbers, a named tuple such as a record or a :class:`Whole` array) is
        passed as it is to every element.
    compute : numpy dtype, keyword-only
        The float type arrays are read in (float64; float32 for a formula whose kernel computes
        in float32, with its constants passed as ``np.float32``).

    Returns
    -------
    ndarray of the broadcast shape, or that shape + (C,) where ``scalar`` returns a C-tuple.
    """
    fdt = np.dtype(compute)
    arrays = [a for a in args if isinstance(a, np.ndarray)]
    arrays += [c for a in args if _is_vector(a) for c in a]
    shape = np.broadcast_shapes(*(a.shape for a in arrays)) if arrays else ()
    size = int(np.prod(shape, dtype=np.int64))

    def flat(a: np.ndarray) -> np.ndarray:
        if a.dtype.kind == "f":
            a = a.astype(fdt, copy=False)
        if size == 0:  # an empty result is typed from one element of zeros
            a = np.zeros(1, dtype=a.dtype)
        else:
            a = np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(size)
        return readonly(a)  # whether or not broadcasting copied it: one loop signature

    packed = tuple(
        flat(a) if isinstance(a, np.ndarray) else tuple(flat(c) for c in a) if _is_vector(a) else a
        for a in args
    )
    out = _loop_of(scalar, len(packed))(packed, max(size, 1))[:size]
    result = out.reshape(shape + out.shape[1:])
    return result.astype(np.dtype(dtype), copy=False) if out.dtype.kind == "f" else result


def _is_vector(a: Any) -> bool:
    """A plain tuple of arrays (a vector argument); a named tuple (a record) is passed whole."""
    return type(a) is tuple and len(a) > 0 and all(isinstance(c, np.ndarray) for c in a)
