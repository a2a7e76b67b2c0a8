"""Collision pairs that should not be checked, found by sampling (as MoveIt's setup assistant).

Three kinds of link pairs are disabled:

* adjacent: links joined by a joint, or through links that have no collision geometry;
* default: closer than the margin at the reference posture (meshes that touch at rest);
* always: closer than the margin in at least ``ALWAYS_FRACTION`` of uniformly sampled
  postures (locked joints at their values), e.g. two finger links once the fingers are
  locked.

MoveIt also disables pairs never seen colliding; posegen does not: a pair that random
postures miss can still meet near the table, and the check is what makes a route safe.
Pairs the SRDF already disables are not surveyed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from posegen.robot.additions import CollisionConfig, DisabledPair, PairReason
from posegen.robot.collision_geometry import add_self_pairs, link_of, robot_geometry
from posegen.robot.geometry import FloatArray

if TYPE_CHECKING:
    from posegen.robot.scene import Scene

ALWAYS_FRACTION = 0.95
DEFAULT_SAMPLES = 400


@dataclass(frozen=True)
class PairSurvey:
    """What sampling found about the checked link pairs."""

    disabled: tuple[DisabledPair, ...]  # in the order adjacent, default, always
    samples: int
    pairs_surveyed: int  # link pairs with collision geometry, before disabling
    frequency: dict[tuple[str, str], float]  # fraction of samples in which each link pair touched


def survey_pairs(
    model: pin.Model,
    geom: pin.GeometryModel,
    reference: FloatArray,
    sample: Callable[[np.random.Generator], FloatArray],
    margin_m: float,
    samples: int = DEFAULT_SAMPLES,
    seed: int = 0,
    rest_margin_m: float | None = None,
) -> PairSurvey:
    """Find the link pairs to disable.

    Args:
        model: Robot model.
        geom: Its collision geometry with the pairs to survey (e.g. all less the SRDF's).
        reference: Reference configuration, shape (nq,).
        sample: Draws a random configuration (nq,) from a generator.
        margin_m: Pairs closer than this count as touching.
        samples: Number of random configurations.
        seed: Seed of the generator.
        rest_margin_m: Pairs closer than this at the reference are "default" (None: ``margin_m``).

    """
    owner = link_of(model, geom)
    link_pairs = sorted({_key(owner[p.first], owner[p.second]) for p in geom.collisionPairs})
    column = {pair: k for k, pair in enumerate(link_pairs)}
    index = np.array([column[_key(owner[p.first], owner[p.second])] for p in geom.collisionPairs], dtype=int)
    data = model.createData()
    geom_data = pin.GeometryData(geom)
    for request in geom_data.collisionRequests:
        request.security_margin = margin_m

    def touching(q: FloatArray, margin: float = margin_m) -> FloatArray:
        for request in geom_data.collisionRequests:
            request.security_margin = margin
        pin.computeCollisions(model, data, geom, geom_data, q, False)
        hit = np.array([r.isCollision() for r in geom_data.collisionResults], dtype=bool)
        out = np.zeros(len(link_pairs), dtype=bool)
        np.logical_or.at(out, index, hit)
        return out

    reasons = _adjacent_pairs(model, geom, link_pairs)
    for k in np.flatnonzero(touching(reference, margin_m if rest_margin_m is None else rest_margin_m)):
        reasons.setdefault(link_pairs[k], PairReason.DEFAULT)
    rng = np.random.default_rng(seed)
    counts = np.zeros(len(link_pairs))
    for _ in range(samples):
        counts += touching(sample(rng))
    frequency = counts / max(samples, 1)
    for k in np.flatnonzero(frequency >= ALWAYS_FRACTION):
        reasons.setdefault(link_pairs[k], PairReason.ALWAYS)
    order = {PairReason.ADJACENT: 0, PairReason.DEFAULT: 1, PairReason.ALWAYS: 2}
    disabled = sorted(reasons.items(), key=lambda item: (order[item[1]], item[0]))
    return PairSurvey(
        disabled=tuple(DisabledPair(a, b, reason) for (a, b), reason in disabled),
        samples=samples,
        pairs_surveyed=len(link_pairs),
        frequency={pair: float(f) for pair, f in zip(link_pairs, frequency, strict=True)},
    )


def _key(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


def _adjacent_pairs(
    model: pin.Model, geom: pin.GeometryModel, link_pairs: list[tuple[str, str]]
) -> dict[tuple[str, str], PairReason]:
    """The link pairs joined by a joint, or through links without collision geometry."""
    joint_of = _geometry_joints(model, geom)
    with_geometry = set(joint_of.values())
    return {
        (a, b): PairReason.ADJACENT for a, b in link_pairs if _adjacent(model, joint_of[a], joint_of[b], with_geometry)
    }


def _geometry_joints(model: pin.Model, geom: pin.GeometryModel) -> dict[str, int]:
    """The joint that moves each link with collision geometry."""
    return {str(model.frames[o.parentFrame].name): int(o.parentJoint) for o in geom.geometryObjects}


def _adjacent(model: pin.Model, joint_a: int, joint_b: int, with_geometry: set[int]) -> bool:
    """Whether one link's joint is the other's nearest ancestor carrying geometry."""

    def parent_with_geometry(joint: int) -> int:
        joint = model.parents[joint]
        while joint > 0 and joint not in with_geometry:
            joint = model.parents[joint]
        return joint

    return joint_a == joint_b or parent_with_geometry(joint_a) == joint_b or parent_with_geometry(joint_b) == joint_a


def survey_scene_pairs(scene: Scene, samples: int = DEFAULT_SAMPLES, seed: int = 0) -> PairSurvey:
    """:func:`survey_pairs` for a scene's robot: its shapes, SRDF and locked joints, not its disabled pairs."""
    collision = CollisionConfig(shapes=scene.config.collision.shapes)
    geom = robot_geometry(scene.model, scene.urdf_xml, scene.files.package_dirs, collision, convex=True)
    add_self_pairs(scene.model, geom, scene.files.srdf_path(), collision)
    margin = scene.margins.joint_limit_rad

    def sample(rng: np.random.Generator) -> FloatArray:
        joints = rng.uniform(scene.lower + margin, scene.upper - margin)
        return scene.model_configuration(np.where(scene.locked, scene.locked_values, joints))

    reference = scene.model_configuration(np.where(scene.locked, scene.locked_values, scene.reference))
    return survey_pairs(scene.model, geom, reference, sample, scene.margins.collision_m, samples, seed)
