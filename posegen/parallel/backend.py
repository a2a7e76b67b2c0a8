"""Jobs, and the two local backends: this process and a pool of worker processes."""

from __future__ import annotations

import abc
import ast
import collections
import concurrent.futures
import concurrent.futures.process
import hashlib
import itertools
import json
import logging
import multiprocessing
import os
import select
import sys
import threading
import time
from collections.abc import Callable, Generator, Iterable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType, TracebackType
from typing import Any, Generic, Protocol, TypeVar

from posegen.errors import BackendError, reason

LOG = logging.getLogger(__name__)

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


def no_state() -> None:
    """The per-worker state of a job whose items carry everything its runs need: none.

    Example:
        >>> job = Job(job_name("plots"), no_state, draw_one)  # draw_one(state, item): module-level

    """
    return None


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


@dataclass(frozen=True)
class _SetupFailed:
    """A worker's ``setup`` raised: kept as its state, reported with each item it is given."""

    reason: str  # the exception's type and first line


def _init_process(job: Job[Any, Any, Any], run_pid: int | None = None) -> None:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    if run_pid is not None:
        _end_with(run_pid)
    try:
        _STATES[job.name] = job.setup()
    except Exception as exc:  # raising here would kill the worker: the run would see only a broken pool
        _STATES[job.name] = _SetupFailed(reason(exc))


def _run_in_process(name: str, run: Callable[[Any, Any], Any], item: Any) -> Any:
    state = _STATES[name]
    if isinstance(state, _SetupFailed):
        raise BackendError(f"workers: a worker process could not set up its work ({state.reason})")
    return run(state, item)


GUARD = 'if __name__ == "__main__":'


def _is_guard(node: ast.stmt) -> bool:
    """Whether ``node`` is ``if __name__ == "__main__":`` (either operand order)."""
    if not isinstance(node, ast.If) or not isinstance(node.test, ast.Compare) or len(node.test.ops) != 1:
        return False
    operands = [node.test.left, *node.test.comparators]
    names = [o.id for o in operands if isinstance(o, ast.Name)]
    texts = [o.value for o in operands if isinstance(o, ast.Constant)]
    return isinstance(node.test.ops[0], ast.Eq) and names == ["__name__"] and texts == ["__main__"]


def _unguarded_script_line(frame: FrameType | None) -> tuple[str, int] | None:
    """The script and line running this call outside a ``__main__`` guard, if a script is.

    Worker processes (forkserver, as spawn) import the main script again as
    ``__mp_main__``: its top-level code outside the guard runs again there, and when it
    starts workers itself they die (``BrokenProcessPool``). ``python -m pkg``, the
    ``posegen`` command, ``python -c`` and notebooks are never re-run this way.
    """
    main = sys.modules.get("__main__")
    spec_name = getattr(getattr(main, "__spec__", None), "name", None) or ""
    if main is None or spec_name == "__main__" or spec_name.endswith(".__main__"):
        return None
    while frame is not None and not (frame.f_globals is vars(main) and frame.f_code.co_name == "<module>"):
        frame = frame.f_back
    if frame is None or not Path(frame.f_code.co_filename).is_file():
        return None
    path, line = frame.f_code.co_filename, frame.f_lineno
    try:
        body = ast.parse(Path(path).read_bytes()).body
    except (OSError, SyntaxError, ValueError):
        return None
    guarded = any(_is_guard(n) and n.lineno <= line <= (n.end_lineno or n.lineno) for n in body)
    return None if guarded else (path, line)


def check_script_guard(workers: int) -> None:
    """Refuse to start worker processes from a script they would run again.

    Raises:
        BackendError: ``workers`` > 1 asked from a script's top-level code outside
            ``if __name__ == "__main__":`` (the message says what to add).

    """
    found = _unguarded_script_line(sys._getframe(1)) if workers > 1 else None
    if found:
        path, line = found
        raise BackendError(
            f"workers: {workers} worker processes would run {path} again (line {line} is outside "
            f"'{GUARD}'): put the script's code under '{GUARD}', or use workers=1"
        )


def start_forkserver(modules: tuple[str, ...]) -> None:
    """Start the forkserver now (if it is not running), importing ``modules`` there in the background.

    Worker processes forked from it later start with these modules imported. The
    forkserver's default preload (the main module) is kept.
    """
    from multiprocessing import forkserver

    multiprocessing.get_context("forkserver").set_forkserver_preload(["__main__", *modules])
    forkserver.ensure_running()


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system says, else the machine's).

    Example:
        >>> usable_cores() >= 1
        True

    """
    affinity = getattr(os, "sched_getaffinity", None)
    return max(1, len(affinity(0)) if affinity is not None else (os.cpu_count() or 1))


class ProcessBackend(Backend):
    """``workers`` local processes (forkserver); with one worker, or one item, all runs in this process.

    Used as a context manager (``with``), it keeps each job's worker processes, and its
    in-process state, from one :meth:`map` to the next until it is closed, so a stage
    that maps a job several times (a route's stops, then its transfers, then its
    repairs) loads the robot once per worker. Otherwise each map starts and stops its own.
    Entered with ``preload`` modules (and more than one worker), it starts the process
    that forks the workers at once, importing them while the command reads its inputs:
    the workers, forked from it later, start with them imported (a second off a
    calibration's wall time). More workers than :func:`usable_cores` run as that many (a warning says so).
    """

    def __init__(self, workers: int, preload: tuple[str, ...] = ()) -> None:
        cores = usable_cores()
        if workers > cores:  # more processes than cores only add start-up and memory (each imports the stack)
            LOG.warning("workers: %d asked, this machine has %d usable cores: running %d", workers, cores, cores)
        self.workers = max(1, min(workers, cores))
        self.preload = preload
        self._keep = False  # inside ``with``: keep processes and states between maps
        self._executors: dict[str, concurrent.futures.ProcessPoolExecutor] = {}
        self._states: dict[str, Any] = {}

    @property
    def slots(self) -> int:
        """Number of worker processes."""
        return self.workers

    def __enter__(self) -> ProcessBackend:
        self._keep = True
        if self.workers > 1 and self.preload:
            start_forkserver(self.preload)
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
        broken = False
        executor = self._executors.get(job.name)
        if executor is None:
            check_script_guard(self.workers)
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
        except concurrent.futures.process.BrokenProcessPool as exc:
            broken = True
            raise BackendError(
                f"workers: a worker process ended abruptly (killed, out of memory, or a script without '{GUARD}' "
                "re-run in it); rerun with workers=1 to see the cause"
            ) from exc
        finally:
            if self._keep and not broken:
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
