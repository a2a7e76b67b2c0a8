"""A kill at every rename boundary: each command, replacing an older output, stopped at each crash point in turn.

The command (a real process) kills itself (``SIGKILL``) at its Nth crash point
(:func:`posegen.io.atomic.crash_point`, ``POSEGEN_CRASH_AT=N``): every rename that puts a
file or a folder in place has one before and one after it. Each run starts from the
output of an older run (another seed) and must leave that old output or the whole new
one, read back as one (a header with the sidecar it names and its companions, a
simulation's truth or a route's CSV; a folder's files, a bag and its truth), plus only
what the next run removes (the lock, hidden temporaries, a sidecar or companion no
header names, the pool's checkpoint). The same command run again then writes
the bytes of an uninterrupted run.

The matrix takes minutes: ``make slow`` and ``make kill-matrix`` run it whole
(``POSEGEN_KILL_MATRIX=full``: at every crash point, between the files a folder is staged
from too), not ``make test`` (``tests/robustness/test_kill.py`` kills each stage there).
Without that variable it kills only where the output changes: just before the header or
the page lands, before the old sidecar or companion is removed, before a folder is
swapped in and before the old one is removed.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from posegen.cli import main
from posegen.io import companion_of, companions_of, sidecars_of, write_yaml
from posegen.io.atomic import CRASH_AT, CRASH_LOG, leftover_temporaries
from tests.conftest import CONFIG, EXAMPLE_POOL
from tests.robustness.test_kill import files

FULL = os.environ.get("POSEGEN_KILL_MATRIX") == "full"
pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]
COMPANIONS = (".truth.yaml", ".csv")  # files named by their header's bytes: a simulation's truth, a route's CSV


def run(argv: list[str], env: dict[str, str] | None = None) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(
        [sys.executable, "-m", "posegen.cli", *argv, "-q"],
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT), **(env or {})},
        capture_output=True,
        cwd=ROOT,
        timeout=600,
        check=False,
    )


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, route_file) -> dict[str, str]:
    """One posture to route, 16 simulated contacts to calibrate from, two sessions to measure, two routes, two plans."""
    folder = tmp_path_factory.mktemp("inputs")
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][4:5]
    write_yaml(folder / "one.yaml", data)
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][:16]
    write_yaml(folder / "sixteen.yaml", data)
    assert main(["simulate", str(folder / "sixteen.yaml"), "--config", str(CONFIG), "-o", str(folder / "m.yaml")]) == 0
    for seed in (1, 2):
        bag = folder / f"bag{seed}"
        assert main(["simulate", str(route_file), "--rate", "100", "--seed", str(seed), "--bag", str(bag), "-q"]) == 0
    shutil.copy(folder / "one.yaml", folder / "plan1.yaml")
    shutil.copy(folder / "sixteen.yaml", folder / "plan2.yaml")
    assert main(["route", str(folder / "one.yaml"), "-q", "-o", str(folder / "route1.yaml")]) == 0  # two routes
    shutil.copy(route_file, folder / "route2.yaml")  # its header names its sidecar, copied beside it
    for sidecar in sidecars_of(route_file):
        shutil.copy(sidecar, folder / sidecar.name)
    paths = {"one": folder / "one.yaml", "sixteen": folder / "sixteen.yaml", "m": folder / "m.yaml"}
    return {**{k: str(v) for k, v in paths.items()}, "route": str(route_file), "dir": str(folder)}


CALIBRATE = ["calibrate", "{m}", "--candidates", "offsets", "--prior-scale", "5", "--fold-seeds", "1"]
STAGES = {  # argv of a run with seed {seed} (output last), output name, what the output is
    "pool": (["pool", "--n", "8", "--workers", "1", "--seed", "{seed}", "--config", str(CONFIG), "-o"], "pool.yaml"),
    "route --csv": (["route", "{one}", "--seed", "{seed}", "--csv", "-o"], "route.yaml"),  # a pair and its CSV
    "simulate": (["simulate", "{sixteen}", "--seed", "{seed}", "--config", str(CONFIG), "-o"], "m.yaml"),
    "simulate --bag": (["simulate", "{route}", "--rate", "100", "--seed", "{seed}", "--bag"], "session"),
    "measure": (["measure", "{dir}/bag{seed}", "--route", "{route}", "--session", "sim", "-o"], "measured.yaml"),
    "calibrate": ([*CALIBRATE, "--config", str(CONFIG), "--seed", "{seed}", "-o"], "cal"),
    "export": (["export", "{dir}/route{seed}.yaml", "--bag"], "bag"),
    "view --html": (["view", "{dir}/plan{seed}.yaml", "--html"], "page.html"),
}


IN_PROCESS = {
    "pool",
    "simulate",
    "simulate --bag",
    "measure",
    "calibrate",
    "export",
    "view --html",
}  # same bytes in this process (route seeds OMPL once)


def run_to_the_end(stage: str, argv: list[str]) -> None:
    """An uninterrupted run: in this process where that gives the same bytes (faster), else a process."""
    if stage in IN_PROCESS:
        assert main([*argv, "-q"]) == 0
    else:
        done = run(argv)
        assert done.returncode == 0, done.stderr.decode()


def artefact(folder: Path, name: str, written_in: tuple[Path, ...] = ()) -> dict[str, bytes]:
    """The output as its reader sees it: a header and the sidecar it names, a folder's files, or a file.

    The output's path, and the paths of the folders ``written_in`` (where a copied output
    was first written: a report names its folder), read ``<out>``.
    """
    path = folder / name
    if path.is_dir():
        found = {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}
    elif not path.exists():
        return {}
    else:
        found = {name: path.read_bytes()}
        if path.suffix == ".yaml" and "arrays" in (header := yaml.safe_load(path.read_text()) or {}):
            sidecar = folder / header["arrays"]["file"]
            found[sidecar.name] = sidecar.read_bytes()
        for suffix in COMPANIONS:  # named by the header's bytes: the header on disk finds its own
            if (companion := companion_of(path, suffix)) is not None:
                found[companion.name] = companion.read_bytes()
    for where in (folder, *written_in):
        found = {k: v.replace(str(where / name).encode(), b"<out>") for k, v in found.items()}
    return found


def allowed_leftovers(folder: Path, name: str) -> set[Path]:
    """What a killed run may leave beside its output, all removed by the next run."""
    path = folder / name
    return {
        folder / f"{name}.lock",
        folder / f"{name}.partial.jsonl",  # the pool's checkpoint, resumed from
        *leftover_temporaries(path),
        *sidecars_of(path),
        *(p for suffix in COMPANIONS for p in companions_of(path, suffix)),
    }


def crash_points(argv: list[str], old: Path, work: Path, name: str) -> list[tuple[int, str]]:
    """The crash points of the run (number, label): those at the output's own renames, or all with FULL."""
    shutil.copytree(old, work)
    log = work.parent / f"{work.name}.points"
    done = run([*argv, str(work / name)], {CRASH_LOG: str(log)})
    assert done.returncode == 0, done.stderr.decode()
    points = [(int(n), label) for n, label in (line.split(" ", 1) for line in log.read_text().splitlines())]
    landing = {f"before {name}", f"before {name}/", f"after {name}/ (old not yet removed)"}  # the state changes

    def own(label: str) -> bool:
        return label in landing or label.startswith(f"before removing {name}.")

    return points if FULL else [(n, label) for n, label in points if own(label)]


@pytest.mark.parametrize("stage", sorted(STAGES))
def test_a_kill_at_every_rename_boundary_leaves_the_old_or_the_new_output(stage, inputs, tmp_path):
    template, name = STAGES[stage]
    argv = {seed: [a.format(seed=seed, **inputs) for a in template] for seed in (1, 2)}
    old, new = tmp_path / "old", tmp_path / "new"
    for seed, folder in ((1, old), (2, new)):
        folder.mkdir()
        run_to_the_end(stage, [*argv[seed], str(folder / name)])
    assert artefact(old, name) != artefact(new, name)
    points = crash_points(argv[2], old, tmp_path / "logged", name)
    assert files(tmp_path / "logged") == files(new)  # the crash points alone change nothing
    assert points, "no crash point at the output's renames"
    for n, label in points:
        killed = tmp_path / f"killed{n}"
        shutil.copytree(old, killed)
        done = run([*argv[2], str(killed / name)], {CRASH_AT: str(n)})
        assert done.returncode == -signal.SIGKILL, (label, done.stderr.decode())
        state = artefact(killed, name, (old,))
        assert state in (artefact(old, name), artefact(new, name)), f"killed {label}: a mix of two runs"
        extra = {p for p in killed.iterdir() if p.name not in state and p.name != name}  # beside the output
        assert extra <= allowed_leftovers(killed, name), (label, extra)
        run_to_the_end(stage, [*argv[2], str(killed / name)])
        assert files(killed) == files(new), f"rerun after a kill {label}"
