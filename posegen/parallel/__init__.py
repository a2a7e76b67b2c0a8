"""Where independent work runs: this process, a local process pool, or a Dask cluster.

Every parallel stage has the same shape: many independent items (chunks of pool samples,
postures to re-check, route segments), each a pure function of the item and of an
expensive per-worker state (the robot model, solvers, collision geometry). A :class:`Job`
says that; a :class:`Backend` runs it and hands the results back in item order, so an
output never depends on the backend or the number of workers.

The backend modules import nothing from here: :func:`open_backend` (which picks one)
lives in this ``__init__``, above both, so ``backend`` and ``cluster`` form no circle.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from __future__ import annotations

from posegen.errors import ArgumentError
from posegen.extras import Extra, require
from posegen.parallel.backend import Backend, Job, ProcessBackend, job_name, no_state, usable_cores


def open_backend(workers: int = 1, scheduler: str | None = None, preload: tuple[str, ...] = ()) -> Backend:
    """The backend a command asked for.

    Args:
        workers: Local worker processes (ignored with ``scheduler``).
        scheduler: Address of a Dask scheduler (``tcp://host:8786``); None: local processes.
        preload: Modules the local workers will need, imported while the command still
            reads its inputs (:class:`ProcessBackend`).

    Raises:
        BackendError: The scheduler cannot be reached, has no worker, or a worker runs
            another posegen version.
        ExtraError: ``scheduler`` is given and Dask is not installed (``posegen[dask]``).

    """
    if scheduler is None:
        return ProcessBackend(workers, preload)
    require(Extra.DASK, "scheduler (a Dask cluster)")
    from posegen.parallel.cluster import DaskBackend

    return DaskBackend(scheduler)


def as_backend(workers: int | Backend) -> Backend:
    """The backend to run on: ``workers`` itself when it is one, else that many local processes.

    A backend made here is not entered: each of its maps starts and stops its own worker
    processes (enter it with ``with`` to keep them between maps). A backend given is
    returned as is, never closed here: its owner closes it.

    Raises:
        ArgumentError: ``workers`` is neither a backend nor a positive integer.

    """
    if isinstance(workers, Backend):
        return workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ArgumentError(f"workers must be a backend or an integer >= 1, got {workers!r}", parameter="workers")
    return ProcessBackend(workers)


__all__ = ["Backend", "Job", "ProcessBackend", "as_backend", "job_name", "no_state", "open_backend", "usable_cores"]
