"""The robot put down on its feet: both true soles flat on the floor before the run starts.

The true robot's legs do not close where the nominal ones do (placement errors of a few
millimetres and tenths of a degree along two legs put the second sole centimetres off).
A robot is put down on its feet and its stance settles: here the anchor sole is placed
at its place of the reference stance, flat on the floor, and the second leg's joints are
solved on the true robot (MuJoCo's kinematics) so that the second sole lies flat on the
floor too (its height, roll and pitch; where it lands on the floor is free), by the
smallest change of the planned angles.

The plan's balance (its CoM and ZMP on the floor) is laid out around the soles where the
plan puts them; the robot stands with its second sole where its legs put it, centimetres
away (:func:`follow_feet` moves the plan's floor points with the soles).
"""

from __future__ import annotations

import mujoco
import numpy as np

from posegen.errors import InfeasibleError
from posegen.physics.builder import Layout
from posegen.robot import FloatArray, Scene

Sole = tuple[FloatArray, FloatArray]  # a sole's pose (4, 4) where the plan puts it, and where the robot stands on it

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


def follow_feet(point: FloatArray, soles: tuple[Sole, Sole], centre: FloatArray) -> FloatArray:
    """A point (2,) m of the plan's floor, moved with the soles from where the plan puts them to where they stand.

    Each sole's motion on the floor (its planned pose to its standing one, (4, 4) each) moves
    the point; it moves by the blend of the two, by how far along it lies from the first
    sole's centre to the second's (0 at the first, 1 at the second, clipped): a ZMP the plan
    puts under one foot stays under that foot, and one the plan puts midway stays midway.
    A balance is a place relative to the feet: the plan's CoM 2 cm inside the second sole's
    outer edge is 2 cm inside wherever that sole stands.

    Args:
        point: (2,) m, world x and y.
        soles: The two soles, each (planned, standing) (4, 4) world poses.
        centre: (3,) m, the foot rectangle's centre in a sole's frame.

    Example:
        >>> moved = np.eye(4); moved[:2, 3] = [0.0, -0.05]  # the second sole 3.5 cm inward of its plan
        >>> planned = np.eye(4); planned[:2, 3] = [0.0, -0.085]
        >>> follow_feet(np.array([0.0, -0.085]), ((np.eye(4), np.eye(4)), (planned, moved)), np.zeros(3))
        array([ 0.  , -0.05])

    """
    (first, _), (second, _) = soles
    start, end = (pose[:2, :3] @ centre + pose[:2, 3] for pose in (first, second))  # the planned centres (2,)
    axis = end - start
    along = float(np.clip((point - start) @ axis / max(float(axis @ axis), 1e-12), 0.0, 1.0))
    on_floor = np.array([point[0], point[1], 0.0, 1.0])
    moved = [(standing @ np.linalg.solve(planned, on_floor))[:2] for planned, standing in soles]  # (2,) each
    return np.asarray((1.0 - along) * moved[0] + along * moved[1])
