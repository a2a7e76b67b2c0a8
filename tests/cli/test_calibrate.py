"""``posegen calibrate``'s start: the workers' imports begin before the command's own."""

from tests.cli.backend_probe import at_backend_opening


def test_the_workers_imports_start_before_the_commands_own(tmp_path):
    """The backend (its forkserver importing the workers' modules) is opened before calibrate imports its stages.

    The workers' imports then run beside this process's (about 0.6 s off a 2-core calibration): opened after
    them, the first cross-validation waited for the forkserver to finish importing.
    """
    argv = ["calibrate", "missing.csv", "-q", "-o", "out"]
    imported, preload = at_backend_opening(tmp_path, argv, ["posegen.calibrate", "posegen.view"])
    assert imported == [False, False]
    assert "posegen.calibrate.model_selection" in preload and "posegen.view.report_figures" in preload
