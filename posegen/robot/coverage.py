"""What the collision check of a scene checks with, and which moving links it cannot see.

``posegen check`` says it: the URDF's meshes (checked as they are), the config's
convex hulls of visual meshes, its primitives (capsules, boxes), and the links that
move, carry mass and reach beyond their joint, but have no collision geometry at all
(anything passes through them).
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from posegen.robot.additions import VisualHull
from posegen.robot.collision_geometry import robot_geometry
from posegen.robot.scene import Scene


@dataclass(frozen=True)
class GeometryCoverage:
    """The collision geometry of a scene's robot, by kind."""

    meshes: int  # the URDF's (or hulls of them: the planner's, never the check's)
    visual_hulls: int  # convex hulls of visual meshes, declared in the config
    primitives: int  # boxes, capsules, spheres, cylinders (URDF or config)
    bare_links: tuple[str, ...]  # links moved by a joint, with mass and extent, without any collision geometry

    def describe(self) -> str:
        """One phrase: what the check checks with."""
        parts = [f"{self.meshes} meshes"]
        if self.visual_hulls:
            parts.append(f"{self.visual_hulls} hulls of visual meshes")
        if self.primitives:
            parts.append(f"{self.primitives} primitives")
        return ", ".join(parts)


def geometry_coverage(scene: Scene) -> GeometryCoverage:
    """Count a scene's collision geometry by kind and find the moving links without any."""
    collision = scene.config.collision
    geom = robot_geometry(scene.model, scene.urdf_xml, scene.files.package_dirs, collision, convex=False)
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
    carried = {int(obj.parentJoint) for obj in geom.geometryObjects}
    bare = tuple(
        str(frame.name)
        for frame in scene.model.frames
        if frame.type == pin.FrameType.BODY
        and frame.parentJoint not in carried
        and scene.model.inertias[frame.parentJoint].mass > 0
        and has_extent(scene.model, frame.parentJoint)
        and _first_body(scene.model, frame)
    )
    return GeometryCoverage(meshes, hulls, primitives, bare)


def _first_body(model: pin.Model, frame: pin.Frame) -> bool:
    """Whether this body frame is its joint's first (the link the joint moves, not one fixed to it)."""
    for other in model.frames:
        if other.parentJoint == frame.parentJoint and other.type == pin.FrameType.BODY:
            return bool(other.name == frame.name)
    return False


MIN_SEGMENT_M = 0.01  # a link shorter than this and without mass needs no geometry


def has_extent(model: pin.Model, joint: int) -> bool:
    """Whether a joint's link reaches MIN_SEGMENT_M from its joint (a child joint, or its CoM, with mass)."""
    children = [model.jointPlacements[c].translation for c in range(2, model.njoints) if model.parents[c] == joint]
    far = [c for c in children if np.linalg.norm(c) >= MIN_SEGMENT_M]
    inertia = model.inertias[joint]
    return bool(far) or (inertia.mass > 0 and float(np.linalg.norm(inertia.lever)) >= MIN_SEGMENT_M)
