"""Frames and golden cases on Dask distributed (the optional extra ``refnpr[distributed]``).

The functions of :mod:`refnpr.sequence` and :mod:`refnpr.golden` with the rendering done by the
workers of a cluster, results identical to a serial run (docs/animation.md, "Many machines"): a
``LocalCluster`` of single-threaded worker processes sharing the cores, or a running scheduler.
Stateless styles render one task per frame; a stateful style renders chunks of consecutive
frames, each from its ``initial_state()`` ``warmup`` frames before the chunk (a frame whose
state did not start at frame 0 records ``"state_from": S``). Workers return PNG bytes (and EXR
RGBA) or golden renders; the client writes every file and compares, with the serial code. On an
error or KeyboardInterrupt the futures are cancelled and a cluster started here is closed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import math
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import golden as _golden
from . import sequence as _sequence
from ._jit import usable_cores
from .sequence import SequenceResult

__all__ = ["check_suite", "open_client", "render_sequence", "update_suite", "worker_threads"]

#: Default warm-up frames before each chunk of a stateful style.
DEFAULT_WARMUP = 8


def _dask(what: str) -> Any:
    """The ``distributed`` module, or a ValueError naming the extra."""
    try:
        import distributed
    except ImportError:
        raise ValueError(
            f"{what}: needs Dask distributed, which is not installed; install the extra with "
            "`pip install 'refnpr[distributed]'` (or run without --workers / --scheduler)"
        ) from None
    return distributed


def worker_threads(n_workers: int, cores: int | None = None) -> int:
    """Numba (and BLAS) threads each of ``n_workers`` LocalCluster workers gets.

    ``max(1, cores // n_workers)``, where ``cores`` defaults to the CPUs this process may run
    on: the workers share the cores instead of each starting a thread per core.
    """
    if cores is None:
        cores = usable_cores()
    return max(1, cores // n_workers)


def _check_workers(workers: Any, scheduler: Any) -> Any:
    """Where to run, checked before any work; the ``distributed`` module (a ValueError naming
    the option given when Dask is not installed)."""
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
    return _dask("scheduler" if scheduler is not None else "workers")


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
    dd = _check_workers(workers, scheduler)
    import logging

    with contextlib.ExitStack() as stack:
        if scheduler is not None:
            try:
                client = dd.Client(scheduler, timeout="10s")
            except (OSError, TimeoutError) as exc:
                raise ValueError(
                    f"scheduler: cannot connect to {scheduler!r} ({exc}); start one with "
                    "`dask scheduler` and workers with `dask worker ADDRESS --nthreads 1`, or "
                    "use --workers N for a local cluster"
                ) from None
        else:
            n = 2 if workers is None else workers
            threads = str(worker_threads(n))
            cluster = dd.LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                memory_limit=0,  # no nanny kills or spilling: refnpr's memory check guards a frame
                dashboard_address=":0",  # no dashboard on the shared port 8787
                silence_logs=logging.CRITICAL,  # worker errors reach the client as exceptions
                env={f"{k}_NUM_THREADS": threads for k in ("NUMBA", "OMP", "OPENBLAS", "MKL")},
            )
            stack.callback(cluster.close)
            client = dd.Client(cluster)
        stack.callback(client.close)  # first: the client, then the cluster
        yield client


@contextlib.contextmanager
def _client_for(client: Any, workers: Any, scheduler: Any) -> Iterator[Any]:
    """The caller's client (left open), or one of :func:`open_client`."""
    if client is not None:
        if workers is not None or scheduler is not None:
            raise ValueError(
                f"client: give a client or workers / scheduler, not both (got workers="
                f"{workers!r}, scheduler={scheduler!r})"
            )
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


def _chunk_task(
    plan: Any, start: int, stop: int, wanted: Sequence[int]
) -> list[tuple[int, bytes, Any]]:
    """Worker: frames ``start .. stop - 1`` from the style's initial state at ``start`` (one
    frame of a stateless style, its previous still from the animation); only the ``wanted``
    frames are returned (the others are warm-up or done)."""
    shader = _sequence._Shader(plan)
    out = []
    for f in range(start, stop):
        image = shader.shade(f)
        if f in wanted:
            # the EXR's image with its passes; rgba copied (the context reuses its buffer)
            frame = dataclasses.replace(image, rgba=np.array(image.rgba)) if plan.exr else None
            out.append((f, image.to_png_bytes(), frame))
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
    *args: Any,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
    chunk: int | None = None,
    warmup: int = DEFAULT_WARMUP,
    **kwargs: Any,
) -> SequenceResult:
    """:func:`refnpr.sequence.render_sequence` with the frames rendered on a Dask cluster.

    Files, records and restart rules are the serial driver's; for a stateless style the
    directory is byte-identical to a serial run's (module docstring).

    Parameters
    ----------
    *args, **kwargs
        ``scene, style, width, height, spp, out_dir, frames, exr, progress`` as for
        :func:`refnpr.sequence.render_sequence`; ``progress`` is called for each frame as its
        result arrives (``"rendered"``), in completion order, after the done frames
        (``"skipped"``).
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
    bound = inspect.signature(_sequence.render_sequence).bind(*args, **kwargs)
    bound.apply_defaults()
    plan = _sequence._plan(**bound.arguments)
    with _sequence.claim(plan.out, plan.created):
        result = _run_sequence(
            plan, bound.arguments["progress"], (client, workers, scheduler), chunk, warmup
        )
    result.seconds = time.perf_counter() - t_start
    return result


def _run_sequence(plan: Any, progress: Any, where: tuple, chunk: Any, warmup: int) -> Any:
    """The missing frames of ``plan`` on the cluster of ``where`` (client, workers, scheduler)."""
    client, workers, scheduler = where
    todo, result = plan.todo, plan.result()
    missing = [f for f in todo if not plan.done(f)]
    for f in todo:
        if f not in missing:
            result._tick(f, "skipped", progress)
    if missing:
        with _client_for(client, workers, scheduler) as c:
            [plan_f] = c.scatter([plan], broadcast=True, hash=False)
            parts = [(f, f + 1, [f]) for f in missing]  # (start, stop, wanted) of each task
            if plan.stateful:
                parts = []
                for part in _chunks(todo, _n_workers(c), chunk):
                    wanted = [f for f in part if f in missing]
                    if wanted:
                        parts.append((max(0, part.start - warmup), max(wanted) + 1, wanted))
            extra = {  # the frames of a chunk whose state did not start at frame 0
                f: {"state_from": start}
                for start, _, wanted in parts
                if plan.stateful and start > 0
                for f in wanted
            }
            futures = [c.submit(_chunk_task, plan_f, *part, pure=False) for part in parts]
            with contextlib.closing(_as_completed(c, futures)) as arrived:
                for fut in arrived:
                    payload = fut.result()
                    fut.release()  # the workers forget it (an EXR frame's RGBA is large)
                    for f, png, frame in payload:
                        _sequence._write_frame(plan, f, png, frame, extra.get(f))
                        result._tick(f, "rendered", progress)
    result.rendered.sort()
    return result


# -- golden cases -------------------------------------------------------------------------------


def _golden_on_cluster(run: Any, suite_path: Any, where: tuple, catch: bool, **kwargs: Any) -> Any:
    """``run`` (golden.check_suite / update_suite) with its cases rendered on the cluster of
    ``where`` (workers, scheduler, client); ``catch``: render errors as check_suite words them."""
    workers, scheduler, client = where
    _check_workers(workers, scheduler)
    _golden.load_suite(suite_path)  # a bad suite fails before a cluster starts
    with _client_for(client, workers, scheduler) as c:

        def render_cases(cases: Sequence[Any]) -> Iterator[tuple[int, Any, str | None]]:
            futures = [c.submit(_golden._render, case, catch, pure=False) for case in cases]
            index = {fut.key: i for i, fut in enumerate(futures)}
            with contextlib.closing(_as_completed(c, futures)) as arrived:
                for fut in arrived:
                    got, error = fut.result()
                    fut.release()
                    yield index[fut.key], got, error

        return run(suite_path, render_cases=render_cases, **kwargs)


def check_suite(
    suite_path: str | Path,
    *,
    only: list[str] | None = None,
    failure_dir: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
) -> list[Any]:
    """:func:`refnpr.golden.check_suite` with the cases rendered on a Dask cluster (``workers``,
    ``scheduler``, ``client``: as for :func:`render_sequence`); the comparison runs on the client,
    so results (in suite order), messages and failure images are the serial check's."""
    where = (workers, scheduler, client)
    return _golden_on_cluster(
        _golden.check_suite, suite_path, where, True, only=only, failure_dir=failure_dir
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
    """:func:`refnpr.golden.update_suite` with the cases rendered on a Dask cluster: the same
    golden files, written by the client as each case arrives (``log`` lines in completion order,
    the returned paths in suite order); a case that fails to render raises, as serially."""
    where = (workers, scheduler, client)
    return _golden_on_cluster(_golden.update_suite, suite_path, where, False, only=only, log=log)
