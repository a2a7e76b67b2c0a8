"""What touches what in the physical scene: the robot's collision shapes, soles, tips, floor and table.

The robot's shapes are posegen's own collision geometry
(:func:`posegen.robot.robot_geometry`: the URDF's meshes as convex hulls, or the config's
replacement shapes), attached to the MuJoCo bodies of their links. Contacts are kept
only where the experiment makes them or where they would be a fault worth reporting:

* a box sole under each sole frame (the config's foot rectangle ``stance.foot_x_m`` x
  ``stance.foot_y_m``, its bottom face on the sole frame) touches the floor; the links the
  config lets touch the floor (``stance.floor_contact_frames``) do not (their box does);
* a small sphere at each fingertip end (flush contacts) or the point tip's rounding
  (point contacts) touches the table; the links carrying them (and the chain's
  ``touching_links``) do not (their spheres do): the links the planner's collision check
  exempts at a contact (:func:`posegen.robot.carrying_links`: a frame the config declares
  is carried by the link with geometry it is fixed to);
* every other robot shape touches the floor and the table, so that an unwanted contact
  happens, and is reported, instead of passing through;
* the robot never touches itself (``check`` verifies self-collisions on the planned route).

Collision filtering is by bit: the floor and the table each carry one ``contype`` bit, a
robot shape the ``conaffinity`` bits of what it may touch (:class:`Touches`).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import coal
import mujoco
import numpy as np
import pinocchio as pin

from posegen.robot import FloatArray, Scene, carrying_links, link_of, robot_geometry

TIP_RADIUS_M = 0.005  # the sphere at each fingertip end (its lowest point is the end)
SOLE_THICKNESS_M = 0.01  # the box sole, above the sole frame
FLOOR_HALF_SIZE_M = 20.0
FRICTION = (1.0, 0.005, 0.0001)  # sliding, torsional, rolling (MuJoCo's defaults)
# the floor's contact: time constant (s), damping ratio. Stiff (two steps): with MuJoCo's
# default (0.02 s) a loaded sole sinks 0.6 mm and a foot pressed on its edge rolls by centiradians
FLOOR_SOLREF = (0.004, 1.0)


class Touches(enum.IntFlag):
    """What a shape may touch: the ``contype`` bit of the floor and of the table."""

    NOTHING = 0
    FLOOR = 1
    TABLE = 2


class ShapeRole(enum.Enum):
    """Why a geom is in the scene (what its contacts mean)."""

    FLOOR = "floor"
    TABLE = "table"
    SOLE = "sole"  # a box sole: its floor contacts carry the robot
    TIP = "tip"  # a fingertip end or point tip: its table contacts are the experiment's
    BODY = "body"  # any other robot shape: its contacts are unwanted


@dataclass(frozen=True)
class Shape:
    """One geom added to the spec: its role and the link (body) it is on."""

    name: str
    role: ShapeRole
    link: str  # the robot link ("" for the floor and the table)
    chain: str = ""  # TIP: the chain whose contact it makes
    sole: str = ""  # SOLE: the sole frame


def _link_of_frame(model: pin.Model, name: str) -> str:
    """The URDF link (a MuJoCo body) a frame is rigidly on: itself when it is a link."""
    frame = model.frames[model.getFrameId(name)]
    while frame.type != pin.FrameType.BODY:
        frame = model.frames[frame.parentFrame]
    return str(frame.name)


def _add_mesh_geom(spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, hull: coal.Convex) -> mujoco.MjsGeom:
    mesh = spec.add_mesh(name=f"{name}_hull")
    mesh.uservert = np.asarray(hull.points(), dtype=float).ravel()  # (v, 3) in the geom frame
    geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name)
    return geom


def _add_robot_geom(spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, obj: pin.GeometryObject) -> None:
    """A posegen collision shape as a geom of ``body`` (placement already in the body frame)."""
    shape = obj.geometry
    if isinstance(shape, coal.Convex):
        geom = _add_mesh_geom(spec, body, name, shape)
    elif isinstance(shape, coal.Box):
        geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=np.asarray(shape.halfSide))
    elif isinstance(shape, coal.Sphere):
        geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[shape.radius, 0, 0])
    elif isinstance(shape, coal.Capsule):
        geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[shape.radius, shape.halfLength, 0])
    elif isinstance(shape, coal.Cylinder):
        geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[shape.radius, shape.halfLength, 0])
    else:
        return  # a shape MuJoCo has no counterpart for (none in posegen's geometry today)
    geom.pos = obj.placement.translation
    geom.quat = pin.Quaternion(obj.placement.rotation).coeffs()[[3, 0, 1, 2]]  # (w, x, y, z)


def _robot_shapes(spec: mujoco.MjSpec, scene: Scene) -> list[Shape]:
    """Posegen's collision shapes on their links, each touching the floor and the table unless exempt."""
    model = scene.model
    geometry = robot_geometry(model, scene.urdf_xml, scene.files.package_dirs, scene.config.collision, True)
    links = set(link_of(model, geometry))  # the links with shapes; a frame exempts the one that carries it
    no_floor = carrying_links(model, (*scene.stance.floor_contact_frames, *scene.stance.sole_frames), links)
    no_table: set[str] = set()
    for chain in scene.chains:
        carried = tuple(frame for kind in chain.kinds for frame in kind.carried_frames(chain))
        no_table |= carrying_links(model, carried, links) | set(chain.touching_links)
    shapes = []
    for obj in geometry.geometryObjects:
        frame = model.frames[obj.parentFrame]
        link = str(frame.name)
        local = pin.GeometryObject(obj)  # a copy, its placement made relative to the link
        local.placement = frame.placement.inverse() * obj.placement
        body = spec.body(link)
        name = f"shape:{obj.name}"
        _add_robot_geom(spec, body, name, local)
        geom = spec.geom(name)
        if geom is None:
            continue
        touches = Touches.NOTHING
        if link not in no_floor:
            touches |= Touches.FLOOR
        if link not in no_table:
            touches |= Touches.TABLE
        _set_touches(geom, touches)
        shapes.append(Shape(name, ShapeRole.BODY, link))
    return shapes


def _set_touches(geom: mujoco.MjsGeom, touches: Touches) -> None:
    geom.contype = 0  # a robot shape is never the one that picks (so never touches another robot shape)
    geom.conaffinity = int(touches)
    geom.friction = FRICTION
    geom.mass = 0.0  # the URDF's inertials alone give the masses
    geom.density = 0.0


def _sole_shapes(spec: mujoco.MjSpec, scene: Scene) -> list[Shape]:
    """A box under each sole frame: the foot rectangle, its bottom face on the sole frame."""
    centre, half = scene.stance.foot_centre_m, scene.stance.foot_half_m
    shapes = []
    for sole in scene.stance.sole_frames:
        link = _link_of_frame(scene.model, sole)
        name = f"sole:{sole}"
        geom = spec.body(link).add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX)
        geom.size = [*half, SOLE_THICKNESS_M / 2]
        in_link = _frame_in_link(scene, sole)
        geom.pos = in_link.act(np.array([*centre, SOLE_THICKNESS_M / 2]))
        geom.quat = pin.Quaternion(in_link.rotation).coeffs()[[3, 0, 1, 2]]
        _set_touches(geom, Touches.FLOOR)
        geom.solref = FLOOR_SOLREF
        shapes.append(Shape(name, ShapeRole.SOLE, link, sole=sole))
    return shapes


def sole_in_link(scene: Scene, sole: str) -> FloatArray:
    """A sole frame's placement (4, 4) in the link its box is on."""
    return np.asarray(_frame_in_link(scene, sole).homogeneous)


def _frame_in_link(scene: Scene, name: str) -> pin.SE3:
    """A frame's placement in the link it is on."""
    model = scene.model
    frame = model.frames[scene.frame_id(name)]
    link = model.frames[model.getFrameId(_link_of_frame(model, name))]
    return link.placement.inverse() * frame.placement


def tip_points(scene: Scene, chain_name: str) -> list[tuple[str, FloatArray, FloatArray]]:
    """Where a chain's hand touches the table: (frame, point (3,), normal (3,)) in that frame, m.

    Flush: each fingertip end (``fingertip_length_m`` beyond its origin, against the
    contact normal); point: the point frame's origin (its rounding's centre). The normal
    points away from the table at a contact.
    """
    chain = scene.chain(chain_name)
    if chain.fingertip_frames:
        contact = scene.contact_placements[chain_name]  # the contact frame in the gripper frame
        normal = contact.rotation[:, 2]
        model = scene.model
        data = model.createData()
        pin.framesForwardKinematics(model, data, scene.model_configuration(scene.locked_values))
        grip = data.oMf[scene.frame_id(chain.gripper_frame)]
        out = []
        for tip in chain.fingertip_frames:
            in_grip = grip.actInv(data.oMf[scene.frame_id(tip)])
            end = in_grip.translation - chain.fingertip_length_m * normal
            out.append((tip, in_grip.rotation.T @ (end - in_grip.translation), in_grip.rotation.T @ normal))
        return out
    return [(chain.point_frame, np.zeros(3), np.array([0.0, 0.0, 1.0]))]


def _tip_shapes(spec: mujoco.MjSpec, scene: Scene) -> list[Shape]:
    """A sphere at each place a chain's hand touches the table, its lowest point there."""
    shapes = []
    for chain in scene.chains:
        radius = TIP_RADIUS_M if chain.fingertip_frames else chain.point_radius_m
        for k, (frame, point, normal) in enumerate(tip_points(scene, chain.name)):
            link = _link_of_frame(scene.model, frame)
            in_link = _frame_in_link(scene, frame)
            centre = point + (radius * normal if chain.fingertip_frames else 0.0)
            name = f"tip:{chain.name}:{k}"
            geom = spec.body(link).add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0])
            geom.pos = in_link.act(centre)
            _set_touches(geom, Touches.TABLE)
            shapes.append(Shape(name, ShapeRole.TIP, link, chain=chain.name))
    return shapes


def _world_shapes(spec: mujoco.MjSpec, scene: Scene, table_top: FloatArray) -> list[Shape]:
    """The floor (z = 0) and the table box, its top face at ``table_top`` (4, 4)."""
    floor = spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE)
    floor.size = [FLOOR_HALF_SIZE_M, FLOOR_HALF_SIZE_M, 1.0]
    size = np.asarray(scene.table.size_m, dtype=float)
    table = spec.worldbody.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=size / 2)
    table.pos = table_top[:3, :3] @ np.array([0.0, 0.0, -size[2] / 2]) + table_top[:3, 3]
    table.quat = pin.Quaternion(table_top[:3, :3]).coeffs()[[3, 0, 1, 2]]
    for geom, bit in ((floor, Touches.FLOOR), (table, Touches.TABLE)):
        geom.contype = int(bit)
        geom.conaffinity = 0
        geom.friction = FRICTION
    floor.solref = FLOOR_SOLREF
    return [Shape("floor", ShapeRole.FLOOR, ""), Shape("table", ShapeRole.TABLE, "")]


def add_shapes(spec: mujoco.MjSpec, scene: Scene, table_top: FloatArray) -> tuple[Shape, ...]:
    """Add every geom of the scene to ``spec``: the robot's shapes, soles, tips, floor and table.

    Args:
        spec: A spec of the robot alone (its links as bodies, without geoms).
        scene: The nominal scene: shapes, frames and the foot rectangle (the shapes sit on
            links, so a perturbed robot's links carry them where its bodies are).
        table_top: World pose of the table's top face centre, (4, 4).

    Returns:
        Every geom added, in spec order.

    Example:
        >>> shapes = add_shapes(spec, scene, scene.table_pose)

    """
    return (
        *_world_shapes(spec, scene, table_top),
        *_robot_shapes(spec, scene),
        *_sole_shapes(spec, scene),
        *_tip_shapes(spec, scene),
    )
