"""Every shipped robot config: robot-agnostic code, loadable scenes, chains that match pinocchio."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from posegen.io import load_pool, write_pool
from posegen.model import ChainModel
from posegen.robot import Scene, load_config
from tests.conftest import CONFIG

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))


def names_in_config(data: dict) -> set[str]:
    """Robot, joint, link and frame names a config declares.

    A plain lowercase word ("head", "chest") is vocabulary, not a name: only names with an
    underscore, a digit or a capital letter count, plus the robots' and postures' names.
    """
    robot = data["robot"]
    names = {robot["source"].get("example_robot_data", "")}
    for key in ("locked_joints", "velocity_limits_rad_s", "frames"):
        names |= set(robot.get(key) or {})
    names |= {f["parent"] for f in (robot.get("frames") or {}).values()}
    collision = robot.get("collision") or {}
    names |= {link for pair in collision.get("disabled_pairs", []) for link in pair[:2]}
    names |= set(collision.get("shapes") or {})
    stance = data["stance"]
    names |= {stance.get("reference_posture") or "", *stance["sole_frames"], *stance["floor_contact_frames"]}
    names |= set(stance.get("reference_joints") or {})
    for chain in data["chains"].values():
        names |= {chain["sole_frame"], chain["gripper_frame"], chain["contact_frame"], *chain["fingertip_frames"]}
        names.add(chain.get("recorded_as", "").split("/")[0])
    distinctive = {n for n in names if re.search(r"[_0-9A-Z]", n)}
    return distinctive | {robot["source"].get("example_robot_data", ""), stance.get("reference_posture") or ""} - {""}


def test_the_package_names_no_robot_joint_or_frame():
    names = set().union(*(names_in_config(yaml.safe_load(p.read_text())) for p in CONFIGS))
    assert {"talos", "talos_full", "romeo", "icub", "half_sitting", "head_1_joint", "l_sole"} <= names
    sources = {p: p.read_text() for p in (ROOT / "posegen").rglob("*.py")}
    found = {  # an attribute (pin.FrameType.BODY) or a hyphenated word (human-readable) is not a robot's name
        (name, str(path.relative_to(ROOT)))
        for name in names
        for path, text in sources.items()
        if re.search(rf"(?<![\w.]){re.escape(name)}(?![\w-])", text)
    }
    assert not found, f"robot-specific names in posegen/: {sorted(found)}"


@pytest.fixture(scope="module", params=[p.name for p in CONFIGS])
def shipped(request):
    return Scene(load_config(ROOT / "configs" / request.param))


def test_every_shipped_chain_matches_pinocchio(shipped):
    """Chains of any length (6 leg + 1..5 torso + 7..8 arm joints here), any joint axis, flush or point contacts."""
    rng = np.random.default_rng(2)
    joints = rng.uniform(shipped.lower, shipped.upper, size=(3, len(shipped.joint_names)))
    joints = np.where(shipped.locked, shipped.locked_values, joints)  # a point frame may sit on a locked finger
    data = shipped.model.createData()
    for chain in shipped.chains:
        model = ChainModel(shipped, chain.name)
        assert 14 <= len(model.joint_indices) <= 19
        kind = chain.kinds[0]
        frames = model.sole_to_contact(joints, model.nominal_placements(), np.zeros(3), kind)
        for i in range(len(joints)):
            pin.framesForwardKinematics(shipped.model, data, shipped.configuration(joints[i]))
            sole = data.oMf[shipped.frame_id(chain.sole_frame)]
            contact = data.oMf[shipped.frame_id(chain.frame(kind))]
            assert frames[i] == pytest.approx(sole.actInv(contact).homogeneous, abs=1e-10)


@pytest.mark.parametrize(
    "config",
    [pytest.param(p.name, marks=() if p == CONFIG else pytest.mark.slow) for p in CONFIGS],
)  # the default robot in `make test`, every other one in `make slow`
def test_shipped_config_runs_end_to_end(config, tmp_path, capsys):
    """A few postures of each shipped robot: pool, check, route, check, simulate, calibrate (no edits).

    Selection needs a pool that identifies every base parameter (100+ postures): the
    benchmark runs it on every robot (``make bench``).
    """
    from posegen.cli.main import main

    def run(*argv: str) -> str:
        code = main(list(argv))
        out = capsys.readouterr().out
        assert code == 0, out
        return out

    pool = tmp_path / "pool.yaml"
    path = str(ROOT / "configs" / config)
    run("pool", "--n", "10", "--seed", "3", "--workers", "1", "--config", path, "-q", "-o", str(pool))
    assert "FAIL" not in run("check", str(pool), "-q")
    made = load_pool(pool)
    first = tmp_path / "first.yaml"
    write_pool(first, dataclasses.replace(made, postures=made.postures[:3]))
    route = tmp_path / "route.yaml"
    routed = re.search(r"route: (\d) of 3 postures", run("route", str(first), "-q", "-o", str(route)))
    assert routed and int(routed.group(1)) >= 1  # a pool (no repair): a posture may have no free motion
    assert "FAIL" not in run("check", str(route), "-q")
    measurements = tmp_path / "sim.yaml"
    run("simulate", str(pool), "--seed", "1", "-o", str(measurements))
    argv = ("calibrate", str(measurements), "--prior-scale", "5", "-q", "-o", str(tmp_path / "cal"))
    run(*argv)
    assert (tmp_path / "cal" / "calibrated.urdf").exists()
