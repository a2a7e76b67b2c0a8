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
away (:class:`PlannedFeet` moves the plan's floor points with the soles).
"""

from __future__ import annotations

import mujoco
import numpy as np

from posegen.errors import InfeasibleError
from posegen.physics.builder import Layout
from posegen.physics.lapack import Factored
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


class PlannedFeet:
    """The two soles where the plan puts them; :meth:`follow` moves the plan's floor points with them.

    Each sole's motion on the floor (its planned pose to its standing one) moves a point;
    the point moves by the blend of the two, by how far along it lies from the first sole's
    centre to the second's (0 at the first, 1 at the second, clipped): a ZMP the plan puts
    under one foot stays under that foot, and one the plan puts midway stays midway. A
    balance is a place relative to the feet: the plan's CoM 2 cm inside the second sole's
    outer edge is 2 cm inside wherever that sole stands. The planned poses are factored
    once (the controllers move two points every control period).

    Example:
        >>> moved = np.eye(4); moved[:2, 3] = [0.0, -0.05]  # the second sole 3.5 cm inward of its plan
        >>> planned = np.eye(4); planned[:2, 3] = [0.0, -0.085]
        >>> PlannedFeet((np.eye(4), planned), np.zeros(3)).follow(np.array([0.0, -0.085]), (np.eye(4), moved))
        array([ 0.  , -0.05])

    """

    def __init__(self, planned: tuple[FloatArray, FloatArray], centre: FloatArray) -> None:
        """Both soles' planned world poses (4, 4); ``centre`` (3,) m, the foot rectangle's centre in a sole frame."""
        start, end = (pose[:2, :3] @ centre + pose[:2, 3] for pose in planned)  # the planned centres (2,)
        self._start = start
        self._axis = end - start
        self._length_sq = max(float(self._axis @ self._axis), 1e-12)
        self._planned = tuple(Factored(pose) for pose in planned)

    def follow(self, point: FloatArray, standing: tuple[FloatArray, FloatArray]) -> FloatArray:
        """The point (2,) m (world x and y) moved with the soles to where they stand ((4, 4) world poses each)."""
        along = min(max(float((point - self._start) @ self._axis / self._length_sq), 0.0), 1.0)  # np.clip's numbers
        on_floor = np.array([point[0], point[1], 0.0, 1.0])
        moved = [(pose @ planned.solve(on_floor))[:2] for planned, pose in zip(self._planned, standing, strict=True)]
        return np.asarray((1.0 - along) * moved[0] + along * moved[1])
