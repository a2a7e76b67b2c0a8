"""Jobs, and the two local backends: this process and a pool of worker processes."""

from __future__ import annotations

import abc
import collections
import concurrent.futures
import hashlib
import itertools
import json
import multiprocessing
import os
import select
import threading
import time
from collections.abc import Callable, Generator, Iterable
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Generic, Protocol, TypeVar

from posegen.extras import Extra, require

StateT = TypeVar("StateT")
ItemT = TypeVar("ItemT")
ResultT = TypeVar("ResultT")
ResultT_co = TypeVar("ResultT_co", covariant=True)

WINDOW_PER_SLOT = 2  # items in flight per worker slot: keeps every worker busy, memory bounded


@dataclass(frozen=True)
class Job(Generic[StateT, ItemT, ResultT]):
    """Independent items that share one expensive state per worker.

    ``setup`` and ``run`` must be picklable (module-level functions, or
    ``functools.partial`` of them) and deterministic: the result of an item may depend on
    nothing but the item and ``name``'s state, never on what the worker ran before.
    """

    name: str  # identity of the state: a hash of everything ``setup`` depends on
    setup: Callable[[], StateT]  # builds the per-worker state, once per worker
    run: Callable[[StateT, ItemT], ResultT]  # one item's result


def job_name(kind: str, *parts: Any) -> str:
    """A job's name: its kind and a hash of what its state depends on (JSON-able parts)."""
    from posegen import __version__

    text = json.dumps([kind, __version__, *parts], sort_keys=True)
    return f"{kind}-{hashlib.sha256(text.encode()).hexdigest()[:16]}"


class Pending(Protocol[ResultT_co]):
    """A submitted task (a ``concurrent.futures`` or a Dask future)."""

    def result(self) -> ResultT_co:
        """Wait for the task; its result, or its exception raised here."""

    def cancel(self) -> Any:
        """Cancel the task if it has not run."""


def in_order(
    submit: Callable[[ItemT], Pending[ResultT]], items: Iterable[ItemT], window: int
) -> Generator[ResultT, None, None]:
    """Submit items up to ``window`` ahead of the one consumed; yield results in item order.

    Closing the generator cancels what is still pending.
    """
    pending: collections.deque[Pending[ResultT]] = collections.deque()
    try:
        for item in items:
            pending.append(submit(item))
            if len(pending) >= window:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
    finally:
        for task in pending:
            task.cancel()


class Backend(abc.ABC):
    """Runs jobs; results come back in item order."""

    @property
    @abc.abstractmethod
    def slots(self) -> int:
        """How many items run at once."""

    @abc.abstractmethod
    def map(
        self, job: Job[StateT, ItemT, ResultT], items: Iterable[ItemT], window: int | None = None
    ) -> Generator[ResultT, None, None]:
        """Run ``job`` on ``items`` lazily, a bounded window ahead; results in item order.

        ``items`` may be endless: closing the iterator cancels what is still pending.
        ``window`` (default: two items per worker slot) is how many items may be in
        flight; a finite batch of items of very unequal cost runs faster with all of
        them in flight (``len(items)``), as no worker then waits for the slowest.
        """

    def close(self) -> None:  # noqa: B027  (most backends hold nothing to release)
        """Release the backend's resources (default: none)."""

    def __enter__(self) -> Backend:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, value: BaseException | None, traceback: TracebackType | None
    ) -> None:
        self.close()


_STATES: dict[str, Any] = {}  # per worker process: each job's state, built by the pool's initializer


def _end_with(pid: int) -> None:
    """End this worker process when process ``pid``, the run that started it, ends (``kill -9`` too).

    Without it, the workers of a killed run (and their forkserver) would wait forever for
    work that never comes.
    """
    try:
        handle: int | None = os.pidfd_open(pid)  # readable once ``pid`` has ended
    except (AttributeError, OSError):  # not Linux 5.3+: poll instead
        handle = None

    def watch() -> None:
        if handle is not None:
            select.select([handle], [], [])
        else:
            while True:
                time.sleep(1.0)
                try:
                    os.kill(pid, 0)
                except ProcessLookupError:
                    break
        os._exit(1)

    threading.Thread(target=watch, name="posegen-end-with-run", daemon=True).start()


def _init_process(job: Job[Any, Any, Any], run_pid: int | None = None) -> None:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    if run_pid is not None:
        _end_with(run_pid)
    _STATES[job.name] = job.setup()


def _run_in_process(name: str, run: Callable[[Any, Any], Any], item: Any) -> Any:
    return run(_STATES[name], item)


class ProcessBackend(Backend):
    """``workers`` local processes (forkserver); with one worker, or one item, all runs in this process.

    Used as a context manager (``with``), it keeps each job's worker processes, and its
    in-process state, from one :meth:`map` to the next until it is closed, so a stage
    that maps a job several times (a route's stops, then its transfers, then its
    repairs) loads the robot once per worker. Otherwise each map starts and stops its own.
    """

    def __init__(self, workers: int) -> None:
        self.workers = max(1, workers)
        self._keep = False  # inside ``with``: keep processes and states between maps
        self._executors: dict[str, concurrent.futures.ProcessPoolExecutor] = {}
        self._states: dict[str, Any] = {}

    @property
    def slots(self) -> int:
        """Number of worker processes."""
        return self.workers

    def __enter__(self) -> ProcessBackend:
        self._keep = True
        return self

    def map(
        self, job: Job[StateT, ItemT, ResultT], items: Iterable[ItemT], window: int | None = None
    ) -> Generator[ResultT, None, None]:
        """Run ``job`` on ``items``; see :meth:`Backend.map`."""
        iterator = iter(items)
        head = list(itertools.islice(iterator, 2))
        if self.workers == 1 or (len(head) < 2 and job.name not in self._executors):  # not worth starting processes
            state = self._states[job.name] if job.name in self._states else job.setup()
            if self._keep:
                self._states[job.name] = state
            for item in itertools.chain(head, iterator):
                yield job.run(state, item)
            return
        items = itertools.chain(head, iterator)
        executor = self._executors.get(job.name)
        if executor is None:
            context = multiprocessing.get_context("forkserver")
            executor = concurrent.futures.ProcessPoolExecutor(
                max_workers=self.workers, mp_context=context, initializer=_init_process, initargs=(job, os.getpid())
            )
        try:
            yield from in_order(
                lambda item: executor.submit(_run_in_process, job.name, job.run, item),
                items,
                max(window or 0, WINDOW_PER_SLOT * self.workers),
            )
        finally:
            if self._keep:
                self._executors[job.name] = executor
            else:
                executor.shutdown(wait=True, cancel_futures=True)

    def close(self) -> None:
        """Stop the kept worker processes and drop the kept states."""
        for executor in self._executors.values():
            executor.shutdown(wait=True, cancel_futures=True)
        self._executors.clear()
        self._states.clear()
        self._keep = False


def open_backend(workers: int = 1, scheduler: str | None = None) -> Backend:
    """The backend a command asked for.

    Args:
        workers: Local worker processes (ignored with ``scheduler``).
        scheduler: Address of a Dask scheduler (``tcp://host:8786``); None: local processes.

    Raises:
        BackendError: The scheduler cannot be reached, has no worker, or a worker runs
            another posegen version.
        ExtraError: ``scheduler`` is given and Dask is not installed (``posegen[dask]``).

    """
    if scheduler is None:
        return ProcessBackend(workers)
    require(Extra.DASK, "scheduler (a Dask cluster)")
    from posegen.parallel.cluster import DaskBackend

    return DaskBackend(scheduler)
