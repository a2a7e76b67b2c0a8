"""Gauss-Newton projection of a joint sample onto balanced table contact (placo).

The problem: both soles at their fixed poses, the CoM ground projection inside the
support polygon with margin, one chain's contact frame flush on the table (height,
roll, pitch zero; yaw free) near a target spot, joint limits shrunk by a margin, and the
sample itself as a weak posture task (what keeps the pool diverse).

Solving from a random sample with every task hard is infeasible at the first step, so
the solver runs a soft phase, then a hard phase that makes the equality tasks exact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import placo

from posegen.robot.description import kinematic_urdf
from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene

FOOT_WEIGHT = 100.0
CONTACT_WEIGHT = 100.0
SPOT_WEIGHT = 1.0
POSTURE_WEIGHT = 1e-3
REGULARIZATION = 1e-4
CONVERGED_M = 2e-6  # equality errors below this end the hard phase
CONVERGED_RAD = 2e-5
COM_BUFFER_M = 1e-3  # solved inside the configured margin, so the re-check has slack
LIMIT_BUFFER_RAD = 1e-4


@dataclass(frozen=True)
class Projection:
    """Result of one projection."""

    joints: FloatArray  # (nj,) rad
    converged: bool
    iterations: int


class _ChainProblem:
    """The placo tasks of one chain in contact (built once, retargeted per sample)."""

    def __init__(self, robot: placo.RobotWrapper, scene: Scene, chain: str) -> None:
        self.solver = placo.KinematicsSolver(robot)
        self.solver.mask_fbase(False)
        self.solver.enable_joint_limits(True)
        self.solver.enable_velocity_limits(False)
        for i, name in enumerate(scene.joint_names):
            if scene.locked[i]:
                self.solver.mask_dof(name)
        self.feet = [self.solver.add_frame_task(f, scene.sole_poses[f]) for f in scene.stance.sole_frames]
        contact = scene.chain(chain).contact_frame
        table_normal = scene.table_pose[:3, 2].copy()
        self.height = self.solver.add_position_task(contact, scene.table_pose[:3, 3].copy())
        self.height.mask.set_axises("z", "world")
        self.spot = self.solver.add_position_task(contact, scene.table_pose[:3, 3].copy())
        self.spot.mask.set_axises("xy", "world")
        self.spot.configure(f"{chain}_spot", "soft", SPOT_WEIGHT)
        self.flush = self.solver.add_axisalign_task(contact, np.array([0.0, 0.0, 1.0]), table_normal)
        com = self.solver.add_com_polygon_constraint(scene.support_polygon, scene.margins.com_m + COM_BUFFER_M)
        com.configure("com", "hard", 1.0)
        self.posture = self.solver.add_joints_task()
        self.posture.configure("posture", "soft", POSTURE_WEIGHT)
        self.solver.add_regularization_task(REGULARIZATION)
        self.contact = contact

    def harden(self, hard: bool) -> None:
        mode = "hard" if hard else "soft"
        for k, task in enumerate(self.feet):
            task.configure(f"foot_{k}", mode, FOOT_WEIGHT)
        self.height.configure("height", mode, CONTACT_WEIGHT)
        self.flush.configure("flush", mode, CONTACT_WEIGHT)


class Projector:
    """Projects joint samples onto balanced flush contact, one chain at a time."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.robot = placo.RobotWrapper("", placo.Flags.ignore_collisions, kinematic_urdf(scene.urdf_xml))
        margin = scene.margins.joint_limit_rad + LIMIT_BUFFER_RAD
        for i, name in enumerate(scene.joint_names):
            if not scene.locked[i]:
                self.robot.set_joint_limits(name, scene.lower[i] + margin, scene.upper[i] - margin)
        self._problems = {c.name: _ChainProblem(self.robot, scene, c.name) for c in scene.chains}

    def _set_joints(self, joints: FloatArray) -> None:
        for name, value in zip(self.scene.joint_names, joints, strict=True):
            self.robot.set_joint(name, float(value))
        self.robot.set_T_world_fbase(np.eye(4))
        self.robot.update_kinematics()
        anchor = self.scene.anchor_sole
        self.robot.set_T_world_frame(anchor, self.scene.sole_poses[anchor])
        self.robot.update_kinematics()

    def _errors(self, problem: _ChainProblem, target: FloatArray) -> tuple[float, float]:
        position = 0.0
        angle = 0.0
        for frame, pose in self.scene.sole_poses.items():
            actual = self.robot.get_T_world_frame(frame)
            position = max(position, float(np.linalg.norm(actual[:3, 3] - pose[:3, 3])))
            angle = max(angle, float(np.linalg.norm(actual[:3, :3] - pose[:3, :3])))
        contact = self.robot.get_T_world_frame(problem.contact)
        normal = self.scene.table_pose[:3, 2]
        position = max(position, abs(float(normal @ (contact[:3, 3] - target))))
        angle = max(angle, float(np.arccos(np.clip(contact[:3, 2] @ normal, -1.0, 1.0))))
        return position, angle

    def project(self, joints: FloatArray, chain: str, target_m: FloatArray) -> Projection:
        """Project a sample onto flush contact of ``chain`` near ``target_m``.

        Args:
            joints: Sample joint angles (rad), shape (nj,); locked joints are overwritten.
            chain: Name of the chain in contact.
            target_m: World position of the target spot on the table top, shape (3,).

        Returns:
            The projected posture; ``converged`` says whether the equalities hold to
            solver precision (feasibility is assessed separately).

        """
        scene = self.scene
        sample = np.where(scene.locked, scene.locked_values, joints)
        problem = self._problems[chain]
        self._set_joints(sample)
        problem.posture.set_joints(dict(zip(scene.joint_names, map(float, sample), strict=True)))
        problem.height.target_world = np.array(target_m, dtype=float)
        problem.spot.target_world = np.array(target_m, dtype=float)
        sampling = scene.sampling
        iterations = 0
        converged = False
        for hard, budget in ((False, sampling.soft_iterations), (True, sampling.hard_iterations)):
            problem.harden(hard)
            for _ in range(budget):
                try:
                    problem.solver.solve(True)
                except RuntimeError:
                    return Projection(self._joints(), False, iterations)
                self.robot.update_kinematics()
                iterations += 1
                position, angle = self._errors(problem, target_m)
                if hard and position < CONVERGED_M and angle < CONVERGED_RAD:
                    converged = True
                    break
                if not hard and position < 2e-2 and angle < 5e-2 and iterations >= 3:
                    break  # close enough: switch to the hard phase
        return Projection(self._joints(), converged, iterations)

    def _joints(self) -> FloatArray:
        return np.array([self.robot.get_joint(n) for n in self.scene.joint_names])
