"""Standing contact postures of every shipped robot, for tests that rehearse each one (``tests/data/standing/``).

Made by ``posegen pool`` (the robot's config, ``--seed 1``): the first ``COUNT`` postures
of each pool, their joint angles, chains and spots, saved with the config's joint names
and robot model hash. Run this module to make them again when a shipped robot changes::

    python -m tests.calibrate.standing_postures
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
FOLDER = ROOT / "tests" / "data" / "standing"
ROBOTS = ("talos", "talos_full", "romeo", "icub", "human", "jvrc")
COUNT = 60


def config_of(robot: str) -> Path:
    return ROOT / "configs" / f"{robot}_table.yaml"


def load_standing(robot: str):
    """The robot's scene and its standing postures as planned contacts (one table session, ``sim``).

    Raises:
        AssertionError: The saved postures were made for another robot model (make them again).

    """
    from posegen.model import Contacts, planned_kinds
    from posegen.robot import Scene, load_config

    scene = Scene(load_config(config_of(robot)))
    with np.load(FOLDER / f"{robot}.npz") as data:
        joints, chains, spots = data["joints"], tuple(str(c) for c in data["chains"]), tuple(data["spots"])
        names, sha = tuple(str(n) for n in data["joint_names"]), str(data["robot_model_sha256"])
    assert names == tuple(scene.joint_names) and sha == scene.files.sha256(), (
        f"{robot}: the saved standing postures are another robot's: run python -m tests.calibrate.standing_postures"
    )
    n = len(chains)
    labels = tuple(f"{robot}.yaml:{i + 1}:{s}" for i, s in enumerate(spots))
    return scene, Contacts(joints, chains, ("sim",) * n, labels, planned_kinds(scene, chains))


def make(robot: str, folder: Path) -> None:
    """Write ``tests/data/standing/<robot>.npz`` from a fresh pool of the shipped config."""
    from posegen.io import load_pool
    from posegen.robot import Scene, load_config

    pool_path = folder / f"{robot}_pool.yaml"
    argv = [sys.executable, "-m", "posegen.cli", "pool", "--config", str(config_of(robot)), "--n", str(COUNT)]
    subprocess.run([*argv, "--seed", "1", "-q", "-o", str(pool_path)], check=True, cwd=ROOT)
    pool = load_pool(pool_path)
    scene = Scene(load_config(config_of(robot)))
    postures = pool.postures[:COUNT]
    np.savez_compressed(
        FOLDER / f"{robot}.npz",
        joints=pool.joints()[:COUNT],
        chains=np.array([p.chain for p in postures]),
        spots=np.array([p.spot for p in postures]),
        joint_names=np.array(scene.joint_names),
        robot_model_sha256=np.array(scene.files.sha256()),
    )


if __name__ == "__main__":
    FOLDER.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        for name in sys.argv[1:] or ROBOTS:
            make(name, Path(scratch))
