"""What the collision check of a scene checks with, and which moving links it cannot see.

``posegen check`` says it: the URDF's meshes (checked as they are), the config's
convex hulls of visual meshes, its primitives (capsules, boxes), and the links that
move and carry mass (or a visual mesh) but have no collision geometry (anything passes
through them). ``posegen robot init`` gives those links geometry by the same rule
(:func:`bare_links`), and says of any it leaves bare what ``check`` then says.

A link is one of the links a joint moves (the joint's own link and those fixed to it:
together, a rigid body). It has collision geometry when it has shapes of its own, or when
its body's shapes stand for it:

* a link with visual geometry: its visual geometry lies within COVER_TOL_M of the convex
  hull of one of its body's collision shapes (:mod:`posegen.robot.enclosure`);
* a link without any geometry: its body carries collision shapes (on the links fixed to
  it), or reaches no farther than MIN_SEGMENT_M from its joint (no extent: a link between
  coincident joints).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from posegen.robot.additions import VisualHull
from posegen.robot.collision_geometry import robot_geometry
from posegen.robot.enclosure import enclosure_of, object_points
from posegen.robot.scene import Scene

COVER_TOL_M = 0.02  # a link's visual geometry this far outside its body's collision shapes is left out by them
MIN_SEGMENT_M = 0.01  # a link shorter than this and without mass needs no geometry


@dataclass(frozen=True)
class GeometryCoverage:
    """The collision geometry of a scene's robot, by kind."""

    meshes: int  # the URDF's (or hulls of them: the planner's, never the check's)
    visual_hulls: int  # convex hulls of visual meshes, declared in the config
    primitives: int  # boxes, capsules, spheres, cylinders (URDF or config)
    bare_links: tuple[str, ...]  # moving links with mass or visual geometry and no collision geometry (bare_links)

    def describe(self) -> str:
        """One phrase: what the check checks with (only the kinds it used).

        Example:
            >>> GeometryCoverage(0, 0, 31, ()).describe()
            '31 primitives'

        """
        kinds = (
            (self.meshes, "meshes"),
            (self.visual_hulls, "hulls of visual meshes"),
            (self.primitives, "primitives"),
        )
        parts = [f"{count} {what}" for count, what in kinds if count]
        return ", ".join(parts) or "no collision geometry"


@dataclass(frozen=True)
class BareLink:
    """A moving link without collision geometry (see the module's rule)."""

    link: str
    joint: int  # the joint that moves it
    visual: bool  # it has visual geometry (its body's collision shapes leave it out)


def geometry_coverage(scene: Scene) -> GeometryCoverage:
    """Count a scene's collision geometry by kind and find the moving links without any."""
    collision = scene.config.collision
    package_dirs = scene.files.package_dirs
    geom = robot_geometry(scene.model, scene.urdf_xml, package_dirs, collision, convex=False)
    hull_links = {shape.link for shape in collision.shapes if isinstance(shape, VisualHull)}
    meshes = hulls = primitives = 0
    for obj in geom.geometryObjects:
        link = str(scene.model.frames[obj.parentFrame].name)
        if isinstance(obj.geometry, coal.BVHModelBase):
            meshes += 1
        elif isinstance(obj.geometry, coal.ConvexBase) and link in hull_links:
            hulls += 1
        elif isinstance(obj.geometry, coal.ConvexBase):
            meshes += 1  # a URDF mesh pinocchio loaded as convex
        else:
            primitives += 1
    own = {str(scene.model.frames[o.parentFrame].name) for o in geom.geometryObjects}
    visual = visual_geometry(scene.model, scene.urdf_xml, package_dirs, without=own)
    bare = bare_links(scene.model, link_masses(scene.urdf_xml), geom, visual)
    return GeometryCoverage(meshes, hulls, primitives, tuple(b.link for b in bare))


def bare_links(
    model: pin.Model, masses: dict[str, float], collision: pin.GeometryModel, visual: pin.GeometryModel
) -> tuple[BareLink, ...]:
    """The moving links with mass or visual geometry that have no collision geometry (the module's rule).

    Args:
        model: The robot model (joint 1 its free-flyer root).
        masses: Each link's own mass (kg, :func:`link_masses`).
        collision: The collision geometry checked.
        visual: The visual geometry (at least that of the links without collision shapes of their own).

    Example:
        >>> [b.link for b in bare_links(model, link_masses(urdf), collision, visual)]  # a palm fixed below a wrist
        ['l_palm', 'r_palm']

    """
    own = {int(o.parentFrame) for o in collision.geometryObjects}
    carrying = {int(o.parentJoint) for o in collision.geometryObjects}
    seen = {int(o.parentFrame) for o in visual.geometryObjects}
    out = []
    for f, frame in enumerate(model.frames):
        joint = int(frame.parentJoint)
        if frame.type != pin.FrameType.BODY or joint == 0 or f in own:
            continue
        if f in seen:
            points = np.vstack([object_points(o) for o in visual.geometryObjects if o.parentFrame == f])
            if enclosure_of(collision, joint).outside_m(points) > COVER_TOL_M:
                out.append(BareLink(str(frame.name), joint, True))
        elif masses.get(str(frame.name), 0.0) > 0 and joint not in carrying and has_extent(model, joint):
            out.append(BareLink(str(frame.name), joint, False))
    return tuple(out)


def left_out_m(model: pin.Model, collision: pin.GeometryModel, visual: pin.GeometryModel, link: str) -> float:
    """How far a link's visual geometry lies outside its body's collision shapes (m; -inf without visual geometry).

    Example:
        >>> left_out_m(model, collision, visual, "torso")  # a 6 cm disc under a 39 cm torso mesh
        0.16

    """
    frame_id = model.getFrameId(link, pin.FrameType.BODY)
    objects = [o for o in visual.geometryObjects if o.parentFrame == frame_id]
    if not objects:
        return -float("inf")
    joint = int(model.frames[frame_id].parentJoint)
    return enclosure_of(collision, joint).outside_m(np.vstack([object_points(o) for o in objects]))


def link_masses(urdf_xml: str) -> dict[str, float]:
    """Each link's own mass (kg), from its ``<inertial>`` (0 without one; pinocchio sums a body's).

    Example:
        >>> link_masses('<robot><link name="a"><inertial><mass value="2"/></inertial></link></robot>')
        {'a': 2.0}

    """
    out = {}
    for link in ET.fromstring(urdf_xml).iter("link"):
        mass = link.find("inertial/mass")
        out[str(link.get("name"))] = float(mass.get("value", 0.0)) if mass is not None else 0.0
    return out


def visual_geometry(
    model: pin.Model, urdf_xml: str, package_dirs: tuple[str, ...], without: set[str]
) -> pin.GeometryModel:
    """The visual geometry of the links not in ``without`` (none if their meshes cannot be loaded).

    Only those links' meshes are read: the check needs the visual geometry of the links
    without collision shapes of their own, and a robot's visual meshes can be heavy.
    """
    root = ET.fromstring(urdf_xml)
    wanted = False
    for link in root.iter("link"):
        if link.get("name") in without:
            for element in link.findall("visual"):
                link.remove(element)
        wanted = wanted or link.find("visual") is not None
    if not wanted:
        return pin.GeometryModel()
    try:
        text = ET.tostring(root, encoding="unicode")
        return pin.buildGeomFromUrdfString(model, text, pin.VISUAL, package_dirs=list(package_dirs))
    except (RuntimeError, ValueError):  # a visual mesh not shipped: those links are judged without it
        return pin.GeometryModel()


def has_extent(model: pin.Model, joint: int) -> bool:
    """Whether a joint's link reaches MIN_SEGMENT_M from its joint (a child joint, or its CoM, with mass)."""
    children = [model.jointPlacements[c].translation for c in range(2, model.njoints) if model.parents[c] == joint]
    far = [c for c in children if np.linalg.norm(c) >= MIN_SEGMENT_M]
    inertia = model.inertias[joint]
    return bool(far) or (inertia.mass > 0 and float(np.linalg.norm(inertia.lever)) >= MIN_SEGMENT_M)
