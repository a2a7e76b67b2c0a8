"""One random sample turned into a feasible contact posture, or the reason it was not.

Sample ``i`` of seed ``s`` draws from its own generator ``default_rng([s, i])``, so a
sample's outcome depends on nothing but (config, seed, i): not on the order samples are
processed in, nor on the number of workers.
"""

from __future__ import annotations

import collections
import enum
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.io import Posture
from posegen.robot import CollisionChecker, FloatArray, Invariant, Projector, Scene, Separation, Spot, Statics, assess


class Rejection(str, enum.Enum):
    """Why a sample was dropped."""

    NOT_CONVERGED = "not_converged"  # the projection did not reach the equalities
    SPOT_MISSED = "spot_missed"  # contact landed too far from its target spot
    SOLE = "sole"
    CONTACT = "contact"
    COM = "com"
    JOINT_LIMITS = "joint_limits"
    COLLISION = "collision"
    ZMP = "zmp"
    TORQUE = "torque"


_INVARIANT_REJECTION = {
    Invariant.SOLE: Rejection.SOLE,
    Invariant.CONTACT: Rejection.CONTACT,
    Invariant.COM: Rejection.COM,
    Invariant.JOINT_LIMITS: Rejection.JOINT_LIMITS,
    Invariant.COLLISION: Rejection.COLLISION,
    Invariant.ZMP: Rejection.ZMP,
    Invariant.TORQUE: Rejection.TORQUE,
}


def rejection_counts(outcomes: Sequence[Posture | Rejection]) -> dict[str, int]:
    """Count rejections by reason, in the order of :class:`Rejection`."""
    counts = collections.Counter(o.value for o in outcomes if isinstance(o, Rejection))
    return {r.value: counts[r.value] for r in Rejection if counts[r.value]}


@dataclass(frozen=True)
class Draw:
    """What sample ``i`` asks for."""

    joints: FloatArray  # (nj,) rad, uniform within the margin-shrunk limits
    chain: str
    spot: Spot


def draw(scene: Scene, seed: int, index: int) -> Draw:
    """The random sample number ``index`` of ``seed``.

    Every joint is drawn uniformly within its limits (less the margin), then the joints
    idle at this contact (another arm, a head: :meth:`posegen.robot.Scene.idle_joints`)
    are set to the reference posture: they carry no information on the chain, and an
    arm held out at random costs balance, torque and collisions, here and on the route.
    """
    rng = np.random.default_rng([seed, index])
    joints = rng.uniform(*scene.planning_limits())
    chains = scene.chains
    chain = chains[int(rng.integers(len(chains)))].name
    spots = [s for s in scene.spots if chain in s.chains]
    spot = spots[int(rng.integers(len(spots)))]
    idle = scene.idle_joints(chain)
    joints[idle] = scene.reference[idle]
    return Draw(joints=joints, chain=chain, spot=spot)


class PostureSampler:
    """Projects and checks samples (one per process: it owns solver state)."""

    def __init__(self, scene: Scene, seed: int) -> None:
        self.scene = scene
        self.seed = seed
        self.projector = Projector(scene)
        self.checker = CollisionChecker(scene, convex=True)
        self.separation = Separation(scene, self.checker)
        self.statics = Statics(scene)
        self.data = scene.model.createData()  # the assessments' kinematics

    def evaluate(self, index: int) -> Posture | Rejection:
        """Turn sample ``index`` into a feasible posture, or say why it is not one."""
        scene = self.scene
        sample = draw(scene, self.seed, index)
        spot = scene.spot_world(sample.spot)  # (3,) m, world
        result = self.projector.project(sample.joints, sample.chain, spot)
        if not result.converged:
            return Rejection.NOT_CONVERGED
        # collisions first: 5 in 10 converged TALOS samples collide (the thighs, mostly), the other invariants
        # fail 1 in 5000; a colliding posture is moved apart (Projector.separate) and checked again, and the
        # assessment (~0.6 ms) is spent on collision-free postures only
        closest = self.checker.closest_unless_within(
            scene.configuration(result.joints), sample.chain, scene.margins.collision_m
        )
        if closest is None:
            result = self.projector.separate(result.joints, sample.chain, spot, self.separation)
            if not result.converged:
                return Rejection.COLLISION
            closest = self.checker.closest_unless_within(
                scene.configuration(result.joints), sample.chain, scene.margins.collision_m
            )
            if closest is None:
                return Rejection.COLLISION
        found = assess(scene, None, result.joints, sample.chain, self.statics, self.data)
        violations = found.violations(scene)
        if violations:
            return _INVARIANT_REJECTION[next(k for k in Invariant if k in violations)]
        offset = np.subtract(found.contact_xy_table_m, sample.spot.xy_table_m)
        if float(np.linalg.norm(offset)) > scene.sampling.spot_tolerance_m:
            return Rejection.SPOT_MISSED
        return Posture(
            sample=index,
            chain=sample.chain,
            spot=sample.spot.name,
            joints=tuple(float(v) for v in result.joints),
            contact_xy_m=found.contact_xy_table_m,
            contact_yaw_rad=found.contact_yaw_rad,
            min_distance_m=closest.distance_m,
            com_margin_m=found.com_margin_m,
        )
