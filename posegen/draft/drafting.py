"""A starting config for a humanoid, found from its description alone (``posegen robot init``).

Everything here is a heuristic a user then checks and edits; it reads structure, never
names, and records every guess with how to check it (:attr:`Draft.checks`):

* up axis, forward, soles, footprint and the reference posture:
  :mod:`posegen.draft.stance` (no SRDF needed: a standing posture with the knees
  bent is found when none gives one), in the steps of :mod:`posegen.draft.body`;
* arms: the two longest chains of the upper body, up to where they branch into light
  parts only (fingers: under 1 % of the robot's mass), which are locked, like every joint
  off the legs and arms (head, neck) (:mod:`posegen.draft.body`). A joint that ends a
  chain stays in it, but for one too narrow to keep the margin from both limits (a
  gripper's slide finger), which is locked too;
* contact: :func:`posegen.draft.geometry.hand_contact` (a flat face pointing down,
  else a point at the hand's tip);
* collision geometry for the links that move without any (or whose collision shapes leave
  out their visual geometry), and capsules for links whose collision geometry misses their
  centre of mass: :mod:`posegen.draft.covering`;
* table: in front of the shoulders, its top about 0.7 arm lengths below them;
* velocity limits the URDF lacks (0) or gives implausibly (> 20 rad/s);
* collision pairs to disable: :mod:`posegen.robot.collision_matrix`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from posegen.draft.body import Body, study_body
from posegen.draft.covering import collision_additions
from posegen.draft.force import held_force
from posegen.draft.geometry import Geometry, HandContact, forearm, hand_contact, link_of_joint, vertices
from posegen.draft.limits import (
    IMPLAUSIBLE_SPEED_RAD_S,
    JOINT_LIMIT_MARGIN_RAD,
    PLACEHOLDER_SPEED_RAD_S,
    limits,
    missing_efforts,
    velocity_placeholders,
)
from posegen.draft.soles import Sole, floor_height
from posegen.draft.source import DraftSource, load_draft_source
from posegen.draft.table import Table, arm_length, place_table
from posegen.robot import (
    CollisionConfig,
    FloatArray,
    FrameConfig,
    PairSurvey,
    RobotSource,
    Shape,
    add_self_pairs,
    robot_geometry,
    survey_pairs,
)

COLLISION_MARGIN_M = 0.005
REST_MARGIN_M = 0.01  # pairs this close at the reference touch at rest (meshes that nearly overlap there)


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
    left_out: dict[str, str]  # link -> how much of its visual geometry its collision shapes leave out (replaced)
    bare: tuple[str, ...]  # moving links left without collision geometry (a CHECK line; `posegen check` warns too)
    table_center_m: tuple[float, float, float]
    table_yaw_deg: float  # the table's x axis along the robot's forward
    table_size_m: tuple[float, float, float]
    spots_x_m: tuple[float, ...]
    spots_y_m: tuple[float, ...]
    reach_m: float
    survey: PairSurvey
    joint_limit_margin_rad: float = JOINT_LIMIT_MARGIN_RAD
    contact_force_n: float | None = None  # route.contact_force_n to write (None: posegen's default)
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

    The steps: :func:`~posegen.draft.body.study_body` (stance, legs, arms, locks),
    :func:`~posegen.draft.covering.collision_additions`, :func:`find_hands`, velocity placeholders,
    :func:`table_for` and the collision pairs to disable (:func:`~posegen.robot.collision_matrix.survey_pairs`).

    Raises:
        ConfigError: Unknown robot, a description that does not load, or a structure that
            is not two legs and two arms (the file and the element named).

    """
    src = load_draft_source(robot, srdf, package_dirs)
    model, body = src.model, study_body(src)
    data = model.createData()
    pin.framesForwardKinematics(model, data, body.reference)
    added, checks = collision_additions(model, data, body, src.text, src.files.package_dirs)
    geometry = added.geometry
    chains, found = find_hands(model, data, geometry, body)
    speeds, urdf_speed = velocity_placeholders(model, body.kept)
    if speeds:
        found += (
            f"{len(speeds)} joints have no plausible URDF velocity limit (none, or above "
            f"{IMPLAUSIBLE_SPEED_RAD_S:g} rad/s): placeholders of {PLACEHOLDER_SPEED_RAD_S:g} rad/s in "
            "robot.velocity_limits_rad_s; put your robot's",
        )
    no_effort = missing_efforts(model, body.kept, set(body.locked))
    if no_effort:
        found += (
            f"{len(no_effort)} joints have no URDF effort limit ({', '.join(no_effort[:3])}"
            f"{', ...' if len(no_effort) > 3 else ''}): their holding torques are not checked (pool, route, check)",
        )
    held = held_force(model, body.reference, [(c.joints, c.contact.frames, c.contact.flush) for c in chains])
    found += held.checks
    table, reach = table_for(model, data, geometry, body, chains[0])
    found += (f"the table is a guess from the arm's reach ({reach:.2f} m): put it where yours is",)
    soles = body.legs.soles
    rpy = tuple(round(float(v), 3) + 0.0 for v in np.rad2deg(pin.rpy.matrixToRpy(body.bearing.root.rotation)))
    return Draft(
        robot=robot,
        source=src.source,
        reference_posture=body.state,
        root_rpy_deg=None if body.bearing.up == "+z" else (rpy[0], rpy[1], rpy[2]),
        reference_joints=body.reference_joints,
        up_axis=body.bearing.up,
        soles=(soles[0], soles[1]),
        foot_x_m=(max(s.x_m[0] for s in soles), min(s.x_m[1] for s in soles)),
        foot_y_m=(max(s.y_m[0] for s in soles), min(s.y_m[1] for s in soles)),
        floor_contact=floor_links(model, geometry, soles, src.text),
        chains=(chains[0], chains[1]),
        locked=body.locked,
        velocity_limits=speeds,
        urdf_velocity=urdf_speed,
        shapes=added.shapes,
        covered=added.covered,
        misplaced=added.misplaced,
        left_out=added.left_out,
        bare=added.bare,
        table_center_m=table[0],
        table_size_m=table[1],
        spots_x_m=table[2],
        spots_y_m=table[3],
        table_yaw_deg=table[4],
        reach_m=reach,
        survey=_survey(model, src, added.shapes, body.reference, body.locked, samples, seed),
        joint_limit_margin_rad=body.joint_limit_margin_rad,
        contact_force_n=held.force_n if held.lowered else None,
        checks=body.checks + checks + found,
    )


def floor_links(model: pin.Model, geometry: Geometry, soles: list[Sole], urdf_text: str) -> tuple[str, ...]:
    """The links that may touch the floor: each foot's link and the links fixed to it that carry geometry.

    A foot is one rigid body: its joint's link, and links fixed to it (a sole plate fixed to
    the ankle link; an MJCF body converted with several hinges, whose foot link is empty and
    its geoms on the body's link fixed to it). An empty foot link itself is left out.
    """
    empty = {link.get("name") for link in ET.fromstring(urdf_text).iter("link") if len(link) == 0}
    links = []
    for sole in soles:
        carriers = [
            str(model.frames[o.parentFrame].name)
            for o in geometry.collision.geometryObjects
            if o.parentJoint == sole.foot_joint
        ]
        links += ([] if sole.foot_link in empty and carriers else [sole.foot_link]) + carriers
    return tuple(dict.fromkeys(links))


def find_hands(model: pin.Model, data: pin.Data, geometry: Geometry, body: Body) -> tuple[list[Chain], tuple[str, ...]]:
    """Each arm's hand, gripper frame and contact (at the posture of ``data``), left then right.

    The chains' joints leave out the torso (the joints both arms share).
    """
    shared = set(body.arms[0]) & set(body.arms[1])
    chains = []
    checks = []
    for name, sole, path in zip(("left", "right"), body.legs.soles, body.arms, strict=True):
        hand = link_of_joint(model, path[-1])
        fingers = set(body.tree.subtree(path[-1])) - {path[-1]}
        contact = hand_contact(model, data, geometry, name, hand, forearm(data, path), fingers)
        joints = tuple(str(model.names[j]) for j in path if j not in shared)
        gripper = FrameConfig(f"{name}_gripper", hand, (0.0, 0.0, 0.0))
        chains.append(Chain(name, sole.frame, hand, gripper, joints, contact))
        checks.append(f"{name} hand ({hand}): {contact.how}; edit robot.frames to where it really touches")
    return chains, tuple(checks)


def table_for(model: pin.Model, data: pin.Data, geometry: Geometry, body: Body, arm: Chain) -> tuple[Table, float]:
    """The table placed from an arm's reach, clear of the body (at the posture of ``data``), and that reach (m)."""
    shoulder = data.oMi[model.getJointId(arm.joints[0])].translation
    reach = arm_length(model, data, arm.joints, arm.hand, arm.contact.frames)
    floor_z = floor_height(model, data, body.legs.soles)
    points = vertices(model, data, geometry.collision, set(range(1, model.njoints)), body.bearing.heading)  # (k, 3)
    points[:, 2] -= floor_z
    return place_table(body.bearing.heading, shoulder, reach, floor_z, points), reach


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
