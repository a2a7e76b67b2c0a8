"""A session is a journal (issue 33): an ``add`` lands whole or is resumed by the same command; nothing half-done.

``session add`` (a real process) kills itself at a rename boundary
(``POSEGEN_CRASH_AT``): the session left must read back (the index and every file it
vouches for), a batch it says is assessed has its whole calibration folder, report
included, and the same command run again finishes the add as an uninterrupted one does.
``make test`` kills where the old code left a calibration without its report and where
the next batch's bag lands; ``make fuzz`` (``HYPOTHESIS_PROFILE=fuzz``) kills at three
boundaries drawn at random among all of them.

An ``add`` that fails on a hand-edited index writes nothing; a rehearsal while another
command holds the session names the lock.
"""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from posegen.cli import main
from posegen.errors import InputError, OutputError
from posegen.io import OutputKind, claim_output
from posegen.io.atomic import CRASH_AT, CRASH_LOG
from posegen.parallel import open_backend
from posegen.session import INDEX_FILE, REHEARSAL_BAG, BatchState, add_bag, open_session, read_index, rehearse_session
from tests.cli.test_cli import assert_one_line_error
from tests.session.conftest import ROBOT

ROOT = Path(__file__).resolve().parents[2]
FUZZ = os.environ.get("HYPOTHESIS_PROFILE") == "fuzz"
STAGED = ("before calibrated", "after calibrated", "before offsets", "after offsets", "before parameters")


def add(session: Path, bag: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(
        [sys.executable, "-m", "posegen.cli", "session", "add", str(session), str(bag), "-q"],
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT), **(env or {})},
        capture_output=True,
        cwd=ROOT,
        timeout=900,
        check=False,
    )


def files_of(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def uninterrupted(started, rehearsed, tmp_path_factory):
    """The add of batch 1's recording run whole, with the crash points it passes (numbered, labelled)."""
    session = tmp_path_factory.mktemp("whole") / "session"
    shutil.copytree(started, session)
    log = session.parent / "crash.log"
    done = add(session, rehearsed[0] / "batch_001" / REHEARSAL_BAG, {CRASH_LOG: str(log)})
    assert done.returncode == 0, done.stderr.decode()
    points = [line.split(" ", 1) for line in log.read_text().splitlines()]
    return read_index(session), [(int(n), label) for n, label in points]


def kill_points(points: list[tuple[int, str]]) -> list[int]:
    """Where to kill: past the calibration folder and before the next batch's bag (or 3 drawn, for make fuzz)."""
    boundaries = [n for n, label in points if not label.startswith(STAGED)]
    if FUZZ:
        return sorted(random.sample(boundaries, 3))
    calibration = next(n for n, label in points if label == "after calibration/")
    route_bag = next(n for n, label in points if label == "before route_bag/")
    return [calibration, route_bag]


@pytest.mark.slow  # two minutes: `make slow` (and `make fuzz`)
def test_a_killed_add_leaves_a_session_the_same_add_finishes(started, rehearsed, uninterrupted, tmp_path):
    reference, points = uninterrupted
    bag = rehearsed[0] / "batch_001" / REHEARSAL_BAG
    for point in kill_points(points):
        session = tmp_path / f"killed_{point}" / "session"
        shutil.copytree(started, session)
        killed = add(session, bag, {CRASH_AT: str(point)})
        assert killed.returncode == -9, (point, killed.stderr.decode())
        index = open_session(session)  # the index, every file it vouches for, the pool: as written
        for batch in index.batches:
            if batch.state is BatchState.ASSESSED and not batch.assessment.error:
                assert (session / batch.folder / "calibration" / "report.html").is_file(), point
        again = add(session, bag)
        assert again.returncode == 0, (point, again.stderr.decode())
        finished = read_index(session)
        assert [(b.recording, b.assessment) for b in finished.batches[:1]] == [
            (b.recording, b.assessment) for b in reference.batches[:1]
        ], point
        assert [(b.pool_rows, b.planned_s) for b in finished.batches[1:]] == [
            (b.pool_rows, b.planned_s) for b in reference.batches[1:]
        ], point
        open_session(session)


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["settings"].update(candidates=["offsets", "no_such_model"]), "unknown candidate model"),
        (lambda d: d["settings"].update(batch_postures="ten"), r"settings\.batch_postures must be an integer"),
        (lambda d: d.update(batches=[]), r"batches: expected the list of batches"),
        (lambda d: d["settings"].update(target_mm=-1.0), r"settings\.target_mm must be > 0"),
    ],
)
def test_an_add_on_a_hand_edited_index_fails_and_writes_nothing(edit, message, started, rehearsed, tmp_path):
    session = tmp_path / "session"
    shutil.copytree(started, session)
    data = yaml.safe_load((session / INDEX_FILE).read_text())
    edit(data)
    (session / INDEX_FILE).write_text(yaml.safe_dump(data, sort_keys=False))
    before = files_of(session)
    with open_backend(1) as backend, pytest.raises(InputError, match=message):
        add_bag(str(session), str(rehearsed[0] / "batch_001" / REHEARSAL_BAG), backend)
    assert files_of(session) == before


@pytest.mark.slow  # the started session (1.7 min, shared with the rehearsed one): `make slow`
def test_a_rehearsal_while_another_command_holds_the_session_names_the_lock(started, tmp_path, capsys):
    session = tmp_path / "session"
    shutil.copytree(started, session)
    before = files_of(session)
    with claim_output(session, OutputKind.FOLDER):  # another add, running
        with open_backend(1) as backend, pytest.raises(OutputError, match="being written by another posegen"):
            rehearse_session(str(session), ROBOT, backend, max_batches=1)
        assert main(["session", "rehearse", str(session), "--seed", "3", "--max-batches", "1"]) == 2
        err = capsys.readouterr().err
        assert_one_line_error(err)
        assert "being written by another posegen (pid" in err and "rosbag2" not in err
    assert files_of(session) == before
