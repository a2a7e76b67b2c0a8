"""Gauss-Newton projection of a joint sample onto balanced table contact (placo).

The problem: both soles at their fixed poses, the CoM ground projection inside the
support polygon with margin, the joint torques that hold the posture within the effort
limits (with the hand unloaded and pressing the contact force: linearised at every
iteration, :mod:`posegen.robot.statics`, for the joints near their limit), one chain's
contact on the table near a target spot (flush:
the contact frame's height, roll, pitch zero, yaw free; point: the tip's centre at its
radius above the table, its tilt only weakly pulled upright and checked against a cone
afterwards), joint limits shrunk by a margin, and the sample itself as a weak posture
task (what keeps the pool diverse).

Solving from a random sample with every task hard is infeasible at the first step, so
the solver runs a soft phase, then a hard phase that makes the equality tasks exact.
For a flush contact the sample's pull acts in the soft phase only: the hard phase is a
Gauss-Newton projection of least change onto the equalities, which converges
quadratically. Kept in the hard phase, that pull fought the equalities (each step's move
toward the sample bent off them again): the error only halved per iteration, and a third
of the samples ran out of the hard phase's budget (TALOS, 1500 postures: 5449 samples
drawn, against 4348 with the pull in the soft phase only). A point contact keeps both
pulls in both phases: its tilt is free, and its pull upright, balanced by the sample's,
gives the varied tilts that identify the tip's offset (without the sample's pull in the
hard phase every tilt went upright).

A converged posture whose bodies came closer than the collision margin (TALOS: the two
thighs, in 95 % of such samples, as the legs close on their soles) is moved apart by
:meth:`Projector.separate`: more hard-phase steps with the pairs within reach linearised
(:mod:`posegen.robot.separation`), unless they are more than ``SEPARATION_DEPTH_M`` into
each other. TALOS, 1500 postures: 2005 samples drawn instead of 4348, and a pool whose
selection is as informative or more (IROC's O1 +2.0 to +3.0 %, seeds 0-2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import placo

from posegen.robot.description import kinematic_urdf
from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene
from posegen.robot.separation import Separation
from posegen.robot.statics import Statics

FOOT_WEIGHT = 100.0
CONTACT_WEIGHT = 100.0
TILT_WEIGHT = 3e-3  # a point contact's pull toward upright. TALOS on one fingertip, 30 deg cone:
# 3e-3 gave tilts of 3-23 deg (varied: what identifies the tip's offset) at 17 % acceptance;
# 1e-2 kept them under 11 deg; 1e-3 let a third of the samples leave the cone.
SPOT_WEIGHT = 1.0
POSTURE_WEIGHT = 1e-2  # the soft phase's pull toward the sample. TALOS, 1500 postures, 10 seeds: 1e-3 and 3e-3
# gave a lower mean O1 and O1*; 3e-2 accepted 19 % of the samples against 35 %
TILTED_POSTURE_WEIGHT = 1e-3  # a point contact's pull toward the sample, in both phases: TILT_WEIGHT's counterweight
REGULARIZATION = 1e-4
CONVERGED_M = 2e-6  # equality errors below this end the hard phase
CONVERGED_RAD = 2e-5
COM_BUFFER_M = 1e-3  # solved inside the configured margin, so the re-check has slack
LIMIT_BUFFER_RAD = 1e-4
PRESSED_BUFFER_M = 1e-3  # the pressed centre of pressure solved this much inside its margin
TORQUE_ACTIVE = 0.85  # a torque above this fraction of its allowed value is constrained (0.7: slower, same postures)
TORQUE_REFRESH = 4  # the torques' derivative is recomputed after this many uses
TORQUE_BUFFER = 0.005  # solved this fraction of the effort limit inside the allowed ratio
TORQUE_WEIGHT = 1.0  # the torque rows in the soft phase (N m)
CYCLE_TOLERANCE = 1e-2  # relative: errors repeating this closely with period 1 or 2 never converge
SEPARATION_BUFFER_M = 2e-3  # a colliding pair is pushed this far beyond the collision margin ...
SEPARATION_REACH_M = 3e-3  # ... and so is every pair within this of that distance (they move together)
SEPARATION_ITERATIONS = 10  # Gauss-Newton steps to separate a converged posture's colliding pairs
SEPARATION_WATCH_M = 0.006  # the pairs this much beyond the margin before separating are the ones watched
SEPARATION_DEPTH_M = 5e-3  # bodies deeper into each other than this are another posture: not separated.
# TALOS: 88 % of its colliding samples are within it (the thighs touching); JVRC: 20 % (a shoulder in the table)


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
        config = scene.chain(chain)
        self.kind = config.contact_kind
        contact = config.frame(self.kind)
        table_normal = scene.table_pose[:3, 2].copy()
        self.height = self.solver.add_position_task(contact, scene.table_pose[:3, 3].copy())
        self.height.mask.set_axises("z", "world")
        self.spot = self.solver.add_position_task(contact, scene.table_pose[:3, 3].copy())
        self.spot.mask.set_axises("xy", "world")
        self.spot.configure(f"{chain}_spot", "soft", SPOT_WEIGHT)
        self.flush = self.solver.add_axisalign_task(contact, np.array([0.0, 0.0, 1.0]), table_normal)
        if not self.kind.aligned:  # a weak pull toward the cone's axis; the sample keeps the tilts varied
            self.flush.configure("tilt", "soft", TILT_WEIGHT)
        self.lift_m = self.kind.lift_m(config)  # e.g. a point contact's tip centre
        com = self.solver.add_com_polygon_constraint(scene.support_polygon, scene.margins.com_m + COM_BUFFER_M)
        com.configure("com", "hard", 1.0)
        self.pressed = self.solver.add_com_polygon_constraint(scene.support_polygon, 0.0)  # set per iteration
        self.pressed.configure("pressed", "hard", 1.0)
        self.torque = self.solver.add_joint_space_half_spaces_constraint(
            np.zeros((1, robot.model.nq)), np.ones(1)
        )  # A q <= b, rows set at every iteration (see Projector._limit_torques)
        self.posture = self.solver.add_joints_task()
        self.posture.configure("posture", "soft", POSTURE_WEIGHT if self.kind.aligned else TILTED_POSTURE_WEIGHT)
        self.solver.add_regularization_task(REGULARIZATION)
        self.contact = contact

    def harden(self, hard: bool) -> None:
        mode = "hard" if hard else "soft"
        self.torque.configure("torque", mode, TORQUE_WEIGHT)
        for k, task in enumerate(self.feet):
            task.configure(f"foot_{k}", mode, FOOT_WEIGHT)
        self.height.configure("height", mode, CONTACT_WEIGHT)
        if self.kind.aligned:
            self.flush.configure("flush", mode, CONTACT_WEIGHT)
            self.posture.configure("posture", "soft", 0.0 if hard else POSTURE_WEIGHT)


class Projector:
    """Projects joint samples onto balanced contact, one chain at a time."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.robot = placo.RobotWrapper("", placo.Flags.ignore_collisions, kinematic_urdf(scene.urdf_xml))
        lower, upper = scene.planning_limits(LIMIT_BUFFER_RAD)  # (nj,) rad
        for i, name in enumerate(scene.joint_names):
            if not scene.locked[i]:
                self.robot.set_joint_limits(name, lower[i], upper[i])
        self._problems = {c.name: _ChainProblem(self.robot, scene, c.name) for c in scene.chains}
        self._soles = [(frame, pose[:3, 3].tolist(), pose[:3, :3].tolist()) for frame, pose in scene.sole_poses.items()]
        self._normal = scene.table_pose[:3, 2].tolist()
        self._statics = Statics(scene)
        weight = float(np.linalg.norm(scene.model.gravity.linear)) * sum(i.mass for i in scene.model.inertias)
        self._pressing_share = scene.route.contact_force_n / weight  # of the weight the table carries (vertical)
        self._pressed_polygon = (1.0 - self._pressing_share) * scene.support_polygon  # (n, 2) m, (1 - a) P
        for problem in self._problems.values():
            problem.pressed.margin = (1.0 - self._pressing_share) * (scene.margins.zmp_m + PRESSED_BUFFER_M)
        allowed = (scene.margins.effort_ratio - TORQUE_BUFFER) * scene.effort_limit  # (nj,) N m, nan: no limit
        self._allowed = np.where(scene.locked, np.nan, allowed)  # a locked joint does not move here
        self._nq = scene.model.nq
        self._derivative: tuple[FloatArray, int] | None = None  # (d torque / d joints, times used)
        self._joint_q = scene.velocity_indices() + 1  # (nj,) 1-dof joints: q index = v index + 1 (free flyer 7 vs 6)

    def _set_joints(self, joints: FloatArray) -> None:
        for name, value in zip(self.scene.joint_names, joints, strict=True):
            self.robot.set_joint(name, float(value))
        self.robot.set_T_world_fbase(np.eye(4))
        self.robot.update_kinematics()
        anchor = self.scene.anchor_sole
        self.robot.set_T_world_frame(anchor, self.scene.sole_poses[anchor])
        self.robot.update_kinematics()

    def _errors(self, problem: _ChainProblem, target_m: list[float], contact: list[list[float]]) -> tuple[float, float]:
        """Largest equality errors: soles' position (m) and rotation (Frobenius), contact height (m) and tilt (rad).

        ``contact``: the contact frame's (4, 4) world placement at the kinematics in the robot.

        Plain floats on purpose: numpy's per-call overhead on 3-vectors cost more than the
        QP step it checks (172 vs 72-110 us per iteration); the sums are written out, in the
        order a generator's sum takes them (7 us a call instead of 12).
        """
        position = 0.0
        angle = 0.0
        for frame, (o0, o1, o2), ((a0, a1, a2), (b0, b1, b2), (c0, c1, c2)) in self._soles:
            r0, r1, r2, _ = self.robot.get_T_world_frame(frame).tolist()
            position = max(position, math.sqrt((r0[3] - o0) ** 2 + (r1[3] - o1) ** 2 + (r2[3] - o2) ** 2))
            squares = (  # summed left to right, row by row
                (r0[0] - a0) ** 2 + (r0[1] - a1) ** 2 + (r0[2] - a2) ** 2
                + (r1[0] - b0) ** 2 + (r1[1] - b1) ** 2 + (r1[2] - b2) ** 2
                + (r2[0] - c0) ** 2 + (r2[1] - c1) ** 2 + (r2[2] - c2) ** 2
            )  # fmt: skip
            angle = max(angle, math.sqrt(squares))
        n0, n1, n2 = self._normal
        k0, k1, k2, _ = contact
        height = n0 * (k0[3] - target_m[0]) + n1 * (k1[3] - target_m[1]) + n2 * (k2[3] - target_m[2])
        position = max(position, abs(height))
        if not problem.kind.aligned:
            return position, angle  # e.g. a point contact's tilt is free (its cone is checked afterwards)
        cosine = k0[2] * n0 + k1[2] * n1 + k2[2] * n2
        return position, max(angle, math.acos(min(1.0, max(-1.0, cosine))))

    def project(self, joints: FloatArray, chain: str, target_m: FloatArray) -> Projection:
        """Project a sample onto contact of ``chain`` (its planned kind) near ``target_m``.

        Args:
            joints: Sample joint angles (rad), shape (nj,); locked joints are overwritten.
            chain: Name of the chain in contact.
            target_m: World position of the target spot on the table top, shape (3,); a
                point contact's frame goes its tip radius above it.

        Returns:
            The projected posture; ``converged`` says whether the equalities hold to
            solver precision (feasibility is assessed separately).

        """
        scene = self.scene
        sample = np.where(scene.locked, scene.locked_values, joints)
        problem = self._problems[chain]
        target_m = np.asarray(target_m, dtype=float) + problem.lift_m * scene.table_pose[:3, 2]
        self._set_joints(sample)
        problem.posture.set_joints(dict(zip(scene.joint_names, map(float, sample), strict=True)))
        problem.height.target_world = np.array(target_m, dtype=float)
        problem.spot.target_world = np.array(target_m, dtype=float)
        target = [float(v) for v in target_m]
        contact = self.robot.get_T_world_frame(problem.contact).tolist()  # (4, 4) the contact frame, world
        sampling = scene.sampling
        iterations = 0
        for hard, budget in ((False, sampling.soft_iterations), (True, sampling.hard_iterations)):
            problem.harden(hard)
            if not hard:
                self._release_torques(problem)
            errors: list[tuple[float, float]] = []
            for _ in range(budget):
                if hard:
                    self._limit_torques(problem, chain)
                self._press(problem, contact)
                try:
                    problem.solver.solve(True)
                except RuntimeError:
                    return Projection(self._joints(), False, iterations)
                self.robot.update_kinematics()
                iterations += 1
                contact = self.robot.get_T_world_frame(problem.contact).tolist()  # (4, 4) read once per iteration
                position, angle = self._errors(problem, target, contact)
                if hard and position < CONVERGED_M and angle < CONVERGED_RAD:
                    return Projection(self._joints(), True, iterations)
                if not hard and position < 2e-2 and angle < 5e-2 and iterations >= 3:
                    break  # close enough: switch to the hard phase
                errors.append((position, angle))
                if _cycling(errors):
                    return Projection(self._joints(), False, iterations)
        return Projection(self._joints(), False, iterations)

    def separate(self, joints: FloatArray, chain: str, target_m: FloatArray, separation: Separation) -> Projection:
        """Move a converged posture whose collision pairs came closer than the margin apart, its equalities kept.

        Hard-phase steps as :meth:`project`'s, each with every pair within reach linearised
        (:class:`Separation`) and held ``SEPARATION_BUFFER_M`` beyond ``margins.collision_m``,
        until the equalities hold and no pair is closer than the margin plus half that buffer.
        Bodies more than ``SEPARATION_DEPTH_M`` into each other are left as they are (not converged).
        The sample's pulls are those of the last :meth:`project` (call it on the same sample first).

        Args:
            joints: The converged posture (rad), shape (nj,).
            chain: Name of the chain in contact.
            target_m: The target spot given to :meth:`project`, shape (3,).
            separation: The robot's collision pairs, linearised.

        Returns:
            The separated posture; ``converged``: equalities and distances reached. The
            caller checks collisions again (a pair out of reach may have come closer).

        Example:
            >>> found = projector.project(sample, "left", spot)
            >>> q = scene.configuration(found.joints)
            >>> if found.converged and checker.closest_unless_within(q, "left", margin) is None:
            ...     found = projector.separate(found.joints, "left", spot, separation)

        """
        problem = self._problems[chain]
        margin = self.scene.margins.collision_m
        target = [float(v) for v in np.asarray(target_m, dtype=float) + problem.lift_m * self.scene.table_pose[:3, 2]]
        self._set_joints(np.where(self.scene.locked, self.scene.locked_values, joints))
        problem.harden(True)
        self._derivative = None
        contact = self.robot.get_T_world_frame(problem.contact).tolist()  # (4, 4) the contact frame, world
        held = True  # the equalities hold (the posture given converged)
        reach = margin + SEPARATION_BUFFER_M + SEPARATION_REACH_M
        watched: tuple[int, ...] | None = None  # the pairs looked at while the posture moves (set at the start)
        for iteration in range(SEPARATION_ITERATIONS):
            now = self._joints()
            if watched is None:
                rows = separation.rows(now, chain, margin + SEPARATION_WATCH_M)
                if np.any(rows.distances_m < -SEPARATION_DEPTH_M):
                    return Projection(now, False, 0)
                watched, rows = rows.pairs, rows.within(reach)
            else:
                rows = separation.rows(now, chain, reach, watched)
            if held and np.all(rows.distances_m >= margin + SEPARATION_BUFFER_M / 2):
                return Projection(now, True, iteration)
            self._limit_torques(problem, chain, rows.half_spaces(margin + SEPARATION_BUFFER_M))
            self._press(problem, contact)
            try:
                problem.solver.solve(True)
            except RuntimeError:
                break
            self.robot.update_kinematics()
            contact = self.robot.get_T_world_frame(problem.contact).tolist()
            position, angle = self._errors(problem, target, contact)
            held = position < CONVERGED_M and angle < CONVERGED_RAD
        return Projection(self._joints(), False, SEPARATION_ITERATIONS)

    def _press(self, problem: _ChainProblem, contact: list[list[float]]) -> None:
        """The CoM's polygon that keeps the centre of pressure inside by ``margins.zmp_m`` with the hand pressing.

        A vertical force ``F`` on the hand at ``h`` moves the soles' centre of pressure
        from the CoM ``c`` to ``(c - a h) / (1 - a)``, ``a = F / (m g)``: it is inside the
        polygon ``P`` by ``d`` exactly when ``c`` is inside ``a h + (1 - a) P`` by ``(1 - a) d``
        (the margin is set once, in :class:`Projector`). ``contact``: the hand's (4, 4) world placement.
        """
        hand = np.array([contact[0][3], contact[1][3]])  # (2,) m
        problem.pressed.polygon = self._pressing_share * hand[None, :] + self._pressed_polygon

    def _release_torques(self, problem: _ChainProblem) -> None:
        """No torque rows (the soft phase): ``0 q <= 1``; the linearisation restarts in the hard phase."""
        self._derivative = None
        problem.torque.A, problem.torque.b = np.zeros((1, self._nq)), np.ones(1)

    def _limit_torques(
        self, problem: _ChainProblem, chain: str, extra: tuple[FloatArray, FloatArray] | None = None
    ) -> None:
        """Linearise the holding torques near their limits (unloaded and pressing) as rows of ``A q <= b``.

        ``extra``: more rows ``(A, b)`` on the joints, (m, nj) and (m,), e.g. :meth:`SeparationRows.half_spaces`.

        The torques are exact at every iteration; their derivative (that of the unloaded
        robot: 30 N on the hand changes it little) is computed when a joint first comes
        near its limit and refreshed every ``TORQUE_REFRESH`` iterations. The rows hold
        ``torque(q) + D (q' - q) <= allowed``: whatever ``D``, a fixed point keeps the limit.
        ``allowed`` is the effort margin less the torque's spread over the CoM's uncertainty.
        """
        joints = self._joints()
        pair = self._statics.torque_pair(joints, chain, self.scene.route.contact_force_n)
        allowed = self._allowed - pair.spread  # (nj,) N m, room for the CoM's uncertainty
        rows: list[FloatArray] = []
        bounds: list[float] = []
        for torques in (pair.unloaded, pair.pressing):
            with np.errstate(invalid="ignore"):
                active = np.flatnonzero(np.abs(torques) > TORQUE_ACTIVE * allowed)  # nan: never
            if not len(active):
                continue
            derivative = self._torque_derivative(joints)
            for j in active:
                sign = float(np.sign(torques[j]))
                row = np.zeros(self._nq)
                row[self._joint_q] = sign * derivative[j]
                rows.append(row)
                bounds.append(float(allowed[j] - sign * torques[j] + sign * derivative[j] @ joints))
        for row_joints, bound in zip(*(extra or ((), ())), strict=True):
            row = np.zeros(self._nq)
            row[self._joint_q] = row_joints
            rows.append(row)
            bounds.append(float(bound))
        if rows:
            problem.torque.A, problem.torque.b = np.array(rows), np.array(bounds)
        else:
            problem.torque.A, problem.torque.b = np.zeros((1, self._nq)), np.ones(1)

    def _torque_derivative(self, joints: FloatArray) -> FloatArray:
        """(nj, nj) the unloaded holding torques' derivative, refreshed every ``TORQUE_REFRESH`` calls."""
        if self._derivative is None or self._derivative[1] >= TORQUE_REFRESH:
            self._derivative = (self._statics.linear(joints, None, 0.0).jacobian, 0)
        jacobian, uses = self._derivative
        self._derivative = (jacobian, uses + 1)
        return jacobian

    def _joints(self) -> FloatArray:
        """(nj,) rad the solver's joint angles, in the scene's order (one-value joints: q index = v index + 1)."""
        return np.array(self.robot.state.q[self._joint_q], dtype=float)


def _cycling(errors: list[tuple[float, float]]) -> bool:
    """Whether the last errors repeat with period 1 or 2 (within CYCLE_TOLERANCE): stuck for good.

    On 1000 TALOS samples this stopped 92 of the 346 projections that never converge,
    saving 8.6 % of all iterations, and no projection that converges.
    """
    for period in (1, 2):
        if len(errors) <= 2 * period:
            continue
        (p0, a0), (p1, a1), (p2, _) = errors[-1], errors[-1 - period], errors[-1 - 2 * period]
        bound = CYCLE_TOLERANCE * p0
        if abs(p0 - p1) <= bound and abs(p1 - p2) <= bound and abs(a0 - a1) <= CYCLE_TOLERANCE * a0:
            return True
    return False
