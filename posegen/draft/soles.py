"""A foot's sole as ``posegen robot init`` finds it: its frame and its footprint.

* the sole frame: a link of the foot (fixed to it) with z up and x forward at the lowest
  point under the ankle when there is one (TALOS's ``*_sole_link``), else a frame declared
  there;
* the footprint (``stance.foot_x_m``, ``foot_y_m``): the lowest vertices of the foot's
  geometry, collision, else visual, and the visual sole's too when it reaches the floor
  beside the collision shapes (a sole mesh wider than the two rods under it:
  :func:`sole_vertices`);
* a foot without any geometry: a rectangle in proportion to the leg, below the ankle by a
  share of the leg's length, and a box over it (:func:`foot_box`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.draft.geometry import Geometry, link_of_joint, round3, vertices
from posegen.errors import ConfigError
from posegen.robot import Box, FloatArray, FrameConfig, convex_hull_clockwise, polygon_margin

SOLE_VERTEX_TOL_M = 0.005  # foot vertices this close to the lowest one make the footprint
SOLE_VISUAL_GAP_M = 0.02  # a sole mesh whose lowest vertex is this close above the collision's counts in the footprint
SOLE_FRAME_TOL_M = 0.005  # an existing link this close to the sole point is the sole frame
SOLE_AXIS_COS = 0.999  # ... when its z axis is up and its x axis forward (the footprint is read along its axes)
FOOT_LENGTH = 0.28  # a foot without geometry: this share of the leg's length
FOOT_WIDTH = 0.12
ANKLE_HEIGHT = 0.12  # a foot without geometry: its sole this share of the leg's length below the ankle
FOOT_BOX_M = 0.02  # thickness of the box given to a foot without geometry
FOOT_MAX_M = 1.0  # a footprint longer or wider than this is no humanoid's (a mesh in mm, not m)
FOOT_MIN_M = 0.01  # ... nor one shorter or narrower than this (a mesh in metres scaled by 0.001)


@dataclass(frozen=True)
class Sole:
    """One foot's sole as found."""

    frame: str  # the sole frame's name
    declared: FrameConfig | None  # the frame to declare in the config (None: the robot's own link)
    foot_link: str
    foot_joint: int
    x_m: tuple[float, float]  # footprint in the sole frame
    y_m: tuple[float, float]
    from_geometry: bool  # False: guessed from the leg's length (a CHECK line)


def find_sole(
    model: pin.Model, data: pin.Data, geometry: Geometry, side: str, foot: int, leg_length: float, heading: pin.SE3
) -> Sole:
    """A foot's sole frame (the robot's, or one to declare) and its footprint, at the posture of ``data``."""
    ankle = data.oMi[foot].translation
    flat = pin.SE3(heading.rotation, np.array([ankle[0], ankle[1], 0.0]))
    collision = vertices(model, data, geometry.collision, {foot}, flat)  # (k, 3) in a level frame under the ankle
    level, low = sole_vertices(collision, vertices(model, data, geometry.visual, {foot}, flat))
    link = link_of_joint(model, foot)
    if len(low) == 0:
        length, width = FOOT_LENGTH * leg_length, FOOT_WIDTH * leg_length
        x = (round(-0.3 * length, 3), round(0.7 * length, 3))
        y = (round(-width / 2, 3), round(width / 2, 3))
        sole_world = pin.SE3(heading.rotation, ankle - np.array([0.0, 0.0, ANKLE_HEIGHT * leg_length]))
        from_geometry = False
    else:
        sole_world = pin.SE3(heading.rotation, np.array([ankle[0], ankle[1], level]))
        x = (round(float(low[:, 0].min()), 3), round(float(low[:, 0].max()), 3))
        y = (round(float(low[:, 1].min()), 3), round(float(low[:, 1].max()), 3))
        from_geometry = True
        if max(x[1] - x[0], y[1] - y[0]) > FOOT_MAX_M:
            raise ConfigError(
                f"link '{link}': its foot geometry spans {x[1] - x[0]:g} x {y[1] - y[0]:g} m, not a foot: meshes in "
                'millimetres? give each <mesh> scale="0.001 0.001 0.001"'
            )
        if min(x[1] - x[0], y[1] - y[0]) < FOOT_MIN_M:
            raise ConfigError(
                f"link '{link}': its foot geometry spans {x[1] - x[0]:g} x {y[1] - y[0]:g} m, not a foot: meshes "
                'scaled down twice (a <mesh scale="0.001 0.001 0.001"> on a mesh in metres)? check the scales'
            )
    for f, frame in enumerate(model.frames):
        if frame.parentJoint != foot or frame.type != pin.FrameType.BODY:
            continue
        if model.frames[frame.parentFrame].type != pin.FrameType.FIXED_JOINT:
            continue  # a joint's own link: calibration moves its joint, not a sole placement
        pose = data.oMf[f]
        forward = float(pose.rotation[:, 0] @ heading.rotation[:, 0])
        level = pose.rotation[2, 2] > SOLE_AXIS_COS and forward > SOLE_AXIS_COS
        if level and np.linalg.norm(pose.translation - sole_world.translation) < SOLE_FRAME_TOL_M:
            shift = pose.actInv(sole_world)  # the footprint, read in the robot's own sole frame
            x = (round(x[0] + float(shift.translation[0]), 3), round(x[1] + float(shift.translation[0]), 3))
            y = (round(y[0] + float(shift.translation[1]), 3), round(y[1] + float(shift.translation[1]), 3))
            return Sole(str(frame.name), None, link, foot, x, y, from_geometry)
    local = data.oMf[model.getFrameId(link)].actInv(sole_world)
    rpy = np.rad2deg(pin.rpy.matrixToRpy(local.rotation))
    declared = FrameConfig(f"{side}_sole", link, round3(local.translation), round3(rpy))
    return Sole(declared.name, declared, link, foot, x, y, from_geometry)


def sole_vertices(collision: FloatArray, visual: FloatArray) -> tuple[float, FloatArray]:
    """A foot's sole level (m) and the vertices its footprint spans (k, 3), from its collision and visual vertices.

    The level is the lowest collision vertex (else visual); the footprint spans the vertices
    within SOLE_VERTEX_TOL_M of it, and the visual geometry's own lowest vertices when its
    lowest lies within SOLE_VISUAL_GAP_M above that level: a sole mesh wider than the
    collision shapes under it (two thin rods) is the foot the robot stands on.

    Example:
        >>> rods = np.array([[-0.1, y, 0.0] for y in (-0.02, 0.02)] + [[0.1, y, 0.0] for y in (-0.02, 0.02)])
        >>> sole = np.array([[x, y, 0.003] for x in (-0.11, 0.11) for y in (-0.05, 0.05)])
        >>> np.ptp(sole_vertices(rods, sole)[1][:, 1])  # the sole's 10 cm, not the rods' 4 cm
        0.1

    """
    points = collision if len(collision) else visual
    if len(points) == 0:
        return 0.0, points
    level = float(points[:, 2].min())
    low = points[points[:, 2] < level + SOLE_VERTEX_TOL_M]
    if len(collision) and len(visual) and float(visual[:, 2].min()) < level + SOLE_VISUAL_GAP_M:
        bottom = max(level, float(visual[:, 2].min()))
        low = np.vstack([low, visual[visual[:, 2] < bottom + SOLE_VERTEX_TOL_M]])
    return level, low


def sole_pose(model: pin.Model, data: pin.Data, sole: Sole) -> pin.SE3:
    """A sole frame's world pose in ``data`` (the robot's frame, or the one to declare)."""
    if sole.declared is None:
        return data.oMf[model.getFrameId(sole.frame)].copy()
    frame = sole.declared
    local = pin.SE3(pin.rpy.rpyToMatrix(*np.deg2rad(frame.rpy_deg)), np.array(frame.xyz_m))
    return data.oMf[model.getFrameId(frame.parent)] * local


def floor_height(model: pin.Model, data: pin.Data, soles: list[Sole]) -> float:
    """The lowest sole's height (m) in ``data``: the floor."""
    return min(float(sole_pose(model, data, s).translation[2]) for s in soles)


def foot_box(model: pin.Model, data: pin.Data, sole: Sole) -> Box:
    """A box over a sole's footprint, FOOT_BOX_M thick, in the foot link's frame."""
    pose = sole_pose(model, data, sole)
    centre = np.array([sum(sole.x_m) / 2, sum(sole.y_m) / 2, FOOT_BOX_M / 2])
    local = data.oMf[model.getFrameId(sole.foot_link)].actInv(pose)
    size = (round(sole.x_m[1] - sole.x_m[0], 3), round(sole.y_m[1] - sole.y_m[0], 3), FOOT_BOX_M)
    rpy = round3(np.rad2deg(pin.rpy.matrixToRpy(local.rotation)))
    return Box(sole.foot_link, round3(local.act(centre)), size, rpy)


def com_margin(model: pin.Model, q: FloatArray, soles: list[Sole]) -> float:
    """How far (m) the CoM at ``q`` (nq,) lies inside the soles' support polygon (negative: outside).

    The polygon spans the footprints' corners at their poses in ``q``, as the scene's
    (:func:`posegen.robot.stand`) does with the soles flattened on the floor.

    Example:
        >>> com_margin(model, q, legs.soles)  # a balanced stance: a few centimetres
        0.041

    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    corners = [
        sole_pose(model, data, sole).act(np.array([x, y, 0.0]))[:2]
        for sole in soles
        for x in sole.x_m
        for y in sole.y_m
    ]
    com = pin.centerOfMass(model, data, q)  # (3,) m, world
    return polygon_margin(convex_hull_clockwise(np.array(corners)), com[:2])
