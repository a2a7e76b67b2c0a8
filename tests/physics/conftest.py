"""Shared fixtures of the physics tests: MuJoCo models of TALOS, nominal and perturbed (skipped without mujoco)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("mujoco")

from posegen.calibrate import Perturbation
from posegen.physics.builder import Built, build
from posegen.physics.gains import Gains, joint_gains
from posegen.physics.tool import Tool, wrist_tool
from posegen.physics.true_robot import TrueRobot, draw_true_robot
from posegen.robot import Scene

PHYSICS_ROWS = [92, 0]  # one contact per arm, the example pool's lowest torques whose CoM is 4 cm inside


@pytest.fixture(scope="session")
def gains(scene: Scene) -> Gains:
    return joint_gains(scene)


@pytest.fixture(scope="session")
def tools(scene: Scene) -> dict[str, Tool]:
    return {c.name: wrist_tool(scene, c.sensor_frame) for c in scene.chains}


@pytest.fixture(scope="session")
def nominal(scene: Scene, gains: Gains, tools: dict[str, Tool]) -> Built:
    """The nominal TALOS at the config's table."""
    return build(scene, scene.urdf_xml, scene.table_pose, gains, tools)


@pytest.fixture(scope="session")
def true_robot(scene: Scene) -> TrueRobot:
    """The robot ``simulate --bag --seed 3`` draws, with a compliant hip pitch."""
    return draw_true_robot(scene, "sim", Perturbation(compliance_rad_per_nm=3e-4), 3)


@pytest.fixture(scope="session")
def perturbed(scene: Scene, gains: Gains, tools: dict[str, Tool], true_robot: TrueRobot) -> Built:
    return build(scene, true_robot.urdf, true_robot.table_top, gains, tools, true_robot.springs)


@pytest.fixture(scope="session")
def physics_route(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The route through two postures of the example pool that the robot's joints hold with room to spare."""
    from posegen.io import load_pool, write_yaml
    from posegen.route import route_postures_file
    from tests.conftest import EXAMPLE_POOL

    folder = tmp_path_factory.mktemp("physics_route")
    data = load_pool(EXAMPLE_POOL).to_dict()
    data["postures"] = [data["postures"][i] for i in PHYSICS_ROWS]
    write_yaml(folder / "two.yaml", data)
    route_postures_file(str(folder / "two.yaml"), str(folder / "route.yaml"), 0, None)
    return folder / "route.yaml"
