"""``posegen robot init MODEL.xml``: an MJCF humanoid drafted through the URDF written beside the draft."""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from posegen.cli.main import main
from posegen.draft.mjcf import convert_mjcf
from posegen.io import load_pool
from posegen.io.atomic import CRASH_AT, CRASH_LOG, leftover_temporaries
from posegen.robot import Scene, load_config
from tests.draft.humanoid_mjcf import humanoid_mjcf

REPO = Path(__file__).resolve().parents[2]


def _init(mjcf: Path, output: Path) -> int:
    return main(["robot", "init", str(mjcf), "-o", str(output), "--samples", "20", "-q"])


def test_robot_init_writes_a_draft_and_its_urdf_and_the_draft_runs(tmp_path, capsys):
    mjcf = humanoid_mjcf(tmp_path / "model")
    output = tmp_path / "configs" / "humanoid.yaml"
    assert _init(mjcf, output) == 0
    out = capsys.readouterr().out
    urdf = (tmp_path / "configs" / "humanoid.urdf").absolute()
    assert f"note: MJCF {mjcf} converted to {urdf}" in out
    assert urdf.read_text() == convert_mjcf(mjcf).text  # the conversion, whole
    text = output.read_text()
    assert yaml.safe_load(text)["robot"]["source"] == {"urdf": str(urdf)}  # the stages read the URDF
    sha = hashlib.sha256(mjcf.read_bytes()).hexdigest()
    (check,) = [line for line in text.splitlines() if "converted by posegen from the MJCF" in line]
    assert check.startswith("# CHECK: robot.source.urdf") and f"{mjcf.resolve()} (sha256 {sha})" in check
    assert "Not carried: 1 actuator; 1 site; 1 body with visual-only geoms" in check
    scene = Scene(load_config(output))
    assert {"l_hip_yaw", "l_hip_roll", "l_hip_pitch", "l_ankle_pitch", "l_ankle_roll"} <= set(scene.model.names)
    pool = tmp_path / "pool.yaml"
    argv = ["pool", "--n", "3", "--seed", "1", "--workers", "1", "--config", str(output), "-q", "-o", str(pool)]
    assert main(argv) == 0
    assert len(load_pool(pool).postures) == 3
    capsys.readouterr()
    assert main(["check", str(pool), "-q"]) == 0
    assert re.search(r"\(\d+ primitives; pinocchio", capsys.readouterr().out)  # no mesh: no "meshes" said
    assert _init(mjcf, output) == 0  # a re-run: the same URDF is there already, kept


def test_a_slide_finger_ending_the_arm_is_locked_and_the_draft_loads(tmp_path, capsys):
    """Was: the 2 cm finger stayed in the arm, the hand was the finger, and the draft did not load."""
    mjcf = humanoid_mjcf(tmp_path / "model")
    text = mjcf.read_text()
    for side in ("l", "r"):
        wrist = f'<joint name="{side}_wrist" axis="0 1 0" range="-1 1"/>'
        finger = (
            f'<body name="{side}_finger" pos="0 0 -0.1"><inertial pos="0 0 0" mass="0.005" diaginertia="1e-6 1e-6 '
            f'1e-6"/><joint name="{side}_finger_slide" type="slide" axis="1 0 0" range="0 0.02"/>'
            '<geom type="box" size="0.005 0.005 0.01"/></body>'
        )
        text = text.replace(wrist, wrist + finger)
    mjcf.write_text(text)
    output = tmp_path / "humanoid.yaml"
    assert _init(mjcf, output) == 0
    out = capsys.readouterr().out
    assert "note: the draft loads as a scene" in out and "hands l_hand, r_hand" in out
    draft = output.read_text()
    assert "# CHECK: 'l_finger_slide' ended an arm with a range under twice margins.joint_limit_rad" in draft
    config = load_config(output)
    assert {"l_finger_slide", "r_finger_slide"} <= set(config.locked_joints)
    scene = Scene(config)
    free = {scene.joint_names[j] for j in range(len(scene.joint_names)) if not scene.locked[j]}
    assert "l_wrist" in free and "l_finger_slide" not in free


def test_a_urdf_in_the_way_is_never_overwritten(tmp_path, capsys):
    mjcf = humanoid_mjcf(tmp_path / "model")
    theirs = tmp_path / "humanoid.urdf"
    theirs.write_text("<robot name='theirs'/>")
    assert _init(mjcf, tmp_path / "humanoid.yaml") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(r"humanoid\.urdf exists and is not this MJCF's conversion", err)
    assert theirs.read_text() == "<robot name='theirs'/>" and not (tmp_path / "humanoid.yaml").exists()
    assert _init(mjcf, tmp_path / "model.urdf") == 2  # the draft itself where the URDF goes
    assert "give an -o ending in .yaml" in capsys.readouterr().err
    before = mjcf.read_bytes()
    assert _init(mjcf, mjcf) == 2  # the draft over its MJCF
    assert "is an input of this command" in capsys.readouterr().err and mjcf.read_bytes() == before


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("malformed", r"robot\.xml: not valid XML"),
        ("no_legs", r"model/robot\.xml: no two legs: .*'waist'"),  # the MJCF named, not its removed URDF
        ("ball", r"robot\.xml: joint 'r_knee' is a ball joint"),
    ],
)
def test_bad_mjcf_is_one_line_and_nothing_is_written(case, message, tmp_path, capsys):
    mjcf = humanoid_mjcf(tmp_path / "model", legs=0 if case == "no_legs" else 2)
    if case == "malformed":
        mjcf.write_text(mjcf.read_text().replace("</worldbody>", ""))
    elif case == "ball":
        mjcf.write_text(
            mjcf.read_text().replace('<joint name="r_knee" axis="0 1 0"', '<joint name="r_knee" type="ball"')
        )
    out = tmp_path / "out"
    assert _init(mjcf, out / "draft.yaml") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("posegen: error: ")
    assert re.search(message, err), err
    assert not list(out.glob("*")) if out.exists() else True  # neither the draft nor its URDF


def test_a_kill_at_every_write_leaves_whole_files_and_a_rerun_finishes(tmp_path):
    mjcf = humanoid_mjcf(tmp_path / "model")
    expected = convert_mjcf(mjcf).text
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(REPO)}
    argv = [sys.executable, "-m", "posegen.cli", "robot", "init", str(mjcf), "--samples", "5", "-q", "-o"]
    log = tmp_path / "crash.log"
    subprocess.run([*argv, str(tmp_path / "full" / "d.yaml")], env={**env, CRASH_LOG: str(log)}, cwd=cwd, check=True)
    points = len(log.read_text().splitlines())
    assert points == 4  # before and after each of the two renames
    for n in range(1, points + 1):
        folder = tmp_path / f"kill{n}"
        draft, urdf = folder / "d.yaml", folder / "d.urdf"
        result = subprocess.run([*argv, str(draft)], env={**env, CRASH_AT: str(n)}, cwd=cwd, capture_output=True)
        assert result.returncode == -9
        assert not urdf.exists() or urdf.read_text() == expected  # whole or absent
        assert not draft.exists() or urdf.exists()  # never a draft without its URDF
        subprocess.run([*argv, str(draft)], env=env, cwd=cwd, check=True, capture_output=True)  # a re-run finishes
        same = draft.read_text().replace(str(folder), str(tmp_path / "full"))
        assert urdf.read_text() == expected and same == (tmp_path / "full" / "d.yaml").read_text()
        assert not leftover_temporaries(draft) and not leftover_temporaries(urdf)
