"""The tool a wrist sensor carries: its mass and centre of mass are MuJoCo's subtree's, in the sensor's frame."""

from __future__ import annotations

import mujoco
import numpy as np

from posegen.physics.builder import Built
from posegen.physics.tool import Tool
from posegen.robot import Scene


def test_the_tool_is_the_sensor_body_s_subtree(scene: Scene, nominal: Built, tools: dict[str, Tool]) -> None:
    model = nominal.model
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    data.qpos[nominal.layout.qpos] = scene.locked_values  # the fingers at their locked values
    mujoco.mj_forward(model, data)
    for chain, tool in tools.items():
        body = model.body(tool.link).id
        assert abs(model.body_subtreemass[body] - tool.mass_kg) < 1e-9
        site = nominal.layout.wrists[chain].site
        rotation, origin = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
        assert np.abs(rotation.T @ (data.subtree_com[body] - origin) - tool.com_m).max() < 1e-9
    assert 1.0 < tools["left"].mass_kg < 1.5  # TALOS's gripper
