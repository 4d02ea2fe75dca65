"""Frames and golden cases on Dask distributed (the optional extra ``refnpr[distributed]``).

DESIGN.md: "Beyond one machine, frames and golden cases run on Dask distributed (a LocalCluster
by default, any cluster by scheduler address), with results identical to a serial run; never a
home-made process pool." This module is that: the same functions as
:func:`refnpr.sequence.render_sequence`, :func:`refnpr.golden.check_suite` and
:func:`refnpr.golden.update_suite`, with the rendering done by the workers of a cluster.

* **Cluster.** :func:`open_client` starts a ``LocalCluster(n_workers=N, threads_per_worker=1,
  processes=True)`` or connects to a running scheduler (``tcp://HOST:PORT``). One task runs at
  a time in each worker process; numba parallelizes inside it. A LocalCluster gives each worker
  ``NUMBA_NUM_THREADS`` (and the BLAS / OpenMP thread counts) ``max(1, cores // N)``, so N
  workers together use the machine's cores without oversubscribing them. The workers of an
  existing cluster keep their own settings (start them with ``--nthreads 1`` and
  ``NUMBA_NUM_THREADS`` set the same way). Pixels do not depend on the thread count. A
  LocalCluster sets no memory limit per worker (Dask would kill a worker over its share of the
  memory where a serial run succeeds): each frame's own memory check applies, as serially.
* **Frames.** Stateless styles (:func:`refnpr.sequence.is_stateful`; X-Toon's optical flow
  included, since its ``for_frame`` needs only the previous *still*, which the animation gives)
  render one task per frame. A stateful style renders chunks of consecutive frames, each from
  the style's ``initial_state()`` at ``warmup`` frames before the chunk (frame 0 at the
  latest); those warm-up frames are shaded for their state only and discarded. A frame equals
  the serial run's whenever the style's state depends on the last ``warmup`` frames only (and
  always in the first chunk); otherwise it differs the way documented in docs/animation.md
  ("Many machines"), and its record says so: ``"state_from": S``, the frame its state started
  from (serial records, whose state starts at 0, have no such key).
* **Files.** Workers return each frame's PNG bytes (encoded there, in parallel) and, for
  ``exr``, its float32 RGBA; the client writes the files and records, atomically, exactly as
  the serial driver does (one writer per directory, so the restart rules and a mixed serial /
  distributed resume hold; and the workers need no access to the output directory, so a
  remote cluster works as a local one). Golden cases come back as their images or G-buffer
  channels and are compared (reports, failure images, golden files) on the client by the
  serial code.
* **Progress** comes from the futures as they complete (``as_completed``); on an error or
  KeyboardInterrupt the futures are cancelled and a cluster this module started is closed.

Workers must be able to import refnpr (the same version: the frame records hold it); a
LocalCluster's do. Without dask installed every entry point raises a ``ValueError`` naming the
extra to install.
"""

from __future__ import annotations

import contextlib
import math
import os
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import golden as _golden
from . import sequence as _sequence
from ._jit import usable_cores
from .sequence import SequenceProgress, SequenceResult

__all__ = ["check_suite", "open_client", "render_sequence", "update_suite", "worker_threads"]

#: Default warm-up frames before each chunk of a stateful style.
DEFAULT_WARMUP = 8

_MISSING = (
    "needs Dask distributed, which is not installed; install the extra with "
    "`pip install 'refnpr[distributed]'` (or run without --workers / --scheduler)"
)


def _dask(what: str) -> Any:
    """The ``distributed`` module, or a ValueError naming the extra."""
    try:
        import distributed
    except ImportError:
        raise ValueError(f"{what}: {_MISSING}") from None
    return distributed


def worker_threads(n_workers: int, cores: int | None = None) -> int:
    """Numba (and BLAS) threads each of ``n_workers`` LocalCluster workers gets.

    ``max(1, cores // n_workers)``, where ``cores`` defaults to the CPUs this process may run
    on: the workers share the cores instead of each starting a thread per core.
    """
    if cores is None:
        cores = usable_cores()
    return max(1, cores // n_workers)


def _check_workers(workers: Any, scheduler: Any) -> None:
    if workers is not None and scheduler is not None:
        raise ValueError(
            f"workers / scheduler: give one, not both (got workers={workers!r} and scheduler="
            f"{scheduler!r}): workers starts a local cluster, scheduler connects to a running one"
        )
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise ValueError(f"workers: expected a whole number >= 1, got {workers!r}")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ValueError(
            f"scheduler: expected a scheduler address such as 'tcp://10.0.0.5:8786', got "
            f"{scheduler!r}"
        )


@contextlib.contextmanager
def open_client(workers: int | None = None, scheduler: str | None = None) -> Iterator[Any]:
    """A ``distributed.Client``: a new LocalCluster of ``workers`` processes, or ``scheduler``.

    Parameters
    ----------
    workers : int, optional
        Start ``LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)`` (no
        dashboard), each worker with :func:`worker_threads` numba threads. Default when neither
        is given: 2.
    scheduler : str, optional
        Connect to a running cluster (``tcp://HOST:PORT``) instead; it is not closed afterwards.

    Yields
    ------
    distributed.Client
        Closed (and the LocalCluster with it) when the block ends, on errors and
        KeyboardInterrupt too.
    """
    _check_workers(workers, scheduler)
    what = "scheduler" if scheduler is not None else "workers"
    dd = _dask(what)
    import logging

    if scheduler is not None:
        try:
            client = dd.Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise ValueError(
                f"scheduler: cannot connect to {scheduler!r} ({exc}); start one with "
                "`dask scheduler` and workers with `dask worker ADDRESS --nthreads 1`, or use "
                "--workers N for a local cluster"
            ) from None
        try:
            yield client
        finally:
            client.close()
        return
    n = 2 if workers is None else workers
    threads = str(worker_threads(n))
    env = {
        k: threads
        for k in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    }
    cluster = dd.LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        memory_limit=0,  # no nanny kills or spilling: refnpr's own memory check guards a frame
        dashboard_address=":0",  # no dashboard on the shared port 8787
        silence_logs=logging.CRITICAL,  # worker errors reach the client as exceptions
        env=env,
    )
    try:
        client = dd.Client(cluster)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()


@contextlib.contextmanager
def _client_for(client: Any, workers: Any, scheduler: Any, what: str) -> Iterator[Any]:
    """The caller's client (left open), or one of :func:`open_client`."""
    if client is not None:
        if workers is not None or scheduler is not None:
            raise ValueError(
                f"client: give a client or workers / scheduler, not both (got workers="
                f"{workers!r}, scheduler={scheduler!r})"
            )
        _dask(what)
        yield client
        return
    with open_client(workers, scheduler) as c:
        yield c


def _as_completed(client: Any, futures: list[Any]) -> Iterator[Any]:
    """Each future as it completes; all cancelled when the iteration stops early (an error or
    KeyboardInterrupt here or in the consumer, which closes the generator)."""
    import distributed

    finished = False
    try:
        yield from distributed.as_completed(futures)
        finished = True
    finally:
        if not finished:
            with contextlib.suppress(Exception):
                client.cancel(futures)


# -- frames -------------------------------------------------------------------------------------


def _frame_payload(plan: Any, f: int, image: Any) -> tuple[int, bytes, np.ndarray | None]:
    rgba = np.array(image.rgba, dtype=np.float32) if plan.exr else None  # the buffer is reused
    return f, _sequence._png_bytes(image), rgba


def _frame_task(plan: Any, f: int) -> list[tuple[int, bytes, np.ndarray | None]]:
    """Worker: one frame of a stateless style (its previous still from the animation)."""
    shader = _sequence._Shader(plan, f)
    return [_frame_payload(plan, f, shader.shade(f))]


def _chunk_task(
    plan: Any, start: int, stop: int, wanted: Sequence[int]
) -> list[tuple[int, bytes, np.ndarray | None]]:
    """Worker: frames ``start .. stop - 1`` of a stateful style from its initial state at
    ``start``; only the ``wanted`` frames are returned (the others are warm-up or done)."""
    shader = _sequence._Shader(plan, start)
    keep = set(wanted)
    out = []
    for f in range(start, stop):
        image = shader.shade(f)
        if f in keep:
            out.append(_frame_payload(plan, f, image))
    return out


def _n_workers(client: Any) -> int:
    try:
        info = client.scheduler_info(n_workers=-1)  # newer versions list only a few by default
    except TypeError:
        info = client.scheduler_info()
    return max(1, len(info.get("workers", {})))


def _chunks(todo: range, n: int, chunk: int | None) -> list[range]:
    size = chunk if chunk is not None else max(1, math.ceil(len(todo) / max(1, n)))
    return [range(a, min(a + size, todo.stop)) for a in range(todo.start, todo.stop, size)]


def render_sequence(
    scene: Any,
    style: Any = None,
    width: int = 512,
    height: int = 512,
    spp: int = 1,
    *,
    out_dir: str | os.PathLike,
    frames: Any = None,
    exr: bool = False,
    progress: SequenceProgress | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
    chunk: int | None = None,
    warmup: int = DEFAULT_WARMUP,
) -> SequenceResult:
    """:func:`refnpr.sequence.render_sequence` with the frames rendered on a Dask cluster.

    Files, records and restart rules are the serial driver's; for a stateless style the
    directory is byte-identical to a serial run's (module docstring).

    Parameters
    ----------
    scene, style, width, height, spp, out_dir, frames, exr
        As for :func:`refnpr.sequence.render_sequence`.
    progress : callable(done, total, frame, status), optional
        Called for each frame as its result arrives (``"rendered"``), after the done frames
        (``"skipped"``); frames arrive in completion order, not frame order.
    workers, scheduler, client
        Where to run: a new LocalCluster of ``workers`` processes (default 2), a running
        cluster's ``scheduler`` address, or an open ``distributed.Client`` (left open).
    chunk : int, optional
        Stateful styles: frames per chunk (default: the range split evenly over the workers).
    warmup : int
        Stateful styles: frames shaded before each chunk for the state only (default 8).

    Returns
    -------
    SequenceResult
        ``rendered`` in frame order.
    """
    t_start = time.perf_counter()
    for name, value, lo in (("chunk", chunk, 1), ("warmup", warmup, 0)):
        if value is None and name == "chunk":
            continue
        if isinstance(value, bool) or not isinstance(value, int) or value < lo:
            raise ValueError(f"{name}: expected a whole number >= {lo}, got {value!r}")
    _check_workers(workers, scheduler)
    what = "scheduler" if scheduler is not None else "workers"
    _dask(what)
    plan = _sequence._plan(scene, style, width, height, spp, out_dir, frames, exr, progress)
    todo = plan.todo
    result = SequenceResult(plan.out, list(todo), stateful=plan.stateful)
    result.paths = [plan.out / f"{_sequence.FRAME_NAME.format(f)}.png" for f in todo]
    missing = [f for f in todo if not plan.done(f)]
    result.skipped = [f for f in todo if f not in set(missing)]
    count = 0
    for f in result.skipped:
        count += 1
        if progress is not None:
            progress(count, len(todo), f, "skipped")
    if missing:
        with _client_for(client, workers, scheduler, what) as c:
            [plan_f] = c.scatter([plan], broadcast=True, hash=False)
            extra: dict[int, dict[str, Any]] = {}
            if not plan.stateful:
                futures = [c.submit(_frame_task, plan_f, f, pure=False) for f in missing]
            else:
                n = _n_workers(c)
                futures = []
                left = set(missing)
                for part in _chunks(todo, n, chunk):
                    wanted = [f for f in part if f in left]
                    if not wanted:
                        continue
                    start = max(0, part.start - warmup)
                    stop = max(wanted) + 1
                    futures.append(c.submit(_chunk_task, plan_f, start, stop, wanted, pure=False))
                    if start > 0:
                        extra.update({f: {"state_from": start} for f in wanted})
            with contextlib.closing(_as_completed(c, futures)) as arrived:
                for fut in arrived:
                    payload = fut.result()
                    fut.release()  # the workers forget it (an EXR frame's RGBA is large)
                    for f, png, rgba in payload:
                        _sequence._write_frame(plan, f, png, rgba, extra.get(f))
                        result.rendered.append(f)
                        count += 1
                        if progress is not None:
                            progress(count, len(todo), f, "rendered")
    result.rendered.sort()
    result.seconds = time.perf_counter() - t_start
    return result


# -- golden cases -------------------------------------------------------------------------------


def _case_task(case: Any, catch: bool) -> tuple[Any, str | None]:
    """Worker: one golden case rendered; with ``catch``, a render error as check_suite words it."""
    if not catch:
        return _golden.render_case(case), None
    return _golden.render_or_error(case)


def _case_renderer(client: Any, catch: bool) -> Any:
    def render_cases(cases: Sequence[Any]) -> Iterator[tuple[int, Any, str | None]]:
        futures = [client.submit(_case_task, case, catch, pure=False) for case in cases]
        index = {fut.key: i for i, fut in enumerate(futures)}
        with contextlib.closing(_as_completed(client, futures)) as arrived:
            for fut in arrived:
                got, error = fut.result()
                fut.release()
                yield index[fut.key], got, error

    return render_cases


def check_suite(
    suite_path: str | Path,
    *,
    only: list[str] | None = None,
    failure_dir: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
) -> list[Any]:
    """:func:`refnpr.golden.check_suite` with the cases rendered on a Dask cluster.

    Same results (in suite order), messages and failure images as the serial check; the
    comparison runs on the client. ``workers``, ``scheduler``, ``client``: as for
    :func:`render_sequence`.
    """
    _check_workers(workers, scheduler)
    what = "scheduler" if scheduler is not None else "workers"
    _dask(what)
    _golden.load_suite(suite_path)  # a bad suite fails before a cluster starts
    with _client_for(client, workers, scheduler, what) as c:
        return _golden.check_suite(
            suite_path,
            only=only,
            failure_dir=failure_dir,
            render_cases=_case_renderer(c, catch=True),
        )


def update_suite(
    suite_path: str | Path,
    *,
    only: list[str] | None = None,
    log: Any = print,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
) -> list[Path]:
    """:func:`refnpr.golden.update_suite` with the cases rendered on a Dask cluster.

    The same golden files, written by the client as each case arrives (``log`` lines in
    completion order; the returned paths in suite order). A case that fails to render raises
    its error, as serially.
    """
    _check_workers(workers, scheduler)
    what = "scheduler" if scheduler is not None else "workers"
    _dask(what)
    _golden.load_suite(suite_path)
    with _client_for(client, workers, scheduler, what) as c:
        return _golden.update_suite(
            suite_path, only=only, log=log, render_cases=_case_renderer(c, catch=False)
        )
