"""A humanoid's body as ``posegen robot init`` finds it from its kinematic tree, one step each.

:func:`study_body` runs them in order:

1. :func:`srdf_state`: the SRDF's first state, unless it breaks the URDF's limits (or, found
   after step 3, its CoM is not inside the soles' polygon by the drafted margin);
2. :func:`orient`: the up axis, forward and left (:mod:`posegen.draft.stance`);
3. :func:`find_legs` then :func:`find_soles`: the two branches reaching the floor, their
   feet and soles; the legs branch from the root, else from a joint below it (a torso-rooted
   model: the joints from the root down to that branching joint are the waist, free joints of
   the upper body, in neither the legs nor the arms: :func:`~posegen.draft.stance.waist_joints`);
4. :func:`bend_reference`: without an SRDF state, a standing posture with the knees bent;
5. :func:`find_arms`: the two longest chains of the upper body, up to where they branch
   into light parts only (fingers: under 1 % of the robot's mass), less the joints at their
   ends a plan cannot use (:mod:`posegen.draft.arm_ends`: too narrow, or a light part the
   hand's tip does not follow);
6. :func:`locked_joints` and :func:`clear_of_limits`: every joint off the legs and arms is
   locked where it is; the arms' joints are moved clear of their limits.

Each step returns what it found and the ``# CHECK:`` lines it adds, in the draft's order.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.draft.arm_ends import without_idle_ends, without_narrow_ends
from posegen.draft.geometry import Geometry, load_geometry
from posegen.draft.heading import TURNED, Bearing, forward_of, knees_forward
from posegen.draft.limits import (
    COM_MARGIN_M,
    JOINT_LIMIT_MARGIN_RAD,
    clear_of_limits,
    locked_joints,
    near_limit,
    outside_limits,
    with_joints,
    without_room,
)
from posegen.draft.soles import ANKLE_HEIGHT, Sole, com_margin, find_sole, sole_pose
from posegen.draft.source import DraftSource
from posegen.draft.stance import (
    bend_legs,
    find_up,
    foot_joint,
    joint_path,
    reaching_branches,
    upper_branches,
    waist_joints,
)
from posegen.errors import ConfigError
from posegen.robot import FloatArray, RobotFiles, read_srdf_states, yaw_rotation

LIGHT_FRACTION = 0.01  # a branch lighter than this share of the robot's mass is an end effector's part
ROBOT_MAX_M = 5.0  # joints farther apart than this are no humanoid's (a URDF in millimetres, not metres)


@dataclass(frozen=True, eq=False)
class Tree:
    """A model's kinematic tree: each joint's children (the root's are its branches)."""

    model: pin.Model
    children: dict[int, list[int]]

    @classmethod
    def of(cls, model: pin.Model) -> Tree:
        """The tree of ``model`` (joint 1 is the free-flyer root)."""
        return cls(
            model, {j: [c for c in range(2, model.njoints) if model.parents[c] == j] for j in range(model.njoints)}
        )

    def subtree(self, joint: int) -> list[int]:
        """``joint`` and every joint below it, depth first."""
        out = [joint]
        for child in self.children[joint]:
            out += self.subtree(child)
        return out

    def mass(self, joints: list[int]) -> float:
        """The mass (kg) the bodies of these joints carry."""
        return float(sum(self.model.inertias[j].mass for j in joints))


@dataclass(frozen=True, eq=False)
class Legs:
    """The two legs, left then right."""

    roots: list[int]  # each leg's first joint
    feet: list[int]  # each leg's last joint
    paths: list[list[int]]  # each leg's joints, hip to foot
    length_m: float  # hip to ankle
    soles: list[Sole]

    @property
    def joints(self) -> set[int]:
        """Every joint of both legs."""
        return {j for path in self.paths for j in path}


@dataclass(frozen=True, eq=False)
class Body:
    """What the body's structure gives the draft: its bearing, legs, arms, reference posture and locks."""

    tree: Tree
    state: str  # the SRDF state used ("" when none)
    bearing: Bearing
    legs: Legs
    arms: list[list[int]]  # each arm's joints from the torso, left then right
    waist: list[int]  # the joints from the root down to the legs' branching joint (none when it is the root)
    geometry: Geometry
    reference: FloatArray  # (nq,) root placed, legs bent (without a state), locked joints at their values
    reference_joints: dict[str, float]  # rad, what the draft set (legs bent, joints off their limits)
    locked: dict[str, float]  # rad
    joint_limit_margin_rad: float
    checks: tuple[str, ...]
    stuck: frozenset[int] = frozenset()  # joints of the legs, arms or waist locked for want of room between limits

    @property
    def kept(self) -> set[int]:
        """The joints of the legs, arms and waist (not locked)."""
        return (self.legs.joints | {j for arm in self.arms for j in arm} | set(self.waist)) - self.stuck


WORLD_LINK = "world"  # the URDF convention for a fixed base (a joint from it pins the robot)


def study_body(src: DraftSource, refused_state: str = "") -> Body:
    """Find the legs, soles, arms, reference posture and joints to lock of a humanoid.

    An SRDF state whose CoM is not ``COM_MARGIN_M`` inside the soles' polygon is not used:
    the body is studied again without it (``refused_state``: the CHECK line saying why).

    Raises:
        ConfigError: Not two legs reaching the floor, or not two arms.

    """
    model, tree = src.model, Tree.of(src.model)
    state, q, checks = srdf_state(model, src.files, refused_state)
    check_size(model, q, src.label)
    bearing = orient(model, q, tree, src.label)
    q[:7] = pin.SE3ToXYZQUAT(bearing.root)
    if bearing.up != "+z":
        checks += (f"the model's up axis is its root's {bearing.up} axis: the root is turned by stance.root_rpy_deg",)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    roots = find_legs(model, data, tree, bearing.left, src.label)
    if (facing := knees_forward(model, data, tree.children, tree.subtree, roots, bearing)) is not bearing:
        bearing, checks = facing, (*checks, TURNED.format(axis=facing.root_axis()))
        roots = find_legs(model, data, tree, bearing.left, src.label)
    geometry = load_geometry(model, src.text, src.files.package_dirs)
    legs, found = find_soles(model, data, geometry, tree, roots, bearing.heading)
    if state and (margin := com_margin(model, q, legs.soles)) < COM_MARGIN_M:
        return study_body(
            src,
            f"the SRDF's state '{state}' is not balanced (its CoM {1e3 * margin:.1f} mm inside the soles' polygon, "
            f"margins.com_m {1e3 * COM_MARGIN_M:g} mm): the draft finds its own reference posture",
        )
    reference_joints: dict[str, float] = {}
    margin = JOINT_LIMIT_MARGIN_RAD
    if not state:
        q, reference_joints, margin, bent = bend_reference(model, q, legs, bearing.forward)
        found += bent
        pin.framesForwardKinematics(model, data, q)
    arms = find_arms(model, data, tree, roots, bearing.left, src.label)
    light_kg = LIGHT_FRACTION * tree.mass(list(range(1, model.njoints)))
    for drop in (
        lambda arm: without_narrow_ends(model, arm, margin),
        lambda arm: without_idle_ends(model, data, geometry, arm, tree.subtree, light_kg),
    ):
        trimmed = [drop(arm) for arm in arms]
        arms = [arm for arm, _ in trimmed]
        found += tuple(check for _, check in trimmed if check)
    waist = waist_joints(model, roots)
    stuck, found_stuck = without_room(model, legs.joints | {j for arm in arms for j in arm} | set(waist), margin)
    found += found_stuck
    kept = (legs.joints | {j for arm in arms for j in arm} | set(waist)) - stuck
    locked = locked_joints(model, q, kept)
    q = with_joints(model, q, locked)
    cleared = clear_of_limits(model, q, sorted(kept - legs.joints))
    q = with_joints(model, q, cleared)
    reference_joints.update({name: round(value, 4) for name, value in cleared.items()})
    checks += found + fixed_base(src.text)
    return Body(
        tree, state, bearing, legs, arms, waist, geometry, q, reference_joints, locked, margin, checks, frozenset(stuck)
    )


def fixed_base(urdf_text: str) -> tuple[str, ...]:
    """A CHECK line when the URDF pins its body to a ``world`` link (the URDF convention of a fixed base).

    posegen always stands the robot free (a free-flyer at the URDF's root): a body pinned
    to ``world``, as a simulator's description does, is stood free too, and the line asks
    the user to confirm that is meant. A massless ``base_link`` root (REP 105) says nothing.

    Example:
        >>> fixed_base('<robot><link name="world"/><joint name="j" type="fixed">'
        ...            '<parent link="world"/><child link="base"/></joint><link name="base"/></robot>')

    """
    root = ET.fromstring(urdf_text)
    pinned = [
        joint.find("child").get("link")  # type: ignore[union-attr]
        for joint in root.iter("joint")
        if joint.find("parent") is not None and joint.find("parent").get("link") == WORLD_LINK  # type: ignore[union-attr]
    ]
    if not pinned:
        return ()
    return (
        f"the URDF pins '{pinned[0]}' to '{WORLD_LINK}' (a fixed base, as a simulator's description does): posegen "
        "stands the robot free on its feet; check that this description is meant to stand",
    )


def srdf_state(model: pin.Model, files: RobotFiles, refused: str = "") -> tuple[str, FloatArray, tuple[str, ...]]:
    """The SRDF's first state ("" without one) and its configuration (nq,), else the neutral one.

    A state outside the URDF's limits is not used (a CHECK line says so), nor one the
    caller ``refused`` (that CHECK line, e.g. an unbalanced state). The SRDF's states are
    added to ``model.referenceConfigurations``.

    Raises:
        ConfigError: The SRDF is unreadable or malformed.

    """
    states: dict[str, FloatArray] = {}
    if files.srdf is not None:
        read_srdf_states(model, files)  # a clear error for an unreadable or malformed SRDF
        states = {str(e.key()): np.array(e.data()) for e in model.referenceConfigurations}
    if refused:
        return "", pin.neutral(model), (refused,)
    state = next(iter(states), "")
    outside = outside_limits(model, states[state]) if state else []
    if outside:
        check = (
            f"the SRDF's state '{state}' puts {', '.join(outside[:3])} outside the URDF's limits: "
            "the draft finds its own reference posture"
        )
        return "", pin.neutral(model), (check,)
    return state, (states[state].copy() if state else pin.neutral(model)), ()


def orient(model: pin.Model, q: FloatArray, tree: Tree, label: str) -> Bearing:
    """The root's pose putting the up axis up, in posture ``q`` (nq,), and the robot's forward and left.

    Raises:
        ConfigError: No up axis along which exactly two branches reach the lowest level.

    """
    root, up = find_up(model, q, tree.children, tree.subtree, label)
    forward = forward_of(root)
    heading = pin.SE3(yaw_rotation(float(np.arctan2(forward[1], forward[0]))), np.zeros(3))
    return Bearing(root, up, forward, np.cross([0.0, 0.0, 1.0], forward), heading)


def find_legs(model: pin.Model, data: pin.Data, tree: Tree, left: FloatArray, label: str) -> list[int]:
    """The first joints of the two legs, left then right, at the posture of ``data``.

    The legs are the two branches reaching the floor of the root, else of the joint below it
    where they branch (:func:`~posegen.draft.stance.reaching_branches`).

    Raises:
        ConfigError: Not exactly two such branches.

    """
    lowest = {b: min(float(data.oMi[j].translation[2]) for j in tree.subtree(b)) for b in range(2, model.njoints)}
    floor = min(lowest[b] for b in tree.children[1])  # the root's own placement left out (a base_footprint's is low)
    reaching = reaching_branches(tree.children, lowest, floor)
    legs = sorted(reaching, key=lambda b: -float(data.oMi[b].translation @ left))
    if len(legs) != 2:
        raise ConfigError(f"{label}: expected two legs reaching the floor, found {len(legs)}")
    return legs


def find_soles(
    model: pin.Model, data: pin.Data, geometry: Geometry, tree: Tree, roots: list[int], heading: pin.SE3
) -> tuple[Legs, tuple[str, ...]]:
    """Each leg's foot (down its heaviest branch), path and sole, at the posture of ``data``."""
    feet = [foot_joint(model, b, tree.children, tree.subtree) for b in roots]
    paths = [joint_path(model, b, f) for b, f in zip(roots, feet, strict=True)]
    length = float(np.linalg.norm(data.oMi[roots[0]].translation - data.oMi[feet[0]].translation))
    soles = [
        find_sole(model, data, geometry, side, f, length, heading)
        for side, f in zip(("left", "right"), feet, strict=True)
    ]
    checks = []
    for sole in soles:
        if not sole.from_geometry:
            checks.append(
                f"{sole.foot_link} has no geometry: the sole '{sole.frame}' (robot.frames) is put "
                f"{ANKLE_HEIGHT:.0%} of the leg's length below the ankle and the footprint (stance.foot_x_m, "
                "foot_y_m) is a guess from the leg's length: measure the foot"
            )
        elif sole.declared is not None:
            checks.append(f"sole '{sole.frame}' declared under the ankle, on the lowest vertices of {sole.foot_link}")
    return Legs(roots, feet, paths, length, soles), tuple(checks)


def bend_reference(
    model: pin.Model, q: FloatArray, legs: Legs, forward: FloatArray
) -> tuple[FloatArray, dict[str, float], float, tuple[str, ...]]:
    """A reference with the knees bent, soles flat where they stand in ``q`` (nq,), the CoM over the feet.

    Returns:
        The posture (nq,; ``q`` itself, copied, when the legs cannot bend), the leg joints set (rad,
        rounded), the joint limit margin to draft (rad: 0 when straight legs sit at their limits),
        and the CHECK lines.

    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    bent = bend_legs(model, q, legs.paths, [sole_pose(model, data, s) for s in legs.soles], forward, legs.length_m)
    if bent is None:
        checks = ["the legs could not be bent within their limits: the reference stands with straight legs"]
        tight = [str(model.names[j]) for path in legs.paths for j in path if near_limit(model, q, j)]
        if not tight:
            return q.copy(), {}, JOINT_LIMIT_MARGIN_RAD, tuple(checks)
        checks.append(
            f"straight, {', '.join(tight)} sit at their limits (the URDF's limits forbid a bent stance): "
            "margins.joint_limit_rad is 0; check the URDF's limits"
        )
        return q.copy(), {}, 0.0, tuple(checks)
    joints = {
        str(model.names[j]): round(float(bent[model.joints[j].idx_q]), 4) + 0.0 for path in legs.paths for j in path
    }
    check = (
        "no SRDF posture: the reference (stance.reference_joints) bends the knees, soles flat, CoM over the "
        "feet; check it with `posegen view` on a pool"
    )
    return bent, joints, JOINT_LIMIT_MARGIN_RAD, (check,)


def find_arms(
    model: pin.Model, data: pin.Data, tree: Tree, legs: list[int], left: FloatArray, label: str
) -> list[list[int]]:
    """The two longest chains of the upper body, left then right (by their ends at the posture of ``data``).

    Raises:
        ConfigError: Fewer than two chains of at least three joints.

    """
    paths: list[list[int]] = []
    total = tree.mass(list(range(1, model.njoints)))
    upper = upper_branches(model, tree.children, legs)  # the root's off the legs, and the waist's
    for branch in upper:
        _arm_paths(branch, [], tree, total, paths)
    paths.sort(key=len, reverse=True)
    if len(paths) < 2 or len(paths[1]) < 3:
        found = ", ".join(f"'{model.names[p[-1]]}'" for p in paths) or "none"
        names = ", ".join(f"'{model.names[b]}'" for b in upper) or "none"
        raise ConfigError(f"{label}: no two arms: the upper body (from joint {names}) has the chains ending at {found}")
    return sorted(paths[:2], key=lambda p: -float(data.oMi[p[-1]].translation @ left))


def _arm_paths(joint: int, path: list[int], tree: Tree, total: float, out: list[list[int]]) -> None:
    """Chains of the upper body, through single joints and at a branching into its heavy branches.

    A branching into light parts alone (fingers) ends the chain.
    """
    path = [*path, joint]
    below = tree.children[joint]
    heavy = below if len(below) == 1 else [c for c in below if tree.mass(tree.subtree(c)) >= LIGHT_FRACTION * total]
    if not heavy:
        out.append(path)
    for child in heavy:
        _arm_paths(child, path, tree, total, out)


def check_size(model: pin.Model, q: FloatArray, label: str) -> None:
    """The joints at ``q`` (nq,) lie within a humanoid's size: a URDF written in millimetres is named as such.

    Raises:
        ConfigError: Two joints farther apart, along an axis, than :data:`ROBOT_MAX_M`.

    """
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    placed = np.array([data.oMi[j].translation for j in range(2, model.njoints)])  # (njoints - 2, 3) m, not the root
    span = float(np.ptp(placed, axis=0).max()) if len(placed) else 0.0
    if span > ROBOT_MAX_M:
        raise ConfigError(
            f"{label}: its joints lie {span:.0f} m apart, no humanoid's size: lengths in millimetres? A URDF's "
            'lengths are metres: scale its origins, and give each <mesh> scale="0.001 0.001 0.001"'
        )
