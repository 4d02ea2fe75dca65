"""The one place that owns refnpr's numba flags.

Every numba kernel in refnpr is decorated with :func:`njit` or :func:`banded` from this
module, so the reference path is compiled the same way everywhere: ``fastmath`` off (IEEE semantics, no
reassociation, so results do not depend on vector width), ``cache=True`` (a warm start does not
recompile), ``error_model="numpy"`` (division by zero gives inf/nan instead of raising inside a
kernel; public functions validate their inputs so that this never reaches an image).

Where numba finds no writable cache directory (``NUMBA_CACHE_DIR``, ``__pycache__`` beside the
source, the user-wide cache under ``HOME``: a read-only install with an unwritable home) it
raises "cannot cache function ...: no locator available" when a kernel is decorated, that is at
import. Then the kernel is cached in a private directory under :func:`tempfile.gettempdir`
instead, and where that is not writable either it is compiled without caching, with one warning.

numba keys a cached kernel on its own source file (modification time and size) and bytecode,
not on the functions it calls: a kernel in one file that calls a formula's ``f.scalar`` in
another would load its stale machine code after the formula was edited. Every function compiled
here therefore also keys its cache entries on the files of every numba function it reaches
(through its globals, the attributes it reads of them, and its closure), followed
transitively: editing ``f.scalar``'s body recompiles every kernel that calls it, on its next
call, in every process (:func:`dependency_files`).

numba writes a new cache entry by reading the kernel's index, picking the first unused data file
name and rewriting the index. Two processes doing that for two signatures of one kernel at the
same moment (``refnpr warmup --jobs``, pytest-xdist workers, Dask workers on one machine) can
pick the same data file, leaving an index entry that names the other signature's code. Each
save is therefore made under an exclusive ``flock`` on ``<index>.lock`` beside the index
(POSIX; elsewhere numba's own behaviour).

This module imports nothing of refnpr and may be imported by every subpackage.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import os
import pickle
import stat
import tempfile
import threading
import types
import warnings
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np
from numba._dispatcher import compute_fingerprint as _fingerprint
from numba.core import caching as _numba_caching
from numba.core import config as _numba_config
from numba.core.typing.typeof import Purpose as _Purpose

try:
    import fcntl
except ImportError:  # not POSIX: numba's unlocked saves
    fcntl = None

#: Flags of the reference path. ``fastmath`` is off on purpose: see module docstring.
JIT_FLAGS: dict = {"cache": True, "fastmath": False, "nogil": True, "error_model": "numpy"}


def _locked_save(save):
    """numba's ``IndexDataCacheFile.save`` under an exclusive lock on ``<index>.lock``."""

    def locked_save(self, key, data):
        path = getattr(self, "_index_path", None)
        fd = None
        if path is not None:
            try:
                fd = os.open(path + ".lock", os.O_RDWR | os.O_CREAT, 0o600)
                fcntl.flock(fd, fcntl.LOCK_EX)
            except OSError:  # an unwritable directory, a file system without locks: unlocked
                if fd is not None:
                    os.close(fd)
                fd = None
        try:
            return save(self, key, data)
        finally:
            if fd is not None:
                os.close(fd)  # releases the lock

    locked_save.refnpr_locked = True
    locked_save.__wrapped__ = save
    return locked_save


if fcntl is not None and not getattr(_numba_caching.IndexDataCacheFile.save, "refnpr_locked", 0):
    _numba_caching.IndexDataCacheFile.save = _locked_save(_numba_caching.IndexDataCacheFile.save)


def _tolerant_load_index(load_index):
    """numba's ``IndexDataCacheFile._load_index``, reading an index it cannot unpickle as
    empty (stale): an index written by an older refnpr can name a record type that no longer
    exists, and numba would raise instead of recompiling."""

    def tolerant_load_index(self):
        try:
            return load_index(self)
        except (AttributeError, ImportError, EOFError, ValueError, TypeError, IndexError) as exc:
            if isinstance(exc, TypeError) and "pickle" not in str(exc).lower():
                raise
            return {}
        except pickle.UnpicklingError:
            return {}

    tolerant_load_index.refnpr_tolerant = True
    tolerant_load_index.__wrapped__ = load_index
    return tolerant_load_index


if not getattr(_numba_caching.IndexDataCacheFile._load_index, "refnpr_tolerant", 0):
    _numba_caching.IndexDataCacheFile._load_index = _tolerant_load_index(
        _numba_caching.IndexDataCacheFile._load_index
    )


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


def _jit_cached(func, flags: dict):
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


# -- Cache entries keyed on the sources a kernel calls into.


def _dispatchers_in(value, names: frozenset[str]) -> list:
    """The numba functions a global ``value`` of a kernel gives it: the value itself, or
    (a module, a formula's numpy face, a banded kernel) its attributes that the kernel names."""
    if isinstance(value, numba.core.dispatcher.Dispatcher):
        return [value]
    if isinstance(value, Banded):
        return [value.body]
    if value is None or isinstance(value, (int, float, bool, str, bytes)):
        return []
    found = []
    for name in names:
        try:
            attr = getattr(value, name, None)
        except Exception:  # noqa: BLE001 (an object whose attributes raise: not a dependency)
            continue
        if isinstance(attr, numba.core.dispatcher.Dispatcher):
            found.append(attr)
        elif isinstance(attr, Banded):
            found.append(attr.body)
    return found


def _code_names(code: types.CodeType) -> frozenset[str]:
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _code_names(const)
    return frozenset(names)


def dependency_files(py_func) -> tuple[str, ...]:
    """The source files of ``py_func`` and of every numba function it may call, transitively.

    A callee is found where the compiled code can reach one: a global name of the function
    (``detail_depth_scalar``), an attribute it reads of a global (``K.shade``, a module's
    function; ``f.scalar``, a formula's device function), or a closure variable (a kernel
    built by a factory). Sorted, each once.
    """
    files: set[str] = set()
    seen: set[int] = set()
    stack = [py_func]
    while stack:
        func = stack.pop()
        if id(func) in seen or not hasattr(func, "__code__"):
            continue
        seen.add(id(func))
        code = func.__code__
        files.add(code.co_filename)
        names = _code_names(code)
        scope = getattr(func, "__globals__", {})
        values = [scope[n] for n in names if n in scope]
        values += [cell.cell_contents for cell in (func.__closure__ or ()) if _has_contents(cell)]
        for value in values:
            stack.extend(d.py_func for d in _dispatchers_in(value, names))
    return tuple(sorted(files))


def _has_contents(cell) -> bool:
    try:
        cell.cell_contents  # noqa: B018
    except ValueError:  # an empty cell (the closure's variable is not bound yet)
        return False
    return True


def _stamp(files: tuple[str, ...]) -> str:
    """A hash of each file's name, modification time and size (numba's own source stamp)."""
    h = hashlib.sha256()
    for path in files:
        try:
            st = os.stat(path)
            h.update(f"{path}\0{st.st_mtime_ns}\0{st.st_size}\0".encode())
        except OSError:  # a file that is gone: its name alone
            h.update(f"{path}\0-\0".encode())
    return h.hexdigest()


def _track_dependencies(dispatcher) -> None:
    """Key ``dispatcher``'s cache entries also on :func:`dependency_files` (found on first use,
    when every callee is defined)."""
    cache = getattr(dispatcher, "_cache", None)
    if cache is None or not hasattr(cache, "_index_key"):
        return
    base = cache._index_key
    found: list[tuple[str, ...]] = []

    def _index_key(sig, codegen):
        if not found:
            found.append(dependency_files(dispatcher.py_func))
        key = base(sig, codegen)
        return key[:-1] + (key[-1] + (_stamp(found[0]),),)

    cache._index_key = _index_key


def njit(func=None, **overrides):
    """Serial numba kernel with refnpr's flags (``@njit`` or ``@njit(boundscheck=True)``)."""
    if func is None:
        return lambda f: njit(f, **overrides)
    kernel = _jit_cached(func, {**JIT_FLAGS, **overrides})
    _track_dependencies(kernel)
    return kernel


def readonly(a):
    """A read-only view of the array ``a`` (``a`` itself if it is read-only already).

    numba types an array argument's writability, so a kernel called with a writable array in
    one call and a read-only one (a ``np.broadcast_to`` view, a cached array) in another is
    compiled twice. An input that the kernel only reads is passed through this, so that every
    call has one signature."""
    if a.flags.writeable:
        a = a.view()
        a.flags.writeable = False
    return a


def _is_record(value) -> bool:
    return isinstance(value, tuple) and hasattr(value, "_fields")


def frozen(record):
    """``record`` (a named tuple of arrays, numbers and records) with every array in it read-only
    (:func:`readonly`), records inside it too.

    numba types an array's writability: a kernel reading a G-buffer channel rasterized here
    (writable) in one frame and one loaded from a kit (read-only) in another would be compiled
    twice. The records that kernels only read are built frozen (``styles._frame.frame_record``,
    the styles' tables)."""
    return type(record)(
        *(
            readonly(v) if isinstance(v, np.ndarray) else frozen(v) if _is_record(v) else v
            for v in record
        )
    )


# -- Banded kernels: a serial nogil kernel run over contiguous bands of its loop on Python threads.

#: Worker threads shared by every banded kernel (created on first use, dropped in a forked child).
_POOL: list[ThreadPoolExecutor] = []
_POOL_LOCK = threading.Lock()


def usable_cores() -> int:
    """The CPUs this process may run on (its affinity mask; ``os.cpu_count()`` where there is
    none, as on macOS)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _pool() -> ThreadPoolExecutor:
    with _POOL_LOCK:
        if not _POOL:
            workers = max(1, int(_numba_config.NUMBA_NUM_THREADS) - 1)
            _POOL.append(ThreadPoolExecutor(workers, thread_name_prefix="refnpr-band"))
        return _POOL[0]


def _drop_pool() -> None:  # threads do not survive fork: a child makes its own pool
    _POOL.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_drop_pool)


def band_bounds(n: int, parts: int) -> list[tuple[int, int]]:
    """``[0, n)`` split into ``min(parts, n)`` contiguous bands of sizes differing by at most 1."""
    k = max(1, min(int(parts), int(n)))
    return [(i * n // k, (i + 1) * n // k) for i in range(k)]


#: Bands per thread of a banded call with the default banding. The threads take bands in turn
#: from a shared counter, so a thread whose bands hold less work (empty rows around an object)
#: takes more of them; with one band per thread the busier half of an image set the time
#: (teapot toon shading: 11.6 vs 23.6 ms per half). A band costs ~1 us of dispatch.
BANDS_PER_THREAD = 16


def run_bands(body, n: int, args: tuple, parts: int | None = None) -> None:
    """Call ``body(lo, hi, *args)`` for the bands of ``[0, n)`` on the numba threads.

    The loop is cut into ``parts`` contiguous bands (default :data:`BANDS_PER_THREAD` per
    thread of :func:`numba.get_num_threads`, so ``numba.set_num_threads`` and
    ``NUMBA_NUM_THREADS`` govern banded kernels as they govern ``prange``), which the calling
    thread and the pool's threads take in turn until none is left (dynamic scheduling: load
    balance whatever the image holds). The kernels release the GIL (``nogil``), so bands run in
    parallel. Each index of the loop is independent of the others (the contract of every banded
    kernel), so the output does not depend on the bands or on which thread ran them:
    bit-identical for any thread count. An exception in any band is raised here after all
    running bands have finished (a thread stops taking bands after its first error; the others
    go on).
    """
    threads = numba.get_num_threads()
    if parts is None:
        parts = threads * BANDS_PER_THREAD if threads > 1 else 1
    bounds = band_bounds(n, parts)
    if len(bounds) == 1:
        body(0, n, *args)
        return
    ticket = itertools.count()  # next() on a count is atomic under the GIL
    errors: list[BaseException] = []

    def work() -> None:
        for i in ticket:
            if i >= len(bounds):
                return
            lo, hi = bounds[i]
            try:
                body(lo, hi, *args)
            except BaseException as exc:  # raised by the caller once every thread is done
                errors.append(exc)
                return

    pool = _pool()
    # pool threads besides the caller: one per further numba thread, and at least one where
    # the caller asked for several bands on one thread (``parts``)
    helpers = min(len(bounds), max(threads, 2)) - 1
    futures = [pool.submit(work) for _ in range(helpers)]
    work()
    for f in futures:
        f.result()
    if errors:
        raise errors[0]


class Banded:
    """A serial kernel ``body(lo, hi, *args)`` called as ``kernel(*args)`` over bands.

    Attributes: ``body`` (the numba dispatcher: its ``signatures``, ``py_func`` and cache are
    the compiled code), ``count`` (``count(*args) -> n``, the loop's length).
    """

    def __init__(self, body, count, parts=None):
        self.body = body
        self.count = count
        self.parts = parts
        self.py_func = body.py_func
        functools.update_wrapper(self, body.py_func)

    def __call__(self, *args):
        run_bands(self.body, int(self.count(*args)), args, self.parts)

    def __repr__(self) -> str:
        return f"<banded kernel {self.__module__}.{self.__qualname__}>"


def banded(count):
    """Decorator: a parallel kernel as a serial :func:`njit` body over bands of its loop.

    ``count(*args) -> int`` gives the length ``n`` of the parallel loop from the kernel's
    arguments (without ``lo, hi``), or is the name of an array argument whose first axis the
    loop runs over (``@banded("out")``); the decorated function takes ``lo, hi`` first and runs
    ``for i in range(lo, hi)`` where a ``prange`` kernel loops over ``range(n)``, over bands that
    the threads take in turn (:func:`run_bands`; ``Banded(body, count, parts)`` fixes the number
    of bands). Compiles in about half the time of the ``prange`` form (no parallel lowering)
    and, measured on refnpr's kernels, runs as fast or faster (numba's default schedule gives
    each thread one contiguous band, which leaves a thread idle where an image's halves differ in
    work) provided the loop reads no row views: read rows as scalars
    (``refnpr/raster/_kernels.py``).

    Example::

        @banded(lambda out, x: out.shape[0])
        def double(lo, hi, out, x):
            for i in range(lo, hi):
                out[i] = 2.0 * x[i]
    """

    def deco(func):
        length = count
        if isinstance(count, str):  # the rows of an array argument
            names = func.__code__.co_varnames[2 : func.__code__.co_argcount]
            if count not in names:
                raise TypeError(f"banded({count!r}): {func.__qualname__} has no argument {count!r}")
            index = names.index(count)

            def length(*args, _i=index):
                return args[_i].shape[0]

        return Banded(njit(func), length)

    return deco


#: (kernel body, numba's type fingerprint of the arguments) -> the compiled function.
_TYPED: dict = {}


def call_banded(kernel, *args):
    """``kernel(*args)`` for a :class:`Banded` kernel, its arguments typed once for all bands.

    numba's dispatcher types the arguments of every call, a record (a named tuple) field by
    field: a few microseconds per band for a kernel taking several records (the rasterizer's
    visibility pass: 5 us against 1.3 us for the same arrays as plain arguments; 3% of a 1080p
    G-buffer of 82k triangles). Here numba's own fingerprint of the arguments (the key of its
    dispatch cache) picks the compiled function once per call, and every band calls it
    directly: the same machine code and results as ``kernel(*args)``.
    """
    body = kernel.body
    try:
        key = (body, _fingerprint(args))
    except Exception:  # noqa: BLE001 (a value numba does not fingerprint: its own dispatch)
        kernel(*args)
        return
    entry = _TYPED.get(key)
    if entry is None:  # typed as the dispatcher types a call (lo, hi: Python ints)
        sig = tuple(numba.typeof(a, _Purpose.argument) for a in (0, 0, *args))
        entry = _TYPED[key] = body.compile(sig)
    run_bands(entry, int(kernel.count(*args)), args, kernel.parts)


# -- Kernels specialised to the modes a frame uses.


def specialised(factory):
    """Decorator: ``factory(*modes) -> kernel``, called once per combination of modes.

    A large one-pass kernel with every option of its style behind run-time codes (``if src ==
    SRC_LINES``) compiles every option's code on its first call, whichever options the frame
    uses. Written instead as a factory whose modes the kernel reads as closure constants, each
    combination is its own kernel, and numba prunes the branches of the other modes before
    typing them (``numba.core.analysis.dead_branch_prune``: a comparison of two constants), so a
    frame compiles only the code its modes reach. numba caches each combination on disk apart:
    the closure's values are part of a cached kernel's key. The modes must be hashable and
    picklable (ints, bools, floats, strings).

    The returned callable ``get(*modes)`` gives the kernel for those modes, built on first use
    and kept (``get.kernels``: dict of modes to kernel). Example::

        @specialised
        def scale_for(mode):
            @njit
            def scale(out, x):
                for i in range(x.shape[0]):
                    out[i] = 2.0 * x[i] if mode == 0 else x[i] * x[i]

            return scale

        scale_for(0)(out, x)
    """
    kernels: dict = {}
    lock = threading.Lock()

    def get(*modes):
        kernel = kernels.get(modes)
        if kernel is None:
            with lock:
                kernel = kernels.get(modes)
                if kernel is None:
                    kernel = kernels[modes] = factory(*modes)
        return kernel

    get.kernels = kernels
    return functools.update_wrapper(get, factory)


# -- A device function inlined into a hot loop.

_INLINE_COPIES: dict = {}
_INLINE_LOCK = threading.RLock()


def inline_copy(func, keep=()):
    """``func`` (a numba function) compiled from its own source with ``inline="always"``, so
    that numba inlines its body into the caller's IR; the numba functions it calls are inline
    copies too, except those in ``keep`` (plain calls).

    For a hot loop: a device or formula function that LLVM does not inline is a call per
    element, and one that takes arrays takes and drops their references each time; its body
    inlined, LLVM vectorizes the loop, hoists what does not change, and shares what two
    callees compute alike. ``keep`` names small functions of numbers, which LLVM inlines
    itself (fewer copies to type: inlining costs compile time at every call site). The copy
    reads the same code object, so editing the function's source changes it and its callers'
    cache entries (:func:`dependency_files`). Kept per function and ``keep``.
    """
    key = (func, tuple(keep))
    with _INLINE_LOCK:
        copy = _INLINE_COPIES.get(key)
        if copy is not None:
            return copy
        py = func.py_func
        scope = dict(py.__globals__)
        for name in _code_names(py.__code__):
            value = scope.get(name)
            if isinstance(value, numba.core.dispatcher.Dispatcher) and value not in keep:
                scope[name] = inline_copy(value, keep)
        # name, qualname, docstring and module come with the code object and the globals
        clone = types.FunctionType(py.__code__, scope, py.__name__, py.__defaults__, py.__closure__)
        flags = {**JIT_FLAGS, "cache": False, "inline": "always"}
        copy = _INLINE_COPIES[key] = numba.njit(**flags)(clone)
        return copy
