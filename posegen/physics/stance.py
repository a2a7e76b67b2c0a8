"""The robot put down on its feet: both true soles flat on the floor before the run starts.

The true robot's legs do not close where the nominal ones do (placement errors of a few
millimetres and tenths of a degree along two legs put the second sole centimetres off).
A robot is put down on its feet and its stance settles: here the anchor sole is placed
at its place of the reference stance, flat on the floor, and the second leg's joints are
solved on the true robot (MuJoCo's kinematics) so that the second sole lies flat on the
floor too (its height, roll and pitch; where it lands on the floor is free), by the
smallest change of the planned angles.
"""

from __future__ import annotations

import mujoco
import numpy as np

from posegen.errors import InfeasibleError
from posegen.physics.builder import Layout
from posegen.robot import FloatArray, Scene

TOLERANCE = 1e-9  # m and rad
ITERATIONS = 50


def _site_pose(data: mujoco.MjData, site: int) -> FloatArray:
    pose = np.eye(4)
    pose[:3, :3] = data.site_xmat[site].reshape(3, 3)
    pose[:3, 3] = data.site_xpos[site]
    return pose


def _place_base(model: mujoco.MjModel, data: mujoco.MjData, anchor_site: int, target: FloatArray) -> None:
    """Move the free base so that the anchor sole's site is at ``target`` (4, 4)."""
    data.qpos[:7] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    mujoco.mj_kinematics(model, data)
    base = target @ np.linalg.inv(_site_pose(data, anchor_site))
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, base[:3, :3].ravel())
    data.qpos[:3], data.qpos[3:7] = base[:3, 3], quat
    mujoco.mj_kinematics(model, data)


def put_down(
    scene: Scene, model: mujoco.MjModel, data: mujoco.MjData, layout: Layout, joints: FloatArray
) -> FloatArray:
    """Set ``data`` to the robot standing at ``joints`` (nj,) rad, both soles flat; returns the angles it stands at.

    Raises:
        InfeasibleError: The second sole cannot be laid flat (the leg out of reach).

    """
    sites = [sensor.site for sensor in layout.soles.values()]
    leg = scene.leg_joints(scene.second_sole)
    data.qpos[:] = model.qpos0
    out = np.array(joints, dtype=float)
    jac_p, jac_r = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    for _ in range(ITERATIONS):
        data.qpos[layout.qpos] = out
        _place_base(model, data, sites[0], scene.sole_poses[scene.anchor_sole])
        pose = _site_pose(data, sites[1])
        error = np.array([pose[2, 3], pose[2, 0], pose[2, 1]])  # height; world z of the sole's x and y axes
        if np.abs(error).max() < TOLERANCE:
            mujoco.mj_forward(model, data)
            return out
        mujoco.mj_comPos(model, data)  # the Jacobian reads the bodies' frames of motion
        mujoco.mj_jacSite(model, data, jac_p, jac_r, sites[1])
        x_axis, y_axis = pose[:3, 0], pose[:3, 1]  # d(axis)/dt = w x axis: its z is w_x a_y - w_y a_x
        rows = np.vstack(
            [jac_p[2], x_axis[1] * jac_r[0] - x_axis[0] * jac_r[1], y_axis[1] * jac_r[0] - y_axis[0] * jac_r[1]]
        )
        rows = rows[:, layout.dof[leg]]  # the base placed by the anchor: only the second leg's joints act
        out[leg] -= rows.T @ np.linalg.solve(rows @ rows.T + 1e-12 * np.eye(3), error)
    raise InfeasibleError(f"the true robot's {scene.second_sole} cannot be laid flat on the floor at the route's start")
