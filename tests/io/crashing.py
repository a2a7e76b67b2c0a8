"""A script killed at each of its crash points in turn (``posegen.io.atomic``'s CRASH_LOG and CRASH_AT).

Shared by the tests of the writers that promise "the old or the new, whole" after a kill.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from posegen.io.atomic import CRASH_AT, CRASH_LOG

ROOT = Path(__file__).resolve().parents[2]


def run_script(script: str, out: Path, env: dict[str, str]) -> subprocess.CompletedProcess[bytes]:
    """Run ``script`` (Python source; ``sys.argv[1]`` is ``out``) in a fresh interpreter on this tree."""
    return subprocess.run(
        [sys.executable, "-c", script, str(out)],
        env={**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1", **env},
        capture_output=True,
        timeout=120,
        check=False,
    )


def kill_at_every_point(
    tmp_path: Path, script: str, old_state: Callable[[Path], None], check: Callable[[Path, str], None]
) -> list[str]:
    """Log the script's crash points on the old state, then kill it at each one and ``check`` what it left.

    Args:
        tmp_path: A scratch folder (one sub-folder per run).
        script: The writes under test.
        old_state: Writes the old artefacts into a folder.
        check: Called with the folder and the crash point's label after each kill.

    Returns:
        The crash points' labels, in order (the run that logged them must succeed).

    """
    log = tmp_path / "points.log"
    out = tmp_path / "log"
    out.mkdir()
    old_state(out)
    logged = run_script(script, out, {CRASH_LOG: str(log)})
    assert logged.returncode == 0, logged.stderr
    labels = [line.split(" ", 1)[1] for line in log.read_text().splitlines()]
    for n, label in enumerate(labels, start=1):
        out = tmp_path / f"kill{n}"
        out.mkdir()
        old_state(out)
        done = run_script(script, out, {CRASH_AT: str(n)})
        assert done.returncode == -signal.SIGKILL, (label, done.stderr)
        check(out, label)
    return labels
