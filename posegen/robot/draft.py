"""A starting config for a humanoid, found from its description alone (``posegen robot init``).

Everything here is a heuristic a user then checks and edits; it reads structure, never
names:

* legs: the two branches from the root that reach the floor at the reference posture
  (the SRDF's first group state, else every joint at 0); soles: their lowest links;
  feet: the lowest vertices of the geometry the sole's joint carries;
* arms: the two longest chains of the upper body, up to where they branch into light
  parts only (fingers: under 1 % of the robot's mass), which are locked, like every joint
  off the legs and arms (head, neck). A gripper joint that ends a chain stays in it:
  lock it by hand;
* contact: three frames declared on the face of the hand's geometry that points down at
  the reference posture (a flush contact to edit into the real one);
* table: in front of the shoulders, its top about half an arm's length below them;
* velocity limits the URDF lacks (0) or gives implausibly (> 20 rad/s), and links whose
  collision geometry does not contain their centre of mass (a description whose meshes
  do not match its kinematics) with capsules to replace them;
* collision pairs to disable: :mod:`posegen.robot.collision_matrix`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot.additions import Capsule, CollisionConfig, FrameConfig
from posegen.robot.collision_geometry import add_self_pairs, robot_geometry
from posegen.robot.collision_matrix import PairSurvey, survey_pairs
from posegen.robot.config import RobotSource
from posegen.robot.description import resolve_source
from posegen.robot.geometry import FloatArray

LIGHT_FRACTION = 0.01  # a branch lighter than this share of the robot's mass is an end effector's part
FLOOR_TOL_M = 0.02  # a branch whose lowest frame is this close to the lowest one reaches the floor
SOLE_VERTEX_TOL_M = 0.005  # foot vertices this close to the lowest one make the footprint
IMPLAUSIBLE_SPEED_RAD_S = 20.0
PLACEHOLDER_SPEED_RAD_S = 1.0
COM_OUTSIDE_M = 0.02  # a link's CoM this far outside its collision geometry's box: suspicious geometry
TABLE_DEPTH = 0.7  # table top this many arm lengths below the shoulders, its centre as far in front
COLLISION_MARGIN_M = 0.005


@dataclass(frozen=True)
class Chain:
    """One arm, as found."""

    name: str  # "left" or "right"
    sole: str
    hand: str  # the link of the last arm joint
    joints: tuple[str, ...]  # shoulder to wrist
    touch: tuple[FrameConfig, ...]  # three frames declared on the hand's downward face


@dataclass(frozen=True)
class Draft:
    """What ``posegen robot init`` found about a robot."""

    robot: str
    srdf: str | None  # the SRDF named in the config (None: the loader's)
    reference_posture: str  # "" when the SRDF has no group state
    soles: tuple[str, str]  # left, right
    foot_x_m: tuple[float, float]
    foot_y_m: tuple[float, float]
    floor_contact: tuple[str, ...]
    chains: tuple[Chain, Chain]
    locked: dict[str, float]
    velocity_limits: dict[str, float]  # placeholders for the URDF's missing or implausible ones
    urdf_velocity: dict[str, float]  # what the URDF said for those
    shapes: tuple[Capsule, ...]
    misplaced: dict[str, float]  # link -> m its CoM lies outside its collision geometry
    table_center_m: tuple[float, float, float]
    table_size_m: tuple[float, float, float]
    spots_x_m: tuple[float, ...]
    spots_y_m: tuple[float, ...]
    reach_m: float
    survey: PairSurvey
    notes: tuple[str, ...] = field(default=())


def draft_robot(robot: str, srdf: str | None = None, samples: int = 400, seed: int = 0) -> Draft:
    """Study an example-robot-data humanoid and draft its config.

    Raises:
        ConfigError: Unknown robot, no SRDF, or a structure that is not two legs and two arms.

    """
    files = resolve_source(RobotSource(example_robot_data=robot, srdf=srdf))
    text = files.urdf.read_text()
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    pin.loadReferenceConfigurations(model, str(files.srdf), False)
    states = [str(e.key()) for e in model.referenceConfigurations]
    reference = np.array(model.referenceConfigurations[states[0]]) if states else pin.neutral(model)
    data = model.createData()
    pin.framesForwardKinematics(model, data, reference)
    children = {j: [c for c in range(2, model.njoints) if model.parents[c] == j] for j in range(model.njoints)}
    notes: list[str] = []

    def subtree(j: int) -> list[int]:
        out = [j]
        for c in children[j]:
            out += subtree(c)
        return out

    def mass(joints: list[int]) -> float:
        return float(sum(model.inertias[j].mass for j in joints))

    total = mass(list(range(1, model.njoints)))
    lowest = {b: min(_link_heights(model, data, set(subtree(b)))) for b in children[1]}
    floor = min(lowest.values())
    legs = [b for b in children[1] if lowest[b] < floor + FLOOR_TOL_M]
    if len(legs) != 2:
        raise ConfigError(f"{robot}: expected two legs reaching the floor at the reference posture, found {len(legs)}")
    soles = [_sole(model, data, set(subtree(b))) for b in legs]
    mid = _heading(data, model, soles)
    soles.sort(key=lambda s: -mid.actInv(data.oMf[model.getFrameId(s)]).translation[1])  # left (+y) first
    paths: list[list[int]] = []
    for branch in children[1]:
        if branch not in legs:
            _arm_paths(branch, [], children, subtree, mass, total, paths)
    paths.sort(key=len, reverse=True)
    if len(paths) < 2:
        raise ConfigError(f"{robot}: expected two arms in the upper body, found {len(paths)}")
    arms = sorted(paths[:2], key=lambda p: -mid.actInv(data.oMi[p[-1]]).translation[1])
    kept = {j for b in legs for j in subtree(b)} | {j for p in arms for j in p}
    locked = {
        str(model.names[j]): float(np.clip(reference[model.joints[j].idx_q], *_limits(model, j)))
        for j in range(2, model.njoints)
        if model.joints[j].nq == 1 and j not in kept
    }
    geom = robot_geometry(model, text, files.package_dirs, CollisionConfig(), convex=False)
    foot = _footprint(model, data, geom, soles)
    shared = set(arms[0]) & set(arms[1])  # the torso
    chains = []
    for name, sole, path in zip(("left", "right"), soles, arms, strict=True):
        hand = _link_of_joint(model, path[-1])
        joints = tuple(str(model.names[j]) for j in path if j not in shared)
        chains.append(Chain(name, sole, hand, joints, _touch_frames(model, data, geom, name, hand)))
    speeds = {}
    urdf_speed = {}
    for j in sorted(kept - {1}):
        if model.joints[j].nq != 1:
            continue
        v = float(model.velocityLimit[model.joints[j].idx_v])
        if not 0 < v <= IMPLAUSIBLE_SPEED_RAD_S:
            speeds[str(model.names[j])] = PLACEHOLDER_SPEED_RAD_S
            urdf_speed[str(model.names[j])] = v
    if speeds:
        notes.append(f"{len(speeds)} joints have no plausible URDF velocity limit: placeholders of 1 rad/s to edit")
    misplaced = _misplaced_geometry(model, geom)
    shapes = tuple(s for link in misplaced for s in _skeleton(model, link))
    if misplaced:
        notes.append(
            f"{len(misplaced)} links' collision geometry misses their centre of mass (up to "
            f"{1e3 * max(misplaced.values()):.0f} mm): replaced by capsules along the kinematics; check them"
        )
    shoulder = data.oMi[model.getJointId(chains[0].joints[0])].translation
    reach = _arm_length(model, data, chains[0])
    table = _table(mid, shoulder, reach)
    survey_geom = robot_geometry(model, text, files.package_dirs, CollisionConfig(shapes=shapes), convex=True)
    add_self_pairs(model, survey_geom, str(files.srdf), CollisionConfig())
    held = reference.copy()
    for name, value in locked.items():
        held[model.joints[model.getJointId(name)].idx_q] = value

    def sample(rng: np.random.Generator) -> FloatArray:
        q = pin.neutral(model)
        for j in range(2, model.njoints):
            if model.joints[j].nq == 1:
                q[model.joints[j].idx_q] = rng.uniform(*_limits(model, j))
        for name, value in locked.items():
            q[model.joints[model.getJointId(name)].idx_q] = value
        return np.asarray(q)

    survey = survey_pairs(model, survey_geom, held, sample, COLLISION_MARGIN_M, samples, seed)
    return Draft(
        robot=robot,
        srdf=srdf,
        reference_posture=states[0] if states else "",
        soles=(soles[0], soles[1]),
        foot_x_m=foot[0],
        foot_y_m=foot[1],
        floor_contact=foot[2],
        chains=(chains[0], chains[1]),
        locked=locked,
        velocity_limits=speeds,
        urdf_velocity=urdf_speed,
        shapes=shapes,
        misplaced=misplaced,
        table_center_m=table[0],
        table_size_m=table[1],
        spots_x_m=table[2],
        spots_y_m=table[3],
        reach_m=reach,
        survey=survey,
        notes=tuple(notes),
    )


def _limits(model: pin.Model, joint: int) -> tuple[float, float]:
    i = model.joints[joint].idx_q
    return float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])


def _link_heights(model: pin.Model, data: pin.Data, joints: set[int]) -> list[float]:
    frames = [f for f in range(len(model.frames)) if model.frames[f].parentJoint in joints]
    return [float(data.oMf[f].translation[2]) for f in frames]


def _sole(model: pin.Model, data: pin.Data, joints: set[int]) -> str:
    """A leg's sole: its lowest link with z up; among equals the nearest under the ankle, the last declared."""
    ankle = data.oMi[max(joints)].translation
    links = [
        f
        for f in range(len(model.frames))
        if model.frames[f].parentJoint in joints
        and model.frames[f].type == pin.FrameType.BODY
        and data.oMf[f].rotation[2, 2] > 0.9
    ]
    if not links:
        raise ConfigError(f"no link with its z axis up below joint '{model.names[min(joints)]}'")
    low = min(float(data.oMf[f].translation[2]) for f in links)
    links = [f for f in links if data.oMf[f].translation[2] < low + 1e-3]
    near = min(float(np.linalg.norm((data.oMf[f].translation - ankle)[:2])) for f in links)
    links = [f for f in links if np.linalg.norm((data.oMf[f].translation - ankle)[:2]) < near + 1e-3]
    return str(model.frames[links[-1]].name)


def _heading(data: pin.Data, model: pin.Model, soles: list[str]) -> pin.SE3:
    """A level frame between the soles, x along their mean heading (the robot's forward)."""
    poses = [data.oMf[model.getFrameId(s)] for s in soles]
    x = sum(p.rotation[:, 0] for p in poses)
    yaw = float(np.arctan2(x[1], x[0]))
    rotation = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
    middle = sum(p.translation for p in poses) / 2
    return pin.SE3(rotation, np.array([middle[0], middle[1], min(p.translation[2] for p in poses)]))


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


def _link_of_joint(model: pin.Model, joint: int) -> str:
    """The link a joint moves (its first body frame)."""
    for frame in model.frames:
        if frame.parentJoint == joint and frame.type == pin.FrameType.BODY:
            return str(frame.name)
    raise ConfigError(f"joint '{model.names[joint]}' moves no link")


def _vertices(model: pin.Model, data: pin.Data, geom: pin.GeometryModel, joint: int, frame: pin.SE3) -> FloatArray:
    """Collision vertices carried by one joint, in ``frame``. Shape (k, 3)."""
    geom_data = pin.GeometryData(geom)
    pin.updateGeometryPlacements(model, data, geom, geom_data)
    out = []
    for i, obj in enumerate(geom.geometryObjects):
        if obj.parentJoint != joint or not hasattr(obj.geometry, "num_vertices"):
            continue
        points = np.asarray(obj.geometry.vertices(), dtype=float)  # (k, 3) in the geometry's frame
        placement = frame.actInv(geom_data.oMg[i])
        out.append(points @ placement.rotation.T + placement.translation)
    return np.vstack(out) if out else np.zeros((0, 3))


def _footprint(
    model: pin.Model, data: pin.Data, geom: pin.GeometryModel, soles: list[str]
) -> tuple[tuple[float, float], tuple[float, float], tuple[str, ...]]:
    """Sole rectangle (the lowest vertices' box, in the sole frame, both feet) and the feet's links."""
    lows, links = [], []
    for sole in soles:
        frame = model.frames[model.getFrameId(sole)]
        points = _vertices(model, data, geom, frame.parentJoint, data.oMf[model.getFrameId(sole)])
        if len(points) == 0:
            raise ConfigError(f"sole '{sole}' carries no collision geometry to measure the foot from")
        lows.append(points[points[:, 2] < points[:, 2].min() + SOLE_VERTEX_TOL_M])
        carried = [o for o in geom.geometryObjects if o.parentJoint == frame.parentJoint]
        links += [str(model.frames[o.parentFrame].name) for o in carried]
    # one rectangle for both feet: the part common to both (mirrored feet differ in y)
    x = (max(float(p[:, 0].min()) for p in lows), min(float(p[:, 0].max()) for p in lows))
    y = (max(float(p[:, 1].min()) for p in lows), min(float(p[:, 1].max()) for p in lows))
    return (round(x[0], 3), round(x[1], 3)), (round(y[0], 3), round(y[1], 3)), tuple(dict.fromkeys(links))


def _touch_frames(
    model: pin.Model, data: pin.Data, geom: pin.GeometryModel, chain: str, hand: str
) -> tuple[FrameConfig, ...]:
    """Three frames on the face of the hand's geometry box that points down at the reference."""
    frame_id = model.getFrameId(hand)
    placement = data.oMf[frame_id]
    points = _vertices(model, data, geom, model.frames[frame_id].parentJoint, placement)
    if len(points) == 0:
        points = np.zeros((1, 3))
    low, high = points.min(axis=0), points.max(axis=0)
    down = placement.rotation.T @ np.array([0.0, 0.0, -1.0])  # world down, in the hand frame
    axis = int(np.argmax(np.abs(down)))
    face = high[axis] if down[axis] > 0 else low[axis]
    centre = (low + high) / 2
    others = [a for a in range(3) if a != axis]
    spread = 0.3 * (high - low)
    corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 0.0)]
    frames = []
    for k, (u, v) in enumerate(corners):
        xyz = centre.copy()
        xyz[axis] = face
        xyz[others[0]] += u * spread[others[0]]
        xyz[others[1]] += v * spread[others[1]]
        frames.append(FrameConfig(f"{chain}_touch_{k + 1}", hand, tuple(round(float(c), 4) for c in xyz)))  # type: ignore[arg-type]
    return tuple(frames)


def _arm_length(model: pin.Model, data: pin.Data, chain: Chain) -> float:
    """Shoulder to the hand's touch face: the sum of the distances between its joints (m)."""
    joints = [model.getJointId(j) for j in chain.joints]
    length = sum(float(np.linalg.norm(model.jointPlacements[j].translation)) for j in joints[1:])
    hand = data.oMf[model.getFrameId(chain.hand)]
    touch = np.mean([hand.act(np.array(f.xyz_m)) for f in chain.touch], axis=0)
    return length + float(np.linalg.norm(touch - data.oMi[joints[-1]].translation))


def _table(
    heading: pin.SE3, shoulder: FloatArray, reach: float
) -> tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, ...], tuple[float, ...]]:
    """A table TABLE_DEPTH arm lengths in front of and below the shoulders, heights from the floor."""
    local = heading.actInv(shoulder)
    centre = heading.act(np.array([local[0] + TABLE_DEPTH * reach, 0.0, 0.0]))
    height = local[2] - TABLE_DEPTH * reach  # the heading frame lies on the floor
    length, width = round(0.5 * reach, 2), round(2 * (abs(float(local[1])) + 0.5 * reach), 2)
    spots_x = tuple(round(v, 3) for v in (-0.3 * length, 0.0, 0.3 * length))
    half = 0.4 * width
    spots_y = tuple(round(float(v), 3) for v in np.linspace(-half, half, 6))
    top = (round(float(centre[0]), 3), round(float(centre[1]), 3), round(float(height), 3))
    return top, (length, width, 0.04), spots_x, spots_y


def _misplaced_geometry(model: pin.Model, geom: pin.GeometryModel) -> dict[str, float]:
    """Links whose centre of mass lies outside their collision geometry's box, by how far (m)."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    out = {}
    for joint in range(1, model.njoints):
        inertia = model.inertias[joint]
        if inertia.mass <= 0:
            continue
        points = _vertices(model, data, geom, joint, data.oMi[joint])
        if len(points) == 0:
            continue
        gap = np.maximum(0.0, np.maximum(points.min(axis=0) - inertia.lever, inertia.lever - points.max(axis=0)))
        distance = float(np.linalg.norm(gap))
        if distance > COM_OUTSIDE_M:
            out[_link_of_joint(model, joint)] = round(distance, 3)
    return out


def _skeleton(model: pin.Model, link: str) -> list[Capsule]:
    """Capsules from a link's joint to each child joint (or through its CoM, for an end link)."""
    frame = model.frames[model.getFrameId(link)]
    joint = frame.parentJoint
    to_link = frame.placement.inverse()  # joint frame -> link frame
    ends = [model.jointPlacements[c].translation for c in range(2, model.njoints) if model.parents[c] == joint]
    if not ends:
        ends = [2.0 * model.inertias[joint].lever]
    origin = to_link.translation
    out = []
    for end in ends:
        tip = to_link.act(np.asarray(end))
        length = float(np.linalg.norm(tip - origin))
        radius = round(float(np.clip(0.25 * length, 0.02, 0.06)), 3)
        out.append(Capsule(link, _round3(origin), _round3(tip), radius))
    return out


def _round3(v: FloatArray) -> tuple[float, float, float]:
    return (round(float(v[0]), 4) + 0.0, round(float(v[1]), 4) + 0.0, round(float(v[2]), 4) + 0.0)  # no -0.0
