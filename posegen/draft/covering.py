"""The collision geometry ``posegen robot init`` gives the links that move, and why.

Every link a joint moves (the joint's own link and those fixed to it), with mass or
visual geometry, ends up with collision geometry, or is named in a ``# CHECK:`` line that
``posegen check`` repeats (:func:`posegen.robot.bare_links`, the one rule both apply):

* its own collision shapes, unless its visual geometry reaches more than COVER_TOL_M
  (20 mm) outside every collision shape of its body (a 6 cm disc under a 39 cm torso
  mesh; a gripper's coarse collision mesh): then the convex hulls of its visual geometry
  replace them (:func:`left_out_geometry`);
* without shapes of its own: those of its body when they enclose its visual geometry
  (within COVER_TOL_M: a sensor's box inside the torso), else the hulls of its visual
  geometry (a palm fixed below a wrist); a link without any geometry is covered by the
  links fixed to it, else gets capsules along the joints (:func:`skeleton`; none for a
  link of no extent, between coincident joints);
* a foot without any geometry: a box over its guessed footprint;
* geometry that contradicts the kinematics (a link's CoM outside its collision shapes, or
  shapes below the floor standing) is replaced by capsules along the joints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.draft.body import Body
from posegen.draft.geometry import Geometry, link_of_joint, round3, vertices
from posegen.draft.soles import floor_height, foot_box
from posegen.robot import (
    COVER_TOL_M,
    Capsule,
    CollisionConfig,
    Shape,
    VisualHull,
    bare_links,
    left_out_m,
    link_masses,
    robot_geometry,
)

COM_OUTSIDE_M = 0.02  # a link's CoM (or geometry below the floor) this far out: geometry contradicting the kinematics
MIN_SEGMENT_M = 0.01  # a link shorter than this and without mass needs no geometry


@dataclass(frozen=True, eq=False)
class AddedGeometry:
    """Collision shapes the draft adds, and why."""

    shapes: tuple[Shape, ...]  # for links without collision geometry, then for replaced geometry
    covered: dict[str, str]  # link -> what it gets for lacking collision geometry
    misplaced: dict[str, str]  # link -> why its collision geometry is replaced (CoM outside it, below the floor)
    left_out: dict[str, str]  # link -> how much of its visual geometry its collision shapes leave out
    bare: tuple[str, ...]  # links still without collision geometry (``posegen check`` warns of them too)
    geometry: Geometry  # the robot's with these shapes (what the hands and the table are read from)


def collision_additions(
    model: pin.Model, data: pin.Data, body: Body, urdf_text: str, package_dirs: tuple[str, ...] = ()
) -> tuple[AddedGeometry, tuple[str, ...]]:
    """The shapes the draft adds (the module's rules), at the posture of ``data``, and their CHECK lines.

    Args:
        model: The robot model.
        data: Its kinematics at the reference posture.
        body: The body as found (its geometry, feet and soles).
        urdf_text: The URDF (its links' masses; the added shapes are checked on it).
        package_dirs: Where its ``package://`` meshes are.

    """
    geometry = body.geometry
    bare_feet = [s for s in body.legs.soles if not s.from_geometry]
    covered, added = missing_geometry(model, geometry, link_masses(urdf_text), {s.foot_joint for s in bare_feet})
    for sole in bare_feet:
        covered[sole.foot_link] = "a box over the guessed footprint"
        added += (foot_box(model, data, sole),)
    misplaced = misplaced_geometry(model, geometry)
    feet_joints = {j for f in body.legs.feet for j in body.tree.subtree(f)}
    misplaced.update(below_floor(model, data, geometry, feet_joints, floor_height(model, data, body.legs.soles)))
    left_out = {link: why for link, why in left_out_geometry(model, geometry).items() if link not in misplaced}
    shapes = added + tuple(VisualHull(link) for link in left_out)
    shapes += tuple(s for link in misplaced for s in skeleton(model, link))
    final = robot_geometry(model, urdf_text, package_dirs, CollisionConfig(shapes=shapes), convex=False)
    bare = tuple(b.link for b in bare_links(model, link_masses(urdf_text), final, geometry.visual))
    found = AddedGeometry(shapes, covered, misplaced, left_out, bare, Geometry(final, geometry.visual))
    return found, _checks(found)


def _checks(added: AddedGeometry) -> tuple[str, ...]:
    """The CHECK lines of what was added (and of what could not be)."""
    checks = []
    if added.covered:
        checks.append(
            f"{len(added.covered)} moving links have no collision geometry: given "
            + ", ".join(sorted(set(added.covered.values())))
            + " (robot.collision.shapes)"
        )
    if added.left_out:
        checks.append(
            f"{len(added.left_out)} links' collision shapes leave out part of their visual geometry ("
            + "; ".join(f"{link}: {why}" for link, why in added.left_out.items())
            + "): replaced by the convex hulls of their visual geometry"
        )
    if added.misplaced:
        checks.append(
            f"{len(added.misplaced)} links' collision geometry contradicts the kinematics ("
            + "; ".join(f"{link}: {why}" for link, why in added.misplaced.items())
            + "): replaced by capsules along the joints"
        )
    if added.bare:
        checks.append(
            f"{len(added.bare)} moving links with mass or visual geometry still have no collision geometry "
            f"({', '.join(added.bare)}): nothing collides with them (`posegen check` warns of them); give them "
            "robot.collision.shapes"
        )
    return tuple(checks)


def missing_geometry(
    model: pin.Model, geometry: Geometry, masses: dict[str, float], skip: set[int]
) -> tuple[dict[str, str], tuple[Shape, ...]]:
    """Shapes for the moving links without collision geometry (:func:`posegen.robot.bare_links`).

    A link with visual geometry gets its hulls; a link without any gets capsules along the
    joints, unless a link of its body gets hulls (they then stand for it) or another link
    of its body got the capsules already.

    Args:
        model: The robot model.
        geometry: Its geometry.
        masses: Each link's own mass (kg).
        skip: Joints whose links are covered otherwise (bare feet: a box).

    Returns:
        What each covered link gets ("the convex hull of its visual meshes" or "capsules
        along the joints") and the shapes.

    """
    bare = [b for b in bare_links(model, masses, geometry.collision, geometry.visual) if b.joint not in skip]
    hulled = {b.joint for b in bare if b.visual}
    how: dict[str, str] = {}
    shapes: list[Shape] = []
    for link in bare:
        if link.visual:
            how[link.link] = "the convex hull of its visual meshes"
            shapes.append(VisualHull(link.link))
            continue
        if link.joint in hulled:
            continue
        capsules = skeleton(model, link.link)
        if capsules:
            how[link.link] = "capsules along the joints"
            shapes += capsules
            hulled.add(link.joint)
    return how, tuple(shapes)


def left_out_geometry(model: pin.Model, geometry: Geometry) -> dict[str, str]:
    """Links with collision shapes of their own that leave their visual geometry out, and by how much.

    Left out: a vertex of the link's visual geometry more than COVER_TOL_M outside the
    convex hull of every collision shape of its body.
    """
    own = {int(o.parentFrame) for o in geometry.collision.geometryObjects}
    seen = {int(o.parentFrame) for o in geometry.visual.geometryObjects}
    out = {}
    for f in sorted(own & seen):
        link = str(model.frames[f].name)
        outside = left_out_m(model, geometry.collision, geometry.visual, link)
        if outside > COVER_TOL_M:
            out[link] = f"its visual geometry reaches {1e3 * outside:.0f} mm outside them"  # them: the shapes
    return out


def skeleton(model: pin.Model, link: str) -> list[Capsule]:
    """Capsules from a link's origin to each child joint (or through its CoM, for an end link).

    The link's origin is its joint's, unless the link is fixed off its joint's body (a
    pelvis under a root link at the floor: the joint 0.6-1 m below it).

    None for a link of no extent (its children and CoM within MIN_SEGMENT_M of its origin:
    a link between coincident joints, which a sphere would only make collide with its
    neighbours).
    """
    frame = model.frames[model.getFrameId(link)]
    joint = frame.parentJoint
    to_link = frame.placement.inverse()  # joint frame -> link frame
    children = [c for c in range(2, model.njoints) if model.parents[c] == joint]
    ends = [to_link.act(model.jointPlacements[c].translation) for c in children]  # (3,) each, link frame
    ends = [e for e in ends if np.linalg.norm(e) >= MIN_SEGMENT_M]
    at_joint = bool(ends)  # the capsules end at child joints (else one through the CoM)
    inertia = model.inertias[joint]
    com = to_link.act(inertia.lever)
    if not ends and inertia.mass > 0 and np.linalg.norm(com) >= MIN_SEGMENT_M:
        ends = [2.0 * com]
    origin = np.zeros(3)  # the link's own origin: its joint's when the link is the joint's own, else a link fixed
    out = []  # off the joint's body (a pelvis under a `world` or `base_footprint` root: the joint at the floor)
    for end in ends:
        tip = np.asarray(end)
        length = float(np.linalg.norm(tip - origin))
        radius = round(float(np.clip(0.2 * length, 0.02, 0.06)), 3)
        if at_joint and length - radius >= MIN_SEGMENT_M:  # its cap reaches the child joint, not past it
            tip = origin + (tip - origin) * (length - radius) / length  # (a shank's cap past the ankle: the floor)
        out.append(Capsule(link, round3(origin), round3(tip), radius))
    return out


def below_floor(model: pin.Model, data: pin.Data, geometry: Geometry, feet: set[int], floor: float) -> dict[str, str]:
    """Links off the feet whose collision geometry reaches below the floor at the reference."""
    out = {}
    level = pin.SE3(np.eye(3), np.array([0.0, 0.0, floor]))
    for joint in range(1, model.njoints):
        if joint in feet:
            continue
        points = vertices(model, data, geometry.collision, {joint}, level)
        if len(points) and points[:, 2].min() < -COM_OUTSIDE_M:
            link = _geometry_link(model, geometry, joint)
            out[link] = f"reaches {-1e3 * points[:, 2].min():.0f} mm below the floor standing"
    return out


def _geometry_link(model: pin.Model, geometry: Geometry, joint: int) -> str:
    """The link that carries a joint's collision geometry (its first one)."""
    for obj in geometry.collision.geometryObjects:
        if obj.parentJoint == joint:
            return str(model.frames[obj.parentFrame].name)
    return link_of_joint(model, joint)


def misplaced_geometry(model: pin.Model, geometry: Geometry) -> dict[str, str]:
    """Links whose centre of mass lies outside their collision geometry's box, and by how far."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    out = {}
    for joint in range(1, model.njoints):
        inertia = model.inertias[joint]
        if inertia.mass <= 0:
            continue
        points = vertices(model, data, geometry.collision, {joint}, data.oMi[joint])
        if len(points) == 0:
            continue
        gap = np.maximum(0.0, np.maximum(points.min(axis=0) - inertia.lever, inertia.lever - points.max(axis=0)))
        distance = float(np.linalg.norm(gap))
        if distance > COM_OUTSIDE_M:
            out[_geometry_link(model, geometry, joint)] = f"CoM {1e3 * distance:.0f} mm outside it"
    return out
