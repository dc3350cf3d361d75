"""Executors that run cases: local worker processes, in-process, or a Dask cluster.

Any ``concurrent.futures.Executor`` works with the runner; this module builds the usual
ones from a command-line style specification.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Any, Callable

from drake_mh.errors import InvalidArgument

logger = logging.getLogger(__name__)

#: how long to wait for a Dask scheduler to answer
DASK_CONNECT_TIMEOUT = "10s"


class SerialExecutor(Executor):
    """Runs each submitted call immediately in the calling process (``--workers 0``)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:  # noqa: D102
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - delivered through the future
            future.set_exception(exc)
        return future


def default_workers() -> int:
    """Number of local worker processes when none is given: the usable CPU count."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS / Windows
        return max(1, os.cpu_count() or 1)


def parse_executor(spec: str | None) -> tuple[str, str | None]:
    """Parses an executor specification.

    Args:
        spec: ``None``/``"local"`` (worker processes), ``"serial"`` (in-process) or
            ``"dask://HOST:PORT"`` / ``"tcp://HOST:PORT"`` (a Dask distributed scheduler).

    Returns:
        ``(kind, address)`` with kind in ``local``, ``serial``, ``dask``.

    Raises:
        InvalidArgument: an unknown specification.
    """
    if spec is None or spec in ("", "local", "process", "processes"):
        return "local", None
    if spec in ("serial", "inline"):
        return "serial", None
    for prefix in ("dask://", "tcp://"):
        if spec.startswith(prefix):
            address = spec[len(prefix) :]
            if not address or ":" not in address:
                break
            return "dask", "tcp://" + address
    raise InvalidArgument(
        f"unknown executor {spec!r}; use 'local' (worker processes, --workers N), 'serial', "
        "or 'dask://HOST:PORT' for a running Dask scheduler"
    )


#: thread-count variables of the BLAS/OpenMP libraries numpy and scipy may load
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@contextmanager
def _one_blas_thread_per_worker():
    """Worker processes started meanwhile use one BLAS thread each (variables a user set are kept).

    Measured: with two workers and other jobs on 2 cores, OpenBLAS's threaded ``eigh`` of a
    30 x 30 matrix took 4.4 ms instead of ~0.2 ms (threads spinning against each other);
    pycma's CMA-ES at D = 30 ran 7x slower (30.4 s vs 4.2 s for 60,000 evaluations).
    """
    saved = {name: os.environ.get(name) for name in BLAS_THREAD_VARIABLES}
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def exit_with_parent(parent_pid: int, interval: float = 0.5) -> None:
    """Worker initializer: the worker exits as soon as its parent process is gone.

    After ``kill -9`` of ``drake-mh study`` nothing tells the pool's workers to stop (they
    would go on running and holding ports); a daemon thread polls the parent's pid and ends
    the worker with ``os._exit`` once it was re-parented.

    Args:
        parent_pid: ``os.getpid()`` of the process that made the pool.
        interval: [s] between polls.
    """
    import threading
    import time

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(interval)
        os._exit(3)

    threading.Thread(target=watch, name="drake_mh-exit-with-parent", daemon=True).start()


@contextmanager
def open_executor(spec: str | None = None, workers: int | None = None) -> Iterator[tuple[Executor, int]]:
    """Opens an executor and closes it afterwards.

    Args:
        spec: see :func:`parse_executor`.
        workers: local worker processes (``0`` = in-process); ``None`` = CPU count.

    Yields:
        ``(executor, parallelism)`` where parallelism is how many cases run at once.

    Raises:
        InvalidArgument: bad specification or worker count; Dask not installed or the
            scheduler unreachable.
    """
    kind, address = parse_executor(spec)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 0):
        raise InvalidArgument(f"--workers must be an integer >= 0 (0 = run in this process), got {workers!r}")
    if kind == "serial" or (kind == "local" and workers == 0):
        yield SerialExecutor(), 1
        return
    if kind == "local":
        count = workers if workers else default_workers()
        # spawn: workers start clean (no forked Drake/threads state), same on every OS
        context = multiprocessing.get_context("spawn")
        with _one_blas_thread_per_worker():
            executor = ProcessPoolExecutor(max_workers=count, mp_context=context,
                                           initializer=exit_with_parent, initargs=(os.getpid(),))
            try:
                yield executor, count
            finally:
                executor.shutdown(wait=True, cancel_futures=True)
        return
    try:
        from distributed import Client
    except ImportError as exc:
        raise InvalidArgument(
            "the Dask executor needs dask and distributed: pip install 'drake_mh[dask]'"
        ) from exc
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as exc:
        raise InvalidArgument(
            f"cannot reach the Dask scheduler at {address}: {exc}; start one with "
            "`dask scheduler` and `dask worker ADDRESS`, or check the address"
        ) from exc
    try:
        threads = sum(client.nthreads().values()) or 1
        logger.info("Dask scheduler %s: %d worker threads", address, threads)
        executor = client.get_executor(pure=False)
        yield executor, threads
    finally:
        client.close()
