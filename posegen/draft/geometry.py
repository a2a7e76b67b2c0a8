"""What ``posegen robot init`` reads from a robot's geometry: its vertices, and a hand's contact.

* vertices a joint carries (collision geometry, else visual), in any frame;
* a hand's contact: three frames on a flat face of its geometry that points down
  (a flush contact), else a point at its tip (a point contact), else, without any
  geometry, a point beyond the wrist at a stated guess.
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.io import native_output
from posegen.robot import FloatArray, FrameConfig

FLAT_TOL_M = 0.002  # vertices this close to a face's plane lie on it
FLAT_FILL = 0.5  # a face is flat when its touching vertices span this share of its box face in both directions
HAND_GUESS = 0.35  # without geometry, the tip is this share of the forearm beyond the wrist
TIP_RADIUS_M = 0.01  # guessed rounding of a point contact's tip
APART_M = 0.01  # the elbow is the last joint before the wrist at least this far from it


@dataclass(frozen=True)
class Geometry:
    """The robot's collision and visual geometry (meshes as triangles, not hulls)."""

    collision: pin.GeometryModel
    visual: pin.GeometryModel


@dataclass(frozen=True)
class HandContact:
    """The contact proposed for one hand."""

    frames: tuple[FrameConfig, ...]  # three for a flush contact, one for a point contact
    flush: bool
    touching: tuple[str, ...]  # other links of the hand (locked fingers, a palm fixed to it) that may touch the table
    radius_m: float  # a point's tip rounding (0 for flush)
    how: str  # what was found, for the draft's CHECK line


def load_geometry(model: pin.Model, urdf_xml: str, package_dirs: tuple[str, ...]) -> Geometry:
    """Both geometry models of a URDF.

    Raises:
        ConfigError: A mesh that cannot be loaded (not a mesh, or damaged): the loader's cause.

    """
    dirs = list(package_dirs)
    try:
        with native_output():  # the mesh loader's own lines, kept off the terminal
            return Geometry(
                collision=pin.buildGeomFromUrdfString(model, urdf_xml, pin.COLLISION, package_dirs=dirs),
                visual=pin.buildGeomFromUrdfString(model, urdf_xml, pin.VISUAL, package_dirs=dirs),
            )
    except (RuntimeError, ValueError) as exc:
        lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
        said = next((line for line in lines if line.startswith("message:")), lines[0] if lines else "")
        more = next((line for line in lines if line.startswith("Failed")), "")
        cause = " ".join(f"{said.removeprefix('message:').strip()} ({more})".split()) if more else said
        raise ConfigError(f"a mesh of the robot cannot be loaded: {cause}") from exc


def vertices(model: pin.Model, data: pin.Data, geom: pin.GeometryModel, joints: set[int], frame: pin.SE3) -> FloatArray:
    """Vertices of the geometry these joints carry, in ``frame`` (data's kinematics). Shape (k, 3).

    Primitives count by a few points (:func:`_points`).
    """
    out = []
    for obj in geom.geometryObjects:
        if obj.parentJoint not in joints:
            continue
        points = _points(obj.geometry)
        if len(points) == 0:
            continue
        placement = frame.actInv(data.oMi[obj.parentJoint] * obj.placement)
        out.append(points @ placement.rotation.T + placement.translation)
    return np.vstack(out) if out else np.zeros((0, 3))


def carried(model: pin.Model, data: pin.Data, geometry: Geometry, joints: set[int], frame: pin.SE3) -> FloatArray:
    """The joints' collision vertices in ``frame``, else their visual ones. Shape (k, 3)."""
    points = vertices(model, data, geometry.collision, joints, frame)
    return points if len(points) else vertices(model, data, geometry.visual, joints, frame)


def _points(shape: object) -> FloatArray:
    """Points standing for a shape: a mesh's vertices, a box's corners, a round shape's extremes."""
    if hasattr(shape, "num_vertices") and hasattr(shape, "vertices"):
        return np.asarray(shape.vertices(), dtype=float).reshape(-1, 3)
    if hasattr(shape, "points") and hasattr(shape, "num_points"):
        return np.asarray(shape.points(), dtype=float).reshape(-1, 3)
    if isinstance(shape, coal.Box):
        half = np.asarray(shape.halfSide, dtype=float)
        return np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    radius = float(getattr(shape, "radius", 0.0))
    half_length = float(getattr(shape, "halfLength", 0.0))
    ends = [np.array([0.0, 0.0, -half_length]), np.array([0.0, 0.0, half_length])]
    return np.array([end + radius * d for end in ends for d in np.vstack([np.eye(3), -np.eye(3)])])


def forearm(data: pin.Data, arm: list[int]) -> FloatArray:
    """(3,) m, world: from the elbow to the arm's last joint (the wrist), at the posture of ``data``.

    The elbow is the last joint before the wrist at least ``APART_M`` from it; the vector is
    zero when there is none.

    Example:
        >>> forearm(data, body.arms[0])  # a hanging arm: down
        array([ 0.  ,  0.  , -0.25])

    """
    wrist = data.oMi[arm[-1]].translation
    elbow = next(
        (data.oMi[j].translation for j in reversed(arm) if np.linalg.norm(data.oMi[j].translation - wrist) > APART_M),
        wrist,
    )
    return np.array(wrist - elbow, dtype=float)


def link_of_joint(model: pin.Model, joint: int) -> str:
    """The link a joint moves (its first body frame)."""
    for frame in model.frames:
        if frame.parentJoint == joint and frame.type == pin.FrameType.BODY:
            return str(frame.name)
    return str(model.names[joint])


def hand_contact(
    model: pin.Model,
    data: pin.Data,
    geometry: Geometry,
    chain: str,
    hand: str,
    forearm: FloatArray,
    fingers: set[int],
) -> HandContact:
    """The contact proposed for a hand, at the posture of ``data``.

    Args:
        model: The robot model.
        data: Its kinematics at the reference posture (fingers at their locked values).
        geometry: Its geometry.
        chain: The chain's name ("left", "right"), for the frames' names.
        hand: The hand's link.
        forearm: (3,) world vector from the elbow-side joint to the wrist (m).
        fingers: The locked joints below the hand (their geometry is part of the hand).

    """
    frame_id = model.getFrameId(hand)
    placement = data.oMf[frame_id]
    joint = model.frames[frame_id].parentJoint
    points = carried(model, data, geometry, {joint, *fingers}, placement)  # (k, 3) in the hand frame
    along = placement.rotation.T @ forearm / max(float(np.linalg.norm(forearm)), 1e-9)  # in the hand frame
    if len(points) == 0:
        tip = along * HAND_GUESS * float(np.linalg.norm(forearm))
        frame = FrameConfig(f"{chain}_tip", hand, round3(tip), _rpy_deg(along))
        return HandContact(
            (frame,),
            False,
            (),
            TIP_RADIUS_M,
            f"no geometry: a point {HAND_GUESS:.0%} of the forearm's length beyond the wrist, tip radius "
            f"{1e3 * TIP_RADIUS_M:.0f} mm",
        )
    down = placement.rotation.T @ np.array([0.0, 0.0, -1.0])  # in the hand frame
    face = _flat_face(points, down)
    if face is not None:
        frames = tuple(FrameConfig(f"{chain}_touch_{k + 1}", hand, round3(p)) for k, p in enumerate(face))
        axis = int(np.argmax(np.abs(down)))
        on_face = _face_links(model, data, geometry, {joint, *fingers}, placement, axis, float(face[0][axis]))
        how = "a flat face of the hand's geometry pointing down"
        return HandContact(frames, True, tuple(sorted(on_face - {hand})), 0.0, how)
    owner, tip = _tip(model, data, geometry, {joint, *fingers}, placement, along)
    link_pose = data.oMf[model.getFrameId(owner)]
    local_tip = link_pose.actInv(placement.act(tip - along * TIP_RADIUS_M))
    local_along = link_pose.rotation.T @ placement.rotation @ along
    frame = FrameConfig(f"{chain}_tip", owner, round3(local_tip), _rpy_deg(local_along))
    fingers_links = {
        str(model.frames[o.parentFrame].name)
        for o in (*geometry.collision.geometryObjects, *geometry.visual.geometryObjects)
        if o.parentJoint in fingers
    }
    return HandContact(
        (frame,),
        False,
        tuple(sorted(fingers_links - {owner})),
        TIP_RADIUS_M,
        f"no flat face: a point at the hand's tip (its farthest vertex along the forearm, on {owner}), "
        f"tip radius {1e3 * TIP_RADIUS_M:.0f} mm",
    )


def _tip(
    model: pin.Model, data: pin.Data, geometry: Geometry, joints: set[int], frame: pin.SE3, along: FloatArray
) -> tuple[str, FloatArray]:
    """The link carrying the vertex farthest along ``along``, and that vertex (in ``frame``)."""
    best: tuple[float, str, FloatArray] | None = None
    for source in (geometry.collision, geometry.visual):
        for obj in source.geometryObjects:
            if obj.parentJoint not in joints:
                continue
            points = vertices(model, data, _single(source, obj), {int(obj.parentJoint)}, frame)
            if len(points) == 0:
                continue
            k = int(np.argmax(points @ along))
            if best is None or points[k] @ along > best[0]:
                best = (float(points[k] @ along), str(model.frames[obj.parentFrame].name), points[k])
        if best is not None:
            break
    assert best is not None, "called with geometry"
    return best[1], best[2]


def _face_links(
    model: pin.Model, data: pin.Data, geometry: Geometry, joints: set[int], frame: pin.SE3, axis: int, level: float
) -> frozenset[str]:
    """The links whose geometry (as :func:`carried` reads it) reaches a face: ``axis`` at ``level`` in ``frame``.

    A palm fixed below the hand's link, or locked fingers, whose vertices make the face touch
    the table with it (``touching_links``).
    """
    source = geometry.collision if len(vertices(model, data, geometry.collision, joints, frame)) else geometry.visual
    out = set()
    for obj in source.geometryObjects:
        if obj.parentJoint not in joints:
            continue
        points = vertices(model, data, _single(source, obj), {int(obj.parentJoint)}, frame)
        if len(points) and np.any(np.abs(points[:, axis] - level) < FLAT_TOL_M):
            out.add(str(model.frames[obj.parentFrame].name))
    return frozenset(out)


def _single(source: pin.GeometryModel, obj: pin.GeometryObject) -> pin.GeometryModel:
    one = pin.GeometryModel()
    one.addGeometryObject(obj)
    return one


def _rpy_deg(along: FloatArray) -> tuple[float, float, float]:
    """A point frame's orientation in the hand frame: z back up the forearm (away from the table)."""
    rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), -along).toRotationMatrix()
    return round3(np.rad2deg(pin.rpy.matrixToRpy(rotation)))


def _flat_face(points: FloatArray, down: FloatArray) -> list[FloatArray] | None:
    """Three points on the face of the vertices' box that points ``down``, if that face is flat.

    Flat: the vertices within FLAT_TOL_M of the face's plane span at least FLAT_FILL of
    the face in both of its directions.
    """
    low, high = points.min(axis=0), points.max(axis=0)
    axis = int(np.argmax(np.abs(down)))
    level = high[axis] if down[axis] > 0 else low[axis]
    on = points[np.abs(points[:, axis] - level) < FLAT_TOL_M]
    others = [a for a in range(3) if a != axis]
    span = high[others] - low[others]
    if len(on) < 3 or np.any(span <= 0):
        return None
    covered = on[:, others].max(axis=0) - on[:, others].min(axis=0)
    if np.any(covered < FLAT_FILL * span):
        return None
    centre = (on.min(axis=0) + on.max(axis=0)) / 2
    spread = 0.3 * covered
    out = []
    for u, v in ((-1.0, -1.0), (-1.0, 1.0), (1.0, 0.0)):
        p = centre.copy()
        p[axis] = level
        p[others[0]] += u * spread[0]
        p[others[1]] += v * spread[1]
        out.append(p)
    return out


def round3(v: FloatArray) -> tuple[float, float, float]:
    """A 3-vector rounded to 0.1 mm (or 1e-4 of its unit), without -0.0."""
    return (round(float(v[0]), 4) + 0.0, round(float(v[1]), 4) + 0.0, round(float(v[2]), 4) + 0.0)
