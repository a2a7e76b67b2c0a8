"""The scripts of examples/ run as a user runs them (a fresh interpreter, their own folder), on small sizes."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pinocchio as pin
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def run_example(name: str, *args: str, cwd: Path, env: dict[str, str] | None = None) -> str:
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1", **(env or {})}
    result = subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args],
        cwd=cwd,
        env=environment,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Traceback" not in result.stderr
    return result.stdout


def mean_z(stdout: str, row: str, file: str) -> float:
    """The mean absolute height error (mm) the table prints for a set (training, held-out) and file, all chains."""
    lines = [ln for ln in stdout.splitlines() if ln.split()[:1] == [row] and f" {file} " in ln]
    counts = [int(ln.split()[-7]) for ln in lines]
    return float(sum(c * float(ln.split()[-6]) for c, ln in zip(counts, lines, strict=True)) / sum(counts))


def test_every_example_is_run_here():
    tested = set(re.findall(r'run_example\("(\w+\.py)"', Path(__file__).read_text()))
    assert tested == {p.name for p in EXAMPLES.glob("*.py")}


@pytest.mark.slow  # a minute: `make slow`; the wheel's step runs the example too
def test_the_whole_pipeline(tmp_path):
    stdout = run_example("pipeline.py", "out", "--workers", "2", cwd=tmp_path)
    out = tmp_path / "out"
    assert "no violation" in stdout
    for name in ("pool.yaml", "selected.yaml", "route.yaml", "measured.yaml", "calibration/calibrated.urdf"):
        assert (out / name).is_file(), name
    assert mean_z(stdout, "held-out", "calibrated.urdf") < mean_z(stdout, "held-out", "nominal URDF")
    pin.buildModelFromUrdf(str(out / "calibration" / "calibrated.urdf"))


def test_a_robot_from_its_urdf(tmp_path):
    stdout = run_example("robot_from_urdf.py", "out", cwd=tmp_path)
    draft = yaml.safe_load((tmp_path / "out" / "talos_table.yaml").read_text())
    assert draft["robot"]["source"] == {"example_robot_data": "talos"}
    assert "the draft loads as a scene" in stdout and ".urdf" in stdout


def test_calibrating_recorded_csv_and_loading_the_result(tmp_path, real_data):
    stdout = run_example(
        "calibrate_recorded.py", str(real_data), "-o", "out", "--candidates", "offsets", "offsets_hip_pitch",
        cwd=tmp_path,
    )  # fmt: skip
    assert mean_z(stdout, "held-out", "calibrated.urdf") < mean_z(stdout, "held-out", "nominal URDF")
    assert re.search(r"gripper_left_base_link moved \d+\.\d mm", stdout)
    compliant = (tmp_path / "out" / "with_compliance" / "compliance.yaml").is_file()
    assert ("encoders corrected by up to" in stdout) == compliant


def test_calibrating_recorded_csv_without_the_data_skips_politely(tmp_path):
    stdout = run_example("calibrate_recorded.py", cwd=tmp_path, env={"POSEGEN_REAL_DATA": str(tmp_path)})
    assert "skipping" in stdout and not (tmp_path / "plans").exists()


def test_a_follow_up_session(tmp_path):
    stdout = run_example("follow_up.py", "out", cwd=tmp_path)
    chosen = yaml.safe_load((tmp_path / "out" / "next.yaml").read_text())
    assert chosen["method"] == "followup" and len(chosen["postures"]) == 10
    sigma = chosen["figures"]["predicted_height_sigma_mm"][chosen["figures"]["weakest_chain"]]
    assert sigma["after"] < sigma["before"] and "follow-up: 10 postures" in stdout
