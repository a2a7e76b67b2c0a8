"""The optional parts: the core runs without them, and a command that needs one names it.

Each test runs posegen in a fresh interpreter whose imports of the optional packages
fail, as they would after ``pip install posegen`` without extras.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from posegen.extras import PACKAGES, Extra

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE_POOL = ROOT / "plans" / "talos" / "pool.yaml"
EVERY_OPTIONAL = sorted({m for modules in PACKAGES.values() for m in modules})

HIDE = """
import sys

class Hide:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, Hide())
"""


def without(hidden: list[str], code: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a new interpreter where importing any of ``hidden`` fails."""
    script = f"HIDDEN = {set(hidden)!r}\n{HIDE}\n{textwrap.dedent(code)}"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-c", script], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def posegen_without(hidden: list[str], argv: list[str]) -> subprocess.CompletedProcess[str]:
    """The ``posegen`` command with ``argv``, where importing any of ``hidden`` fails."""
    return without(hidden, f"from posegen.cli import main\nsys.exit(main({argv!r}))")


def assert_asks_for(result: subprocess.CompletedProcess[str], extra: Extra) -> None:
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert lines[0].startswith("posegen: error: ") and lines[0].endswith(f"pip install 'posegen[{extra.value}]'")


def test_the_hider_hides():
    result = without(["viser"], "import viser")
    assert result.returncode == 1 and "ModuleNotFoundError" in result.stderr


def test_view_without_viser_names_the_view_extra(tmp_path):
    result = posegen_without(["viser"], ["view", str(EXAMPLE_POOL), "--html", str(tmp_path / "pool.html")])
    assert_asks_for(result, Extra.VIEW)
    assert "viser" in result.stderr and not (tmp_path / "pool.html").exists()


def test_a_scheduler_without_dask_names_the_dask_extra(tmp_path):
    out = tmp_path / "pool.yaml"
    result = posegen_without(["distributed"], ["pool", "--n", "4", "--scheduler", "tcp://127.0.0.1:9", "-o", str(out)])
    assert_asks_for(result, Extra.DASK)
    assert not out.exists()


def test_bags_without_rosbags_name_the_ros_extra(tmp_path):
    result = without(
        ["rosbags"],
        f"""
        from posegen.errors import ExtraError
        from posegen.io.bag_writer import writing_bag
        try:
            with writing_bag({str(tmp_path / "bag")!r}, {{}}):
                pass
        except ExtraError as exc:
            print(exc)
        """,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip().endswith("pip install 'posegen[ros]'") and "rosbags" in result.stdout
    assert not (tmp_path / "bag").exists()


def test_import_posegen_and_the_help_need_no_extra():
    result = without(EVERY_OPTIONAL, "from posegen.cli import main\nsys.exit(main(['--help']))")
    assert result.returncode == 0 and "pool" in result.stdout, result.stderr
    loaded = without(
        [],
        f"""
        import posegen
        heavy = {EVERY_OPTIONAL!r} + ["numpy", "pinocchio", "placo", "matplotlib"]
        print(sorted(m for m in heavy if m in sys.modules))
        """,
    )
    assert loaded.stdout.strip() == "[]", loaded.stdout + loaded.stderr


def test_the_core_simulates_and_calibrates_without_any_extra(tmp_path):
    """simulate -> calibrate with viser, trimesh, Dask and rosbags missing: the folder, no report, one note."""
    meas, out = tmp_path / "meas.yaml", tmp_path / "cal"
    result = posegen_without(EVERY_OPTIONAL, ["simulate", str(EXAMPLE_POOL), "--seed", "2", "-q", "-o", str(meas)])
    assert result.returncode == 0, result.stderr
    argv = ["calibrate", f"{meas}@day1", "--prior-scale", "5", "--candidates", "offsets", "--fold-seeds", "1"]
    result = posegen_without(EVERY_OPTIONAL, [*argv, "--workers", "1", "-q", "-o", str(out)])
    assert result.returncode == 0, result.stderr
    assert (out / "calibrated.urdf").is_file() and (out / "calibration.yaml").is_file()
    assert not (out / "report.html").exists() and "no report.html" in result.stdout
    [note] = [line for line in result.stderr.splitlines() if "report.html not written" in line]
    assert note.startswith("posegen: ") and note.endswith("pip install 'posegen[view]'")


@pytest.mark.parametrize("extra", list(Extra))
def test_every_extra_is_installed_here(extra):
    """``make install`` installs ``posegen[all]``: the tests above hide what is really there."""
    result = without([], f"from posegen.extras import Extra, require\nrequire(Extra({extra.value!r}), 'test')")
    assert result.returncode == 0, result.stderr
