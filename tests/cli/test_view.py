"""``posegen view``: a page written on request, bad artefacts refused in one line with no file left."""

from tests.cli.test_cli import assert_fails_cleanly, run


def test_view_writes_one_page(selection_file, tmp_path, capsys):
    out = tmp_path / "selection.html"
    code, stdout, _ = run(["view", str(selection_file), "--html", str(out)], capsys)
    assert code == 0 and out.exists()
    assert "opens offline" in stdout and f"{out.stat().st_size / 1e6:.2f} MB" in stdout


def test_view_of_a_bad_artefact_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "view.html"
    assert_fails_cleanly(["view", str(tmp_path / "missing.yaml"), "--html", str(out)], out, capsys)
    config = tmp_path / "config.yaml"
    config.write_text("robot: {}\n")
    err = assert_fails_cleanly(["view", str(config), "--html", str(out)], out, capsys)
    assert "pool, selection or route file, nor a calibration folder" in err


def test_the_help_states_the_viewers_defaults():
    """The command line spells the viewer's defaults (to stay light): they must be the viewer's."""
    from posegen.cli import view as command
    from posegen.view import DEFAULT_HOST, DEFAULT_PORT

    assert (command.DEFAULT_PORT_HELP, command.DEFAULT_HOST_HELP) == (DEFAULT_PORT, DEFAULT_HOST)


def test_the_command_line_does_not_load_the_viewer_or_the_calibration():
    """Every command starts without importing viser, the viewer or the calibration stage (~1-2 s)."""
    import subprocess
    import sys

    heavy = ("viser", "posegen.view", "posegen.calibrate", "scipy.stats")
    code = f"import sys, posegen.cli.main; print(sorted(m for m in {heavy!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "[]"
