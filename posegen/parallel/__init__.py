"""Where independent work runs: this process, a local process pool, or a Dask cluster.

Every parallel stage has the same shape: many independent items (chunks of pool samples,
postures to re-check, route segments), each a pure function of the item and of an
expensive per-worker state (the robot model, solvers, collision geometry). A :class:`Job`
says that; a :class:`Backend` runs it and hands the results back in item order, so an
output never depends on the backend or the number of workers.
"""

from posegen.parallel.backend import Backend, Job, ProcessBackend, job_name, open_backend

__all__ = ["Backend", "Job", "ProcessBackend", "job_name", "open_backend"]
