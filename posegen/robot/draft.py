"""A starting config for a humanoid, found from its description alone (``posegen robot init``).

Everything here is a heuristic a user then checks and edits; it reads structure, never
names, and records every guess with how to check it (:attr:`Draft.checks`):

* up axis, forward, soles, footprint and the reference posture:
  :mod:`posegen.robot.draft_stance` (no SRDF needed: a standing posture with the knees
  bent is found when none gives one);
* arms: the two longest chains of the upper body, up to where they branch into light
  parts only (fingers: under 1 % of the robot's mass), which are locked, like every joint
  off the legs and arms (head, neck). A gripper joint that ends a chain stays in it:
  lock it by hand;
* contact: :func:`posegen.robot.draft_geometry.hand_contact` (a flat face pointing down,
  else a point at the hand's tip);
* collision geometry for the links that move without any, and capsules for links whose
  collision geometry misses their centre of mass: :mod:`posegen.robot.draft_geometry`;
* table: in front of the shoulders, its top about 0.7 arm lengths below them;
* velocity limits the URDF lacks (0) or gives implausibly (> 20 rad/s);
* collision pairs to disable: :mod:`posegen.robot.collision_matrix`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot.additions import CollisionConfig, FrameConfig, Shape
from posegen.robot.collision_geometry import add_self_pairs, robot_geometry
from posegen.robot.collision_matrix import PairSurvey, survey_pairs
from posegen.robot.config import RobotSource
from posegen.robot.draft_geometry import (
    Geometry,
    HandContact,
    below_floor,
    hand_contact,
    link_of_joint,
    load_geometry,
    misplaced_geometry,
    missing_geometry,
    skeleton,
    vertices,
)
from posegen.robot.draft_limits import (
    JOINT_LIMIT_MARGIN_RAD,
    limits,
    near_limit,
    outside_limits,
    velocity_placeholders,
)
from posegen.robot.draft_source import DraftSource, load_draft_source
from posegen.robot.draft_stance import (
    ANKLE_HEIGHT,
    Sole,
    bend_legs,
    find_sole,
    find_up,
    floor_height,
    foot_box,
    foot_joint,
    sole_pose,
)
from posegen.robot.draft_table import arm_length, place_table
from posegen.robot.geometry import FloatArray, yaw_rotation

LIGHT_FRACTION = 0.01  # a branch lighter than this share of the robot's mass is an end effector's part
FLOOR_TOL_M = 0.02  # a branch whose lowest frame is this close to the lowest one reaches the floor
COLLISION_MARGIN_M = 0.005
REST_MARGIN_M = 0.01  # pairs this close at the reference touch at rest (meshes that nearly overlap there)
LIMIT_CLEARANCE_RAD = 0.05  # the reference keeps free joints this far inside their limits


@dataclass(frozen=True)
class Chain:
    """One arm, as found."""

    name: str  # "left" or "right"
    sole: str
    hand: str  # the link of the last arm joint
    gripper: FrameConfig  # a frame declared on the hand's link: the chain's end (calibration writes it back)
    joints: tuple[str, ...]  # shoulder to wrist
    contact: HandContact


@dataclass(frozen=True)
class Draft:
    """What ``posegen robot init`` found about a robot."""

    robot: str  # its example-robot-data name or URDF path
    source: RobotSource
    reference_posture: str  # the SRDF state used ("" when none)
    root_rpy_deg: tuple[float, float, float] | None  # root orientation at the reference (None: the state's)
    reference_joints: dict[str, float]  # rad, the legs bent by the draft (empty with an SRDF state)
    up_axis: str
    soles: tuple[Sole, Sole]  # left, right
    foot_x_m: tuple[float, float]
    foot_y_m: tuple[float, float]
    floor_contact: tuple[str, ...]
    chains: tuple[Chain, Chain]
    locked: dict[str, float]
    velocity_limits: dict[str, float]  # placeholders for the URDF's missing or implausible ones
    urdf_velocity: dict[str, float]  # what the URDF said for those
    shapes: tuple[Shape, ...]  # collision shapes added (missing or misplaced geometry)
    covered: dict[str, str]  # link -> what it gets for lacking collision geometry
    misplaced: dict[str, str]  # link -> why its collision geometry is replaced (CoM outside it, below the floor)
    table_center_m: tuple[float, float, float]
    table_size_m: tuple[float, float, float]
    spots_x_m: tuple[float, ...]
    spots_y_m: tuple[float, ...]
    reach_m: float
    survey: PairSurvey
    joint_limit_margin_rad: float = JOINT_LIMIT_MARGIN_RAD
    checks: tuple[str, ...] = field(default=())  # what was guessed, and how to check it
    notes: tuple[str, ...] = field(default=())

    @property
    def frames(self) -> tuple[FrameConfig, ...]:
        """The frames the config declares: soles the robot lacks, then the hands' contact frames."""
        soles = tuple(s.declared for s in self.soles if s.declared is not None)
        return soles + tuple(f for c in self.chains for f in (c.gripper, *c.contact.frames))


def draft_robot(
    robot: str, srdf: str | None = None, samples: int = 400, seed: int = 0, package_dirs: tuple[str, ...] = ()
) -> Draft:
    """Study a humanoid (an example-robot-data name or a URDF file) and draft its config.

    Raises:
        ConfigError: Unknown robot, a description that does not load, or a structure that
            is not two legs and two arms (the file and the element named).

    """
    src = load_draft_source(robot, srdf, package_dirs)
    model = src.model
    checks: list[str] = []
    notes: list[str] = []
    states: dict[str, FloatArray] = {}
    if src.files.srdf is not None:
        pin.loadReferenceConfigurations(model, str(src.files.srdf), False)
        states = {str(e.key()): np.array(e.data()) for e in model.referenceConfigurations}
    state = next(iter(states), "")
    outside = outside_limits(model, states[state]) if state else []
    if outside:
        checks.append(
            f"the SRDF's state '{state}' puts {', '.join(outside[:3])} outside the URDF's limits: "
            "the draft finds its own reference posture"
        )
        state = ""
    q = states[state].copy() if state else pin.neutral(model)
    children = {j: [c for c in range(2, model.njoints) if model.parents[c] == j] for j in range(model.njoints)}

    def subtree(j: int) -> list[int]:
        out = [j]
        for c in children[j]:
            out += subtree(c)
        return out

    def mass(joints: list[int]) -> float:
        return float(sum(model.inertias[j].mass for j in joints))

    root, up = find_up(model, q, children[1], subtree, src.label)
    q[:7] = pin.SE3ToXYZQUAT(root)
    if up != "+z":
        checks.append(f"the model's up axis is its root's {up} axis: the root is turned by stance.root_rpy_deg")
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    forward = _forward(root)
    heading = pin.SE3(yaw_rotation(float(np.arctan2(forward[1], forward[0]))), np.zeros(3))
    left = np.cross([0.0, 0.0, 1.0], forward)
    floor = min(float(data.oMi[j].translation[2]) for j in range(1, model.njoints))
    lowest = {b: min(float(data.oMi[j].translation[2]) for j in subtree(b)) for b in children[1]}
    legs = sorted((b for b in children[1] if lowest[b] < floor + FLOOR_TOL_M), key=lambda b: -_side(data, b, left))
    if len(legs) != 2:
        raise ConfigError(f"{src.label}: expected two legs reaching the floor, found {len(legs)}")
    geometry = load_geometry(model, src.text, src.files.package_dirs)
    feet = [foot_joint(model, b, children, subtree) for b in legs]
    leg_paths = [_path(model, b, f) for b, f in zip(legs, feet, strict=True)]
    leg_length = float(np.linalg.norm(data.oMi[legs[0]].translation - data.oMi[feet[0]].translation))
    soles = [
        find_sole(model, data, geometry, side, f, leg_length, heading)
        for side, f in zip(("left", "right"), feet, strict=True)
    ]
    for sole in soles:
        if not sole.from_geometry:
            checks.append(
                f"{sole.foot_link} has no geometry: the sole '{sole.frame}' (robot.frames) is put "
                f"{ANKLE_HEIGHT:.0%} of the leg's length below the ankle and the footprint (stance.foot_x_m, "
                "foot_y_m) is a guess from the leg's length: measure the foot"
            )
        elif sole.declared is not None:
            checks.append(f"sole '{sole.frame}' declared under the ankle, on the lowest vertices of {sole.foot_link}")
    reference_joints: dict[str, float] = {}
    limit_margin = JOINT_LIMIT_MARGIN_RAD
    if not state:
        sole_world = [sole_pose(model, data, s) for s in soles]
        bent = bend_legs(model, q, leg_paths, sole_world, forward, leg_length)
        if bent is None:
            checks.append("the legs could not be bent within their limits: the reference stands with straight legs")
            tight = [str(model.names[j]) for path in leg_paths for j in path if near_limit(model, q, j)]
            if tight:
                limit_margin = 0.0
                checks.append(
                    f"straight, {', '.join(tight)} sit at their limits (the URDF's limits forbid a bent stance): "
                    "margins.joint_limit_rad is 0; check the URDF's limits"
                )
        else:
            q = bent
            reference_joints = {
                str(model.names[j]): round(float(q[model.joints[j].idx_q]), 4) for path in leg_paths for j in path
            }
            checks.append(
                "no SRDF posture: the reference (stance.reference_joints) bends the knees, soles flat, CoM over the "
                "feet; check it with `posegen view` on a pool"
            )
        pin.framesForwardKinematics(model, data, q)
    paths: list[list[int]] = []
    total = mass(list(range(1, model.njoints)))
    for branch in children[1]:
        if branch not in legs:
            _arm_paths(branch, [], children, subtree, mass, total, paths)
    paths.sort(key=len, reverse=True)
    if len(paths) < 2 or len(paths[1]) < 3:
        found = ", ".join(f"'{model.names[p[-1]]}'" for p in paths) or "none"
        upper = ", ".join(f"'{model.names[b]}'" for b in children[1] if b not in legs) or "none"
        raise ConfigError(
            f"{src.label}: no two arms: the upper body (from joint {upper}) has the chains ending at {found}"
        )
    arms = sorted(paths[:2], key=lambda p: -float(data.oMi[p[-1]].translation @ left))
    kept = {j for path in leg_paths for j in path} | {j for p in arms for j in p}
    locked = {
        str(model.names[j]): float(np.clip(q[model.joints[j].idx_q], *limits(model, j)))
        for j in range(2, model.njoints)
        if model.joints[j].nq == 1 and j not in kept
    }
    for name, value in locked.items():
        q[model.joints[model.getJointId(name)].idx_q] = value
    legs_joints = {j for path in leg_paths for j in path}
    for j in sorted(kept - legs_joints):  # free joints off the legs: clear of their limits
        low, high = limits(model, j)
        i = model.joints[j].idx_q
        inside = float(np.clip(q[i], low + LIMIT_CLEARANCE_RAD, high - LIMIT_CLEARANCE_RAD))
        if low + LIMIT_CLEARANCE_RAD <= high - LIMIT_CLEARANCE_RAD and inside != q[i]:
            q[i] = inside
            reference_joints[str(model.names[j])] = round(inside, 4)
    pin.framesForwardKinematics(model, data, q)
    bare_feet = [s for s in soles if not s.from_geometry]
    covered, added = missing_geometry(
        model, geometry, [j for j in range(1, model.njoints) if j not in {s.foot_joint for s in bare_feet}]
    )
    for sole in bare_feet:
        covered[sole.foot_link] = "a box over the guessed footprint"
        added += (foot_box(model, data, sole),)
    misplaced = misplaced_geometry(model, geometry)
    feet_joints = set(feet) | {j for f in feet for j in subtree(f)}
    misplaced.update(below_floor(model, data, geometry, feet_joints, floor_height(model, data, soles)))
    shapes = added + tuple(s for link in misplaced for s in skeleton(model, link))
    if covered:
        checks.append(
            f"{len(covered)} moving links have no collision geometry: given "
            + ", ".join(sorted(set(covered.values())))
            + " (robot.collision.shapes)"
        )
    if misplaced:
        checks.append(
            f"{len(misplaced)} links' collision geometry contradicts the kinematics ("
            + "; ".join(f"{link}: {why}" for link, why in misplaced.items())
            + "): replaced by capsules along the joints"
        )
    shared = set(arms[0]) & set(arms[1])  # the torso
    full_geometry = _with_shapes(geometry, model, src, shapes)
    chains = []
    for name, sole, path in zip(("left", "right"), soles, arms, strict=True):
        hand = link_of_joint(model, path[-1])
        wrist = data.oMi[path[-1]].translation
        elbow = next((data.oMi[j].translation for j in reversed(path) if _apart(data.oMi[j].translation, wrist)), wrist)
        fingers = set(subtree(path[-1])) - {path[-1]}
        contact = hand_contact(model, data, full_geometry, name, hand, wrist - elbow, fingers)
        joints = tuple(str(model.names[j]) for j in path if j not in shared)
        gripper = FrameConfig(f"{name}_gripper", hand, (0.0, 0.0, 0.0))
        chains.append(Chain(name, sole.frame, hand, gripper, joints, contact))
        checks.append(f"{name} hand ({hand}): {contact.how}; edit robot.frames to where it really touches")
    speeds, urdf_speed = velocity_placeholders(model, kept)
    if speeds:
        checks.append(f"{len(speeds)} joints have no plausible URDF velocity limit: placeholders of 1 rad/s")
    shoulder = data.oMi[model.getJointId(chains[0].joints[0])].translation
    reach = arm_length(model, data, chains[0].joints, chains[0].hand, chains[0].contact.frames)
    floor_z = floor_height(model, data, soles)
    body = vertices(model, data, full_geometry.collision, set(range(1, model.njoints)), heading)  # (k, 3)
    body[:, 2] -= floor_z
    table = place_table(heading, shoulder, reach, floor_z, body)
    checks.append(f"the table is a guess from the arm's reach ({reach:.2f} m): put it where yours is")
    survey = _survey(model, src, shapes, q, locked, samples, seed)
    foot_x = (max(s.x_m[0] for s in soles), min(s.x_m[1] for s in soles))
    foot_y = (max(s.y_m[0] for s in soles), min(s.y_m[1] for s in soles))
    rpy = tuple(round(float(v), 3) + 0.0 for v in np.rad2deg(pin.rpy.matrixToRpy(root.rotation)))
    return Draft(
        robot=robot,
        source=src.source,
        reference_posture=state,
        root_rpy_deg=None if up == "+z" else (rpy[0], rpy[1], rpy[2]),
        reference_joints=reference_joints,
        up_axis=up,
        soles=(soles[0], soles[1]),
        foot_x_m=foot_x,
        foot_y_m=foot_y,
        floor_contact=tuple(dict.fromkeys(s.foot_link for s in soles)),
        chains=(chains[0], chains[1]),
        locked=locked,
        velocity_limits=speeds,
        urdf_velocity=urdf_speed,
        shapes=shapes,
        covered=covered,
        misplaced=misplaced,
        table_center_m=table[0],
        table_size_m=table[1],
        spots_x_m=table[2],
        spots_y_m=table[3],
        reach_m=reach,
        survey=survey,
        joint_limit_margin_rad=limit_margin,
        checks=tuple(checks),
        notes=tuple(notes),
    )


def _forward(root: pin.SE3) -> FloatArray:
    """The robot's forward direction in the world: its root's x axis, levelled. Shape (3,)."""
    for column in (0, 2, 1):
        v = root.rotation[:, column].copy()
        v[2] = 0.0
        if np.linalg.norm(v) > 0.5:
            return np.asarray(v / np.linalg.norm(v))
    return np.array([1.0, 0.0, 0.0])


def _apart(a: FloatArray, b: FloatArray) -> bool:
    return bool(np.linalg.norm(a - b) > 0.01)


def _side(data: pin.Data, joint: int, left: FloatArray) -> float:
    return float(data.oMi[joint].translation @ left)


def _path(model: pin.Model, first: int, last: int) -> list[int]:
    """Joints from ``first`` down to ``last`` (its descendant)."""
    out = [last]
    while out[-1] != first:
        out.append(model.parents[out[-1]])
    return out[::-1]


def _with_shapes(geometry: Geometry, model: pin.Model, src: DraftSource, shapes: tuple[Shape, ...]) -> Geometry:
    """The geometry with the added shapes as collision geometry (what the hands are read from)."""
    if not shapes:
        return geometry
    collision = robot_geometry(model, src.text, src.files.package_dirs, CollisionConfig(shapes=shapes), convex=False)
    return Geometry(collision=collision, visual=geometry.visual)


def _survey(
    model: pin.Model,
    src: DraftSource,
    shapes: tuple[Shape, ...],
    reference: FloatArray,
    locked: dict[str, float],
    samples: int,
    seed: int,
) -> PairSurvey:
    geom = robot_geometry(model, src.text, src.files.package_dirs, CollisionConfig(shapes=shapes), convex=True)
    add_self_pairs(model, geom, src.files.srdf_path(), CollisionConfig())

    def sample(rng: np.random.Generator) -> FloatArray:
        q = pin.neutral(model)
        for j in range(2, model.njoints):
            if model.joints[j].nq == 1:
                q[model.joints[j].idx_q] = rng.uniform(*limits(model, j))
        for name, value in locked.items():
            q[model.joints[model.getJointId(name)].idx_q] = value
        return np.asarray(q)

    return survey_pairs(model, geom, reference, sample, COLLISION_MARGIN_M, samples, seed, REST_MARGIN_M)


def _arm_paths(joint, path, children, subtree, mass, total, out) -> None:  # type: ignore[no-untyped-def]
    """Chains of the upper body, through single joints and at a branching into its heavy branches.

    A branching into light parts alone (fingers) ends the chain.
    """
    path = [*path, joint]
    below = children[joint]
    heavy = below if len(below) == 1 else [c for c in below if mass(subtree(c)) >= LIGHT_FRACTION * total]
    if not heavy:
        out.append(path)
    for child in heavy:
        _arm_paths(child, path, children, subtree, mass, total, out)
