"""Backends: results in item order, one state per worker; a Dask cluster gives the same pool and check."""

import dataclasses
import os
import signal

import numpy as np
import pytest

from posegen.errors import BackendError
from posegen.parallel import Job, ProcessBackend, as_backend, open_backend, usable_cores
from posegen.pool import generate_pool, verify_postures


def _setup():
    return {"pid": os.getpid(), "built": id(object())}


def _run(state, item):
    return item * item, state["pid"], state["built"]


def test_process_backend_keeps_item_order_and_one_state_per_worker():
    job = Job(name="squares", setup=_setup, run=_run)
    for workers in (1, 2):
        results = list(ProcessBackend(workers).map(job, range(40)))
        assert [r[0] for r in results] == [i * i for i in range(40)]
        states = {}
        for _, pid, built in results:
            states.setdefault(pid, set()).add(built)
        assert all(len(built) == 1 for built in states.values())  # set up once per process, not per item
        assert len(states) <= workers
    [(square, pid, _)] = list(ProcessBackend(2).map(job, [3]))
    assert (square, pid) == (9, os.getpid())  # one item: no processes started


def test_a_stage_runs_on_the_backend_it_is_given_or_on_that_many_local_processes():
    job = Job(name="squares", setup=_setup, run=_run)
    with ProcessBackend(1) as given:
        assert as_backend(given) is given
        [(square, _, _)] = list(as_backend(given).map(job, [2]))
        assert square == 4
        assert job.name in given._states  # the given backend keeps its state: as_backend did not close it
    made = as_backend(1)
    assert isinstance(made, ProcessBackend) and made.slots == 1
    opened = open_backend(usable_cores())
    assert isinstance(opened, ProcessBackend) and opened.slots == usable_cores()


def test_more_workers_than_cores_run_as_many_as_cores_and_say_so(caplog):
    cores = usable_cores()
    assert cores == len(os.sched_getaffinity(0))  # Linux: this process's affinity
    with caplog.at_level("WARNING", logger="posegen.parallel.backend"):
        assert ProcessBackend(cores + 998).slots == cores
    assert f"workers: {cores + 998} asked, this machine has {cores} usable cores: running {cores}" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING", logger="posegen.parallel.backend"):
        assert ProcessBackend(cores).slots == cores
    assert caplog.text == ""


def test_closing_the_results_early_stops_the_work():
    job = Job(name="squares", setup=_setup, run=_run)
    results = ProcessBackend(2).map(job, iter(range(10**9)))  # endless items
    assert [next(results)[0] for _ in range(3)] == [0, 1, 4]
    results.close()


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0"
    ) as local:
        yield local


@pytest.fixture(scope="module")
def small_chunks(config):
    """Chunks of 4 samples: the few postures of a test still spread over both workers."""
    return dataclasses.replace(config, sampling=dataclasses.replace(config.sampling, chunk_size=4))


@pytest.fixture(scope="module")
def reference(small_chunks):
    return generate_pool(small_chunks, n=6, seed=7, workers=1)


def test_dask_cluster_gives_the_same_pool_and_check(cluster, small_chunks, reference, scene):
    from posegen.parallel.cluster import DaskBackend

    with DaskBackend(cluster.scheduler_address) as backend:
        assert backend.slots == 2
        pool = generate_pool(small_chunks, n=6, seed=7, workers=backend)
        assert pool.to_dict() == reference.to_dict()
        assert verify_postures(scene, pool.postures, workers=backend) == verify_postures(scene, reference.postures)


def test_dask_cluster_gives_the_same_route(cluster, scene, example_pool):
    """Stops and transfers on the cluster: the same route, point for point and segment for segment."""
    from posegen.parallel.cluster import DaskBackend
    from posegen.route import plan_route, route_arrays_of

    postures = [example_pool.postures[i] for i in (3, 4)]
    local = plan_route(scene, postures, seed=0)
    with DaskBackend(cluster.scheduler_address) as backend:
        remote = plan_route(scene, postures, seed=0, workers=backend)
    pairs = zip(route_arrays_of(local).values(), route_arrays_of(remote).values(), strict=True)
    assert all(np.array_equal(a, b) for a, b in pairs)
    assert remote.segments == local.segments


def test_a_worker_killed_mid_run_changes_nothing(cluster, small_chunks, reference):
    from posegen.parallel.cluster import DaskBackend

    killed = []

    def kill_one_worker(progress):
        if progress.attempts and not killed:  # after the first chunk came back
            pids = backend.client.run(os.getpid)
            victim = sorted(pids.values())[0]
            os.kill(victim, signal.SIGKILL)
            killed.append(victim)

    with DaskBackend(cluster.scheduler_address) as backend:
        pool = generate_pool(small_chunks, n=6, seed=7, workers=backend, progress=kill_one_worker)
    assert killed
    assert pool.to_dict() == reference.to_dict()


def test_a_plugin_the_lost_worker_cannot_unregister_does_not_fail_a_finished_map(cluster, monkeypatch):
    """The scheduler's broadcast to a worker killed during the map fails at cleanup (seen under load): results stand."""
    from distributed.comm.core import CommClosedError

    from posegen.parallel.cluster import DaskBackend

    def closed(name):
        raise CommClosedError(f"in <TCP (closed) ConnectionPool.unregister_worker_plugin>: {name}: Stream is closed")

    job = Job(name="squares", setup=_setup, run=_run)
    with DaskBackend(cluster.scheduler_address) as backend:
        monkeypatch.setattr(backend.client, "unregister_worker_plugin", closed)
        results = list(backend.map(job, range(6)))
    assert [r[0] for r in results] == [i * i for i in range(6)]


def test_workers_of_another_version_are_refused(cluster, monkeypatch):
    from posegen.parallel import cluster as module

    monkeypatch.setattr(module, "__version__", "0.0.0-other")
    with pytest.raises(BackendError, match="another posegen version"):
        module.DaskBackend(cluster.scheduler_address)


def test_an_unreachable_scheduler_is_a_clear_error(monkeypatch):
    pytest.importorskip("distributed")
    from posegen.parallel import cluster as module

    monkeypatch.setattr(module, "CONNECT_TIMEOUT_S", 1.0)
    with pytest.raises(BackendError, match="cannot reach the Dask scheduler at tcp://127"):
        module.DaskBackend("tcp://127.0.0.1:9")


def test_inside_with_the_workers_and_their_states_last_from_one_map_to_the_next():
    job = Job(name="squares", setup=_setup, run=_run)
    for workers in (1, 2):
        with ProcessBackend(workers) as backend:
            first = list(backend.map(job, range(8)))
            again = list(backend.map(job, range(8)))
        assert [r[0] for r in again] == [i * i for i in range(8)]
        states = {(pid, built) for _, pid, built in first + again}  # a worker may sit out a map, never restart
        assert len({pid for pid, _ in states}) == len(states) <= workers


SCRIPT_JOB = """
import operator
from posegen.parallel import Job, ProcessBackend

def squares():
    job = Job(name="sums", setup=int, run=operator.add)  # builtins: picklable from any script
    return list(ProcessBackend(2).map(job, range(6)))
"""


def _run_script(tmp_path, body):
    import subprocess
    import sys
    from pathlib import Path

    script = tmp_path / "script.py"
    script.write_text(SCRIPT_JOB + body)
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root), "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120
    )


def test_an_unguarded_script_with_workers_gets_told_what_to_add(tmp_path):
    result = _run_script(tmp_path, "print('once')\nprint(squares())\n")
    assert result.returncode == 1 and result.stdout == "once\n"  # stopped before any worker re-ran the script
    assert "BrokenProcessPool" not in result.stderr
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("posegen.errors.BackendError: workers: 2 worker processes would run")
    assert 'if __name__ == "__main__":' in last and "line 9 is outside" in last


def test_code_above_the_guard_is_refused_and_code_under_it_runs(tmp_path):
    guarded = _run_script(tmp_path, "if __name__ == '__main__':\n    print(squares())\n")
    assert guarded.returncode == 0, guarded.stderr
    assert guarded.stdout == "[0, 1, 2, 3, 4, 5]\n"  # the script ran once: the workers did not re-run it
    above = _run_script(tmp_path, "print(squares())\nif __name__ == '__main__':\n    pass\n")
    assert above.returncode == 1 and "BackendError" in above.stderr and "line 8 is outside" in above.stderr


def _die(state, item):
    os._exit(3)


def test_a_worker_that_dies_is_a_backend_error_not_a_broken_pool():
    job = Job(name="dies", setup=_setup, run=_die)
    with pytest.raises(BackendError, match="ended abruptly"):
        list(ProcessBackend(2).map(job, range(4)))


def _setup_fails():
    raise RuntimeError("input stream error\nsecond line")


def test_a_worker_whose_setup_fails_says_why_and_is_no_broken_pool():
    job = Job(name="setup-fails", setup=_setup_fails, run=_run)
    with pytest.raises(BackendError, match=r"could not set up its work \(RuntimeError: input stream error\)$"):
        list(ProcessBackend(2).map(job, range(4)))
    with ProcessBackend(2) as backend:  # the pool stays usable: a job that sets up runs after it
        with pytest.raises(BackendError, match="could not set up"):
            list(backend.map(job, range(4)))
        assert [r[0] for r in backend.map(Job(name="squares", setup=_setup, run=_run), range(4))] == [0, 1, 4, 9]


def test_preloaded_modules_are_imported_before_a_worker_sets_up(tmp_path):
    """Entered with ``preload``, the backend's workers start with those modules imported (read while the run works)."""
    body = (
        "import functools, sys\n"
        "def seen(name, item):\n"
        "    return name in sys.modules\n"
        "if __name__ == '__main__':\n"
        "    job = Job(name='seen', setup=functools.partial(str, 'tabnanny'), run=seen)\n"
        "    for preload in ((), ('tabnanny',)):\n"
        "        with ProcessBackend(2, preload) as backend:\n"
        "            print(list(backend.map(job, range(4))))\n"
        "        import multiprocessing.forkserver as fs\n"
        "        fs._forkserver._stop()\n"  # the next backend starts its own forkserver
    )
    result = _run_script(tmp_path, body)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["[False, False, False, False]", "[True, True, True, True]"]


def test_a_preloaded_module_that_cannot_be_imported_is_skipped(tmp_path):
    """A preload names modules an extra may lack (the report's figures): the workers start and run without them."""
    (tmp_path / "lacks_an_extra.py").write_text("raise ImportError('needs an extra')\n")
    body = (
        "import functools, sys\n"
        "def seen(name, item):\n"
        "    return name in sys.modules, item * item\n"
        "if __name__ == '__main__':\n"
        "    job = Job(name='seen', setup=functools.partial(str, 'tabnanny'), run=seen)\n"
        "    with ProcessBackend(2, ('lacks_an_extra', 'tabnanny')) as backend:\n"
        "        print(list(backend.map(job, range(4))))\n"
    )
    result = _run_script(tmp_path, body)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["[(True, 0), (True, 1), (True, 4), (True, 9)]"]
