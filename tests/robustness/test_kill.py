"""Faults of whole processes: ``kill -9`` at a random moment, and two runs on one output.

A killed command leaves its output as it was (absent here) or whole, never half
written; the same command run again takes over the dead run's lock (and says so) and
writes the bytes of an uninterrupted run. Two runs started together on one output: one
writes it, the other fails at once naming the first's pid.

The killed runs, and the first of two runs on one output, are real processes
(``python -m posegen.cli``); the uninterrupted runs, the reruns and the second run go
through ``posegen.cli.main`` in this process where that gives the same bytes (``route``
seeds OMPL once per process, so its runs are processes too).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from posegen.cli import main
from posegen.io import write_yaml
from tests.conftest import CONFIG, EXAMPLE_POOL

RNG = np.random.default_rng(14)  # the random moments, the same in every run of the suite
TAG = "POSEGEN_TEST_RUN"  # marks the processes a test started, and their children


def command(argv: list[str], tag: str) -> subprocess.Popen[bytes]:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", TAG: tag}
    return subprocess.Popen(
        [sys.executable, "-m", "posegen.cli", *argv, "-q"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        cwd=Path(__file__).resolve().parents[2],
    )


def tagged_processes(tag: str) -> list[int]:
    """Processes still running with ``tag`` in their environment (a killed run's workers)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            environ = (entry / "environ").read_bytes()
            state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if f"{TAG}={tag}".encode() in environ.split(b"\0") and state != "Z":
            found.append(int(entry.name))
    return found


def kill_at_random(process: subprocess.Popen[bytes], started: Callable[[], bool], window_s: float) -> None:
    """Wait until the work has ``started``, then ``kill -9`` the process at a random moment of ``window_s``."""
    deadline = time.monotonic() + 120
    while not started() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(float(RNG.uniform(0.0, window_s)))
    if process.poll() is None:
        process.send_signal(signal.SIGKILL)
    process.wait(timeout=60)


def files(folder: Path) -> dict[str, bytes]:
    """The files under ``folder`` by relative path; the folder's own path in them is written ``<out>``."""
    here = str(folder).encode()
    return {
        str(p.relative_to(folder)): p.read_bytes().replace(here, b"<out>")
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def run_here(argv: list[str], capsys) -> str:
    code = main([*argv, "-q"])
    err = capsys.readouterr().err
    assert code == 0, err
    return err


@pytest.fixture(scope="module")
def small_chunks(tmp_path_factory) -> Path:
    """The TALOS config with chunks of 4 samples: a tiny pool spans several checkpointed chunks."""
    data = yaml.safe_load(CONFIG.read_text())
    data["sampling"]["chunk_size"] = 4
    path = tmp_path_factory.mktemp("config") / "talos_table.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_killed_pool_resumes_to_the_same_bytes(small_chunks, tmp_path, capsys):
    argv = ["pool", "--n", "8", "--seed", "3", "--config", str(small_chunks)]
    reference = tmp_path / "reference"
    run_here([*argv, "--workers", "1", "-o", str(reference / "pool.yaml")], capsys)
    killed = tmp_path / "killed"
    output = killed / "pool.yaml"
    checkpoint = killed / "pool.yaml.partial.jsonl"
    tag = uuid.uuid4().hex
    process = command([*argv, "--workers", "2", "-o", str(output)], tag)
    kill_at_random(process, checkpoint.exists, window_s=2.0)
    assert process.returncode in (-signal.SIGKILL, 0), process.stderr.read() if process.stderr else ""
    if output.exists():  # the kill came after the end: the files are whole
        assert files(killed) == files(reference)
    deadline = time.monotonic() + 10
    while tagged_processes(tag) and time.monotonic() < deadline:  # its workers end with it
        time.sleep(0.2)
    assert tagged_processes(tag) == []
    left_locked = (killed / "pool.yaml.lock").exists()  # not when the kill came after the release, at exit
    err = run_here([*argv, "--workers", "2", "-o", str(output)], capsys)
    assert files(killed) == files(reference)  # the pool and its sidecar; no checkpoint, lock or temporary left
    if left_locked:
        assert f"taking over the lock of {output} left by posegen pid {process.pid}" in err


def test_two_runs_on_one_output(small_chunks, tmp_path, capsys):
    argv = ["pool", "--n", "8", "--seed", "4", "--workers", "1", "--config", str(small_chunks)]
    reference, both = tmp_path / "reference", tmp_path / "both"
    run_here([*argv, "-o", str(reference / "pool.yaml")], capsys)
    output = both / "pool.yaml"
    first = command([*argv, "-o", str(output)], uuid.uuid4().hex)
    lock = both / "pool.yaml.lock"
    deadline = time.monotonic() + 120
    while not (lock.exists() and lock.read_text()) and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert first.poll() is None, "the first run ended before the second could start"
    assert main([*argv, "-o", str(output), "-q"]) == 2  # the second, while the first writes
    err = capsys.readouterr().err
    assert err == f"posegen: error: {output} is being written by another posegen (pid {first.pid})\n"
    assert first.wait(timeout=300) == 0, first.stderr.read() if first.stderr else ""
    assert files(both) == files(reference)


@pytest.fixture(scope="module")
def plans(tmp_path_factory, route_file) -> dict[str, Path]:
    """Small inputs of the stages after ``pool``: two postures, and 30 simulated contacts."""
    folder = tmp_path_factory.mktemp("plans")
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][4:5]
    write_yaml(folder / "one.yaml", data)
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][:16]
    write_yaml(folder / "sixteen.yaml", data)
    assert main(["simulate", str(folder / "sixteen.yaml"), "--config", str(CONFIG), "-o", str(folder / "m.yaml")]) == 0
    return {"pool": EXAMPLE_POOL, "one": folder / "one.yaml", "measurements": folder / "m.yaml", "route": route_file}


STAGES = {  # argv (output last), the output's name, how long the work lasts (s), same bytes in this process?
    "select": (["select", "{pool}", "--k", "40", "-o"], "selected.yaml", 2.0, True),
    "select --given": (["select", "{pool}", "--given", "{measurements}", "--k", "3", "-o"], "next.yaml", 1.0, True),
    "simulate": (["simulate", "{one}", "--config", str(CONFIG), "-o"], "m.yaml", 0.5, True),
    "calibrate": (
        [
            "calibrate",
            "{measurements}",
            "--candidates",
            "offsets",
            "--prior-scale",
            "5",
            "--fold-seeds",
            "1",
            "--config",
            str(CONFIG),
            "-o",
        ],
        "cal",
        2.0,
        True,
    ),
    "route": (["route", "{one}", "-o"], "route.yaml", 2.0, False),
    "simulate --bag": (["simulate", "{route}", "--rate", "100", "--bag"], "session", 2.0, True),
}


@pytest.mark.parametrize("stage", sorted(STAGES))
def test_killed_stage_leaves_no_partial_output_and_reruns_to_the_same_bytes(stage, plans, tmp_path, capsys):
    template, name, work_s, in_process = STAGES[stage]
    argv = [a.format(**plans) for a in template]
    reference = tmp_path / "reference"
    if in_process:
        run_here([*argv, str(reference / name)], capsys)
    else:
        process = command([*argv, str(reference / name)], uuid.uuid4().hex)
        assert process.wait(timeout=600) == 0
    killed = tmp_path / "killed"
    process = command([*argv, str(killed / name)], uuid.uuid4().hex)
    kill_at_random(process, (killed / f"{name}.lock").exists, window_s=work_s)
    left = files(killed)
    if process.returncode == 0:
        assert left == files(reference)
    else:  # the dead run's lock, hidden temporary files, and what it had finished writing, whole
        for path, content in left.items():
            hidden = any(part.startswith(".") and ".tmp" in part for part in Path(path).parts)
            assert path == f"{name}.lock" or hidden or content == files(reference)[path], path
    if in_process:
        run_here([*argv, str(killed / name)], capsys)
    else:
        assert command([*argv, str(killed / name)], uuid.uuid4().hex).wait(timeout=600) == 0
    assert files(killed) == files(reference)  # the rerun took the lock over and removed the temporaries
