"""The Dask backend: jobs on a ``dask.distributed`` cluster, several machines if need be.

Start a scheduler on one machine and workers on every machine (one thread per worker
process: placo and coal states are per thread anyway, processes use the cores)::

    dask scheduler --port 8786
    dask worker tcp://SCHEDULER:8786 --nworkers 2 --nthreads 1

then ``posegen pool --scheduler tcp://SCHEDULER:8786``. Every worker needs the same posegen
version as the client: the client refuses to start otherwise, and each task checks again
(a worker may join later).

Each task is keyed by the job and a token of its item: equal keys are equal work (the
result is a pure function of them), so the scheduler may merge or rerun them freely. A
worker killed mid-run loses nothing: its tasks run again elsewhere, with the same result.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Generator, Iterable
from typing import Any

from dask.base import tokenize
from distributed import Client, Future, get_worker
from distributed.comm.addressing import parse_address, parse_host_port
from distributed.diagnostics.plugin import WorkerPlugin

from posegen import __version__
from posegen.errors import BackendError
from posegen.parallel.backend import WINDOW_PER_SLOT, Backend, ItemT, Job, ResultT, StateT, in_order

LOG = logging.getLogger(__name__)
CONNECT_TIMEOUT_S = 10.0
WORKER_TIMEOUT_S = 30.0  # wait this long for a first worker to join
RETRIES = 3  # reruns of a task whose worker died or failed


def _worker_version() -> str:
    from posegen import __version__ as version

    return version


class JobState(WorkerPlugin):
    """Worker plugin: a job's state, built on first use, once per worker thread."""

    def __init__(self, job: Job[Any, Any, Any]) -> None:
        self.job = job
        self._local = threading.local()

    def __getstate__(self) -> dict[str, Any]:
        return {"job": self.job}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.job = state["job"]
        self._local = threading.local()

    def state(self) -> Any:
        """The job's state in the calling worker thread."""
        if not hasattr(self._local, "state"):
            self._local.state = self.job.setup()
        return self._local.state


def _run_task(plugin: str, version: str, run: Callable[[Any, Any], Any], item: Any) -> Any:
    worker = get_worker()
    if _worker_version() != version:
        raise BackendError(
            f"Dask worker {worker.address} runs posegen {_worker_version()}, the client {version}; "
            "install the same version on every worker"
        )
    state = worker.plugins[plugin]
    assert isinstance(state, JobState)
    return run(state.state(), item)


class DaskBackend(Backend):
    """Jobs on the Dask cluster whose scheduler is at ``address``."""

    def __init__(self, address: str) -> None:
        try:  # a malformed address, checked first: a Client that fails to parse it hangs at exit
            scheme, location = parse_address(address)
            if scheme in ("tcp", "tls"):
                parse_host_port(location)
        except ValueError as exc:
            raise BackendError(f"not a Dask scheduler address: {address!r} ({exc}); give tcp://HOST:PORT") from None
        try:
            self.client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise BackendError(f"cannot reach the Dask scheduler at {address}: {exc}") from exc
        try:
            self.client.wait_for_workers(1, timeout=WORKER_TIMEOUT_S)
        except TimeoutError as exc:
            self.client.close()
            raise BackendError(
                f"no Dask worker joined {address} within {WORKER_TIMEOUT_S:.0f} s; "
                f"start one with: dask worker {address}"
            ) from exc
        versions = self.client.run(_worker_version)
        others = {worker: v for worker, v in versions.items() if v != __version__}
        if others:
            self.client.close()
            listed = ", ".join(f"{worker} has {v}" for worker, v in sorted(others.items()))
            raise BackendError(f"Dask workers with another posegen version than this {__version__}: {listed}")

    @property
    def slots(self) -> int:
        """Worker threads of the cluster now."""
        return max(1, sum(self.client.nthreads().values()))

    def map(
        self, job: Job[StateT, ItemT, ResultT], items: Iterable[ItemT], window: int | None = None
    ) -> Generator[ResultT, None, None]:
        """Run ``job`` on ``items``; see :meth:`Backend.map`."""
        plugin = f"posegen-{job.name}"
        self.client.register_plugin(JobState(job), name=plugin)

        def submit(item: ItemT) -> Future:
            key = f"{plugin}-{tokenize(job.run, item)}"
            return self.client.submit(_run_task, plugin, __version__, job.run, item, key=key, retries=RETRIES)

        try:
            yield from in_order(submit, items, max(window or 0, WINDOW_PER_SLOT * self.slots))
        finally:
            try:
                self.client.unregister_worker_plugin(plugin)
            except OSError as exc:  # a worker lost meanwhile (its tasks ran again elsewhere): the results stand
                LOG.debug("unregistering %s: %s", plugin, exc)

    def close(self) -> None:
        """Disconnect from the scheduler (the cluster keeps running)."""
        self.client.close()
