"""``posegen calibrate``'s start: the workers' imports begin before the command's own."""

import subprocess
import sys

# open_backend replaced by a probe: it reports what this process had imported when the backend was asked
# for, and the preload the workers were to import, then ends the run
PROBE = """
import os, sys
import posegen.parallel as parallel

def probe(workers=1, scheduler=None, preload=()):
    print("posegen.calibrate" in sys.modules, "posegen.view" in sys.modules, sorted(preload), flush=True)
    os._exit(0)

parallel.open_backend = probe
from posegen.cli import main
main(["calibrate", "missing.csv", "-q", "-o", "out"])
"""


def test_the_workers_imports_start_before_the_commands_own(tmp_path):
    """The backend (its forkserver importing the workers' modules) is opened before calibrate imports its stages.

    The workers' imports then run beside this process's (about 0.6 s off a 2-core calibration): opened after
    them, the first cross-validation waited for the forkserver to finish importing.
    """
    result = subprocess.run(
        [sys.executable, "-c", PROBE], cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False
    )
    assert result.returncode == 0, result.stderr
    calibrate_imported, view_imported, preload = result.stdout.split(maxsplit=2)
    assert (calibrate_imported, view_imported) == ("False", "False")
    assert "posegen.calibrate.model_selection" in preload and "posegen.view.report_figures" in preload
