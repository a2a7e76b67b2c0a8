"""The robot's collision geometry and which of its pairs are checked.

The geometry is the URDF's, except for the links whose shapes the config replaces
(capsules and boxes in the link frame, for descriptions whose meshes do not match the
kinematics). Pairs: every pair of links, less those the SRDF disables and those the
config disables (found by :mod:`posegen.robot.collision_matrix`, or declared by hand).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError, unknown_name
from posegen.robot.additions import Box, Capsule, CollisionConfig, Shape, VisualHull


def robot_geometry(
    model: pin.Model, urdf_xml: str, package_dirs: tuple[str, ...], collision: CollisionConfig, convex: bool
) -> pin.GeometryModel:
    """Collision geometry of the robot, without any pair.

    Args:
        model: The robot model.
        urdf_xml: Its URDF text.
        package_dirs: Where ``package://`` meshes are found.
        collision: The config's replaced shapes.
        convex: Replace meshes by their convex hulls (fast, conservative).

    """
    check_link_names(model, collision)
    geom = pin.buildGeomFromUrdfString(model, urdf_xml, pin.COLLISION, package_dirs=list(package_dirs))
    replaced = collision.replaced_links()
    if replaced:
        doomed = [str(o.name) for o in geom.geometryObjects if str(model.frames[o.parentFrame].name) in replaced]
        for name in doomed:
            geom.removeGeometryObject(name)
        visual = None
        for k, shape in enumerate(collision.shapes):
            name = f"{shape.link}_shape_{k}"
            if isinstance(shape, VisualHull):
                if visual is None:
                    visual = pin.buildGeomFromUrdfString(model, urdf_xml, pin.VISUAL, package_dirs=list(package_dirs))
                _add_visual_hulls(model, geom, visual, shape.link, name)
                continue
            frame = model.frames[model.getFrameId(shape.link, pin.FrameType.BODY)]
            geometry, local = _primitive(shape)
            parent = model.getFrameId(shape.link)
            placement = frame.placement * local
            geom.addGeometryObject(pin.GeometryObject(name, frame.parentJoint, parent, placement, geometry))
    if convex:
        for obj in geom.geometryObjects:
            if isinstance(obj.geometry, coal.BVHModelBase):
                # A true hull (qhull). buildConvexRepresentation would wrap the raw,
                # non-convex mesh, and coal's hill-climbing support function then
                # overestimates distances (seen: 10 mm reported for a 1 mm gap).
                # A flat mesh becomes a thin box: qhull fails on it and coal then crashes.
                shape, local = _visual_hull(obj.geometry)
                obj.geometry = shape
                if not local.isIdentity():
                    obj.placement = obj.placement * local
    return geom


def _add_visual_hulls(
    model: pin.Model, geom: pin.GeometryModel, visual: pin.GeometryModel, link: str, name: str
) -> None:
    """Add the convex hull of each of a link's visual meshes, and its visual primitives as they are, to ``geom``.

    Raises:
        ConfigError: The link has no visual geometry (``robot.collision.shapes``).

    """
    parent = model.getFrameId(link, pin.FrameType.BODY)
    found = [
        o
        for o in visual.geometryObjects
        if o.parentFrame == parent and not isinstance(o.geometry, coal.Plane | coal.Halfspace)
    ]
    if not found:
        raise ConfigError(f"robot.collision.shapes.{link}: visual_hull, but the link has no visual geometry")
    for k, obj in enumerate(found):
        shape, placement = _visual_hull(obj.geometry)
        placed = obj.placement * placement
        geom.addGeometryObject(pin.GeometryObject(f"{name}_{k}", obj.parentJoint, parent, placed, shape))


FLAT = 1e-6  # a mesh whose thinnest principal extent is below this share of its largest is flat
THIN_M = 0.001  # a flat mesh's box is this thick


def _visual_hull(shape: coal.CollisionGeometry) -> tuple[coal.CollisionGeometry, pin.SE3]:
    """A mesh as convex collision geometry (a visual or a collision one), and its placement in the shape's frame.

    A mesh becomes its convex hull (qhull), a flat mesh its box THIN_M thick (qhull would
    fail on it, and coal then crashes), a primitive stays as it is.
    """
    if not isinstance(shape, coal.BVHModelBase):
        return shape, pin.SE3.Identity()
    points = np.asarray(shape.vertices(), dtype=float).reshape(-1, 3)  # (k, 3)
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False) if len(points) >= 4 else np.zeros(3)
    if len(spread) == 3 and spread[2] > FLAT * spread[0]:
        shape.buildConvexHull(True, "Qt")
        return shape.convex, pin.SE3.Identity()
    low, high = points.min(axis=0), points.max(axis=0)
    size = np.maximum(high - low, THIN_M)
    return coal.Box(*size), pin.SE3(np.eye(3), (low + high) / 2)


def _primitive(shape: Shape) -> tuple[coal.CollisionGeometry, pin.SE3]:
    """A coal primitive and its placement in the link frame."""
    if isinstance(shape, Box):
        rotation = pin.rpy.rpyToMatrix(*np.deg2rad(shape.rpy_deg))
        return coal.Box(*shape.size_m), pin.SE3(rotation, np.array(shape.center_m))
    assert isinstance(shape, Capsule)
    a, b = np.array(shape.from_m), np.array(shape.to_m)
    length = float(np.linalg.norm(b - a))
    if length < 1e-9:
        return coal.Sphere(shape.radius_m), pin.SE3(np.eye(3), a)
    axis = (b - a) / length
    rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), axis).toRotationMatrix()
    return coal.Capsule(shape.radius_m, length), pin.SE3(rotation, (a + b) / 2)


def check_link_names(model: pin.Model, collision: CollisionConfig) -> None:
    """Check that the config's disabled pairs and replaced shapes name links of the robot.

    Raises:
        ConfigError: An unknown link (the valid ones are listed).

    """
    links = {str(f.name) for f in model.frames if f.type == pin.FrameType.BODY}
    for k, pair in enumerate(collision.disabled_pairs):
        for link in (pair.link_a, pair.link_b):
            if link not in links:
                raise ConfigError(unknown_name("link", link, links) + f" (robot.collision.disabled_pairs[{k}])")
    for link in sorted(collision.replaced_links() - links):
        raise ConfigError(unknown_name("link", link, links) + " (robot.collision.shapes)")


def link_of(model: pin.Model, geom: pin.GeometryModel) -> list[str]:
    """The link (body frame) each geometry object belongs to.

    Example:
        >>> links = set(link_of(scene.model, robot_geometry(scene.model, scene.urdf_xml, dirs, collision, True)))

    """
    return [str(model.frames[o.parentFrame].name) for o in geom.geometryObjects]


def add_self_pairs(model: pin.Model, geom: pin.GeometryModel, srdf: str | None, collision: CollisionConfig) -> None:
    """Add every pair of links except those the SRDF (if any) or the config disables."""
    geom.addAllCollisionPairs()
    if srdf is not None:
        pin.removeCollisionPairs(model, geom, srdf, False)
    if not collision.disabled_pairs:
        return
    disabled = {frozenset((pair.link_a, pair.link_b)) for pair in collision.disabled_pairs}
    owner = link_of(model, geom)
    doomed = [
        (int(p.first), int(p.second))
        for p in geom.collisionPairs
        if frozenset((owner[p.first], owner[p.second])) in disabled
    ]
    for first, second in doomed:  # by value: removing shifts the pairs after it
        geom.removeCollisionPair(pin.CollisionPair(first, second))


def carrying_links(model: pin.Model, frames: tuple[str, ...], geometry_links: set[str]) -> set[str]:
    """The links with collision geometry that carry these frames (rigidly, through fixed joints).

    A fingertip frame is usually such a link itself; a frame declared in the config is
    not, and its touching geometry is the link it is fixed to.

    Example:
        >>> tip = scene.chain("right").point_frame  # a point the config declares on a finger
        >>> carrying_links(scene.model, (tip,), links)  # the finger's link, which carries its geometry

    """
    out = set()
    for name in frames:
        frame_id = model.getFrameId(name)
        while True:
            frame = model.frames[frame_id]
            if str(frame.name) in geometry_links:
                out.add(str(frame.name))
                break
            if frame.type == pin.FrameType.JOINT or frame_id == frame.parentFrame:
                break  # past a moving joint: nothing rigidly attached carries geometry
            frame_id = frame.parentFrame
    return out
