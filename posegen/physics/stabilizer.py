"""The balance stabilizer: DCM feedback realised by foot admittance (the ankle strategy).

Position-controlled humanoids balance by regulating the ZMP with their feet (Kajita et
al., 2010): a desired ZMP is computed from the divergent component of motion (DCM) of
the centre of mass, and each foot gives way to the wrench it carries beyond its share
of that ZMP, so the ankles lean the body until the floor's wrench is the desired one.

* **DCM feedback.** The CoM ``c`` and its velocity are estimated on the nominal model
  from the encoders and the IMU (:class:`NominalRobot`), the model's CoM corrected by a
  bias the soles' sensors measure (below); ``xi = c + c' / omega``,
  ``omega = sqrt(g / z_c)``. The desired ZMP is
  ``p_d = p_ref + (1 + K_DCM / omega) (xi - xi_ref)``, kept ``ZMP_MARGIN_M`` inside the
  support polygon, with ``xi_ref = c_ref + c_ref' / omega``. The references are the
  plan's: its CoM and CoM velocity, and its ZMP (the commanded motion's, from the whole
  robot's inverse dynamics), moved with the soles from where the plan puts them to where
  the robot believes it stands (:class:`PlannedFeet`: the true legs put the second sole 1-5
  cm from its plan, and the plan may lay its ZMP 2 cm inside that sole's edge); with the
  hands pushing on the table (as planned), the ZMP they move away from the hands, held the
  config's ZMP margin inside the polygon by moving the CoM toward them (:func:`references`).
* **Foot admittance** (foot damping control). The desired ZMP's wrench is shared by the
  soles as flat feet share it (:meth:`NominalRobot.sole_split`); each sole moves, relative
  to the base, at ``v = K (w - w_share)`` in its frame, along its normal, about its
  horizontal axes and along the floor (never about its normal), an excess within
  ``BAND`` leaving it still (the robot rests near equilibrium, so that a contact is
  measured with its joints still): a sole on its edge turns flat, a leg the true
  kinematics makes long shortens, and together they lean the body to move the ZMP. Along
  the floor the shares are the net force's, so only the force between the feet moves them
  (``K_FOOT_SHEAR``): the true legs do not close where the nominal ones do, and as the
  posture changes the stiff joint loops would squeeze or spread the feet (100-150 N),
  sliding a sole as it unloads; the friction holds the soles, so the legs give way.
* **Torque limits.** The desired ZMP is moved back toward the reference just as far as
  keeps every joint's torque (:meth:`NominalRobot.sole_torques`, the soles sharing the
  wrench as flat feet do) within ``TORQUE_RATIO`` of its effort, or within what the
  reference asks, if more: a ZMP the feet make by loading one hip past its effort is not
  one they can make (the hip yields and the body falls toward it).
* **CoM bias.** The nominal model misplaces a perturbed robot's CoM by centimetres. When
  no hand pushes, the measured ZMP less the one the plan's motion gives at the model's CoM
  is low-passed (``BIAS_S``) into the CoM's bias: on average over a few seconds the floor
  carries the weight under the true CoM.
* **CoM position.** The CoM the encoders and the IMU put on the nominal model is brought
  back to its reference by moving the base over the soles (both soles move alike,
  relative to the base, along the floor: ``K_COM``, beyond ``COM_BAND_M``): the joint
  loops' give under load (a leg carrying the whole robot) would otherwise leave the CoM
  off its plan, and near the polygon's edge, where the plan may put the ZMP within a
  centimetre, the feet's admittance alone is too slow to bring it back. Likewise the
  base's height (the soles' admittance along their normals drifts it) is brought back to
  the plan's (``K_HEIGHT``, beyond ``HEIGHT_BAND_M``).
* **Light soles.** A sole carrying less than ``LIGHT_SHARE`` of the load does not turn: it
  cannot make the torque its share asks for (its centre of pressure would leave the
  rectangle), and its admittance would turn it on its edge.
* **Holds.** While a hand holds a contact, the stabilizer rests (zero twists) as long as
  the DCM is within ``REST_DCM_M`` of its reference and the measured ZMP
  ``REST_MARGIN_M`` inside the polygon: the robot stands balanced in a static posture, and a
  contact is measured with every joint still. Past either bound it acts as ever.
* **Body attitude.** The base's roll and pitch, as the IMU reads them, are slowly
  levelled to the plan's by turning both soles alike relative to the base
  (``K_ATTITUDE``): the true legs tilt the body where the nominal ones would not.
* **Soles on their edges.** While a loaded sole's centre of pressure lies within
  ``EDGE_M`` of its rectangle's border (:func:`on_edge`), the CoM's shift along the floor
  and the levelling rest; the admittance turns that sole flat first. A sole pivoting on
  its edge is not moved by the legs: moving it relative to the base turns the whole robot
  about the edge, and the CoM stays where the floor's support puts it. Integrated, the
  shift and the turn wind the legs up (hip and ankle rolls 0.3-0.6 rad off the plan, the
  base 10 deg off level, the CoM unmoved), until the next motion tips the robot over.

The output is each sole's twist relative to the base; :mod:`posegen.physics.offsets`
turns it into leg joint offsets.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posegen.physics.nominal import GRAVITY, NominalRobot
from posegen.physics.shaping import beyond, saturate
from posegen.physics.stance import PlannedFeet
from posegen.robot import FloatArray, Scene, centre_of_pressure, convex_hull_clockwise

K_DCM_PER_S = 2.0  # DCM error -> desired ZMP
VELOCITY_FILTER_S = 0.02  # low-pass of the CoM velocity estimate
BIAS_S = 2.0  # time constant of the CoM bias estimate, s
ZMP_MARGIN_M = (
    0.004  # the desired ZMP is kept this far inside the support polygon (the feedback's authority at the edge)
)
K_FOOT_FORCE = 1e-4  # m/s per N of excess normal force on a sole
K_FOOT_SHEAR = 3e-4  # m/s per N of excess horizontal (internal) force on a sole
K_FOOT_TORQUE = 1e-3  # rad/s per N m of excess torque
MAX_FOOT_SPEED = 0.02  # m/s and rad/s
ADMITTED = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 0.0])  # a sole gives way to every force and tilts; never yaws
BAND = np.array([20.0, 20.0, 20.0, 3.0, 3.0, 3.0])  # N, N m: a sole's excess below this leaves it where it is
K_COM_PER_S = 3.0  # CoM position error -> the base's motion over the soles
COM_BAND_M = 0.003  # a CoM error below this is left as it is (the robot rests still)
MAX_COM_SPEED = 0.05  # m/s
K_HEIGHT_PER_S = 1.0  # the base's height error -> both soles' motion along the vertical
HEIGHT_BAND_M = 0.002
LIGHT_SHARE = 0.1  # of the vertical load: a sole carrying less does not turn
K_ATTITUDE_PER_S = 0.5  # base tilt error -> both soles' turn relative to the base
MAX_TURN_RAD_S = 0.05
ATTITUDE_BAND_RAD = 0.003  # a tilt error below this is left as it is (the robot rests still)
REST_DCM_M = 0.01  # during a hold the stabilizer rests while the DCM is this close to its reference
REST_MARGIN_M = 0.01  # and the measured ZMP this far inside the support polygon
TORQUE_RATIO = 0.95  # the desired ZMP's split asks no joint for more of its effort (or than the reference's asks)
TORQUE_STEPS = 6  # bisection steps between the reference ZMP and the desired one
EDGE_M = 0.005  # a loaded sole's centre of pressure this close to its rectangle's border: the sole is on its edge
POLYGON_EVERY = 25  # control steps between two computations of the support polygon (the soles barely move)


@dataclass(frozen=True)
class SoleReadings:
    """The floor's wrench on each sole, as its sensor reads it: (6,) (force N, torque N m), sole frame."""

    wrenches: tuple[FloatArray, ...]  # in the stance's sole order


@dataclass(frozen=True)
class Reference:
    """What the plan says of the robot's balance at a sample (ground projections, m and m/s)."""

    com: FloatArray  # (2,) m
    com_velocity: FloatArray  # (2,) m/s
    zmp: FloatArray  # (2,) m, the commanded motion's ZMP, hands free
    pelvis_z: float  # m, the free base's height


def references(
    robot: NominalRobot, hands: dict[str, FloatArray], planned: Reference, polygon: Hull, margin_m: float
) -> tuple[FloatArray, FloatArray]:
    """The ZMP and CoM references (2,) each, m, while the hands push on the table.

    The table pushes a pressing hand up (its wrench (6,) on the hand, world axes at its
    contact frame): the floor carries that much less, and the ZMP moves away from the hand,
    ``p = (W p_plan - F h) / (W - F)``. Where that keeps it ``margin_m`` inside the support
    polygon, the CoM stays where the plan puts it; otherwise the ZMP is held at that margin
    and the CoM moves toward the hand by what it takes.

    Example:
        >>> zmp, com = references(robot, {"left": wrench}, Reference(com, velocity, zmp, 1.0), hull, 0.01)

    """
    weight = robot.mass_kg * -GRAVITY[2]
    moment, load = np.zeros(2), 0.0
    for chain, wrench in hands.items():
        up = max(float(wrench[2]), 0.0)  # the table's push on the hand
        moment += up * robot.pose(robot.contact_frames[chain])[:2, 3]
        load += up
    floor = max(weight - load, 0.1 * weight)  # what the floor carries
    free = (weight * planned.zmp - moment) / floor  # the ZMP if the CoM follows the plan
    zmp = clamp_into(polygon, free, margin_m)
    return zmp, np.asarray(planned.com + (zmp - free) * floor / weight)


@dataclass(frozen=True)
class Hull:
    """A convex polygon as its edges' inward normals and offsets: ``margin(p) = min(normals @ p - offsets)``."""

    vertices: FloatArray  # (h, 2) clockwise
    normals: FloatArray  # (h, 2) unit, inward
    offsets: FloatArray  # (h,)

    @classmethod
    def of(cls, points: FloatArray) -> Hull:
        """The convex hull of points (m, 2)."""
        vertices = convex_hull_clockwise(points)
        edges = np.roll(vertices, -1, axis=0) - vertices
        normals = np.column_stack([edges[:, 1], -edges[:, 0]])  # clockwise: the interior is on the right
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        return cls(vertices, normals, np.einsum("ij,ij->i", normals, vertices))

    def margin(self, point: FloatArray) -> float:
        """Signed distance (m) of a point inside the polygon (negative outside)."""
        return float((self.normals @ point - self.offsets).min())  # the method: np.min's dispatch costs more


def clamp_into(hull: Hull, point: FloatArray, margin_m: float) -> FloatArray:
    """The point (2,) pulled toward the polygon's centroid until it is ``margin_m`` inside."""
    if hull.margin(point) >= margin_m:
        return point
    centre = hull.vertices.mean(axis=0)
    low, high = 0.0, 1.0
    for _ in range(12):
        middle = 0.5 * (low + high)
        if hull.margin(centre + middle * (point - centre)) >= margin_m:
            low = middle
        else:
            high = middle
    return np.asarray(centre + low * (point - centre))


def is_light(wrench: FloatArray, load_n: float) -> bool:
    """Whether a sole's wrench (6,) carries less than ``LIGHT_SHARE`` of the soles' vertical load ``load_n`` (N).

    A light sole cannot make the torque a share asks of it (its centre of pressure would
    leave its rectangle): it neither turns nor stands on its edge.

    Example:
        >>> is_light(np.array([0, 0, 50.0, 0, 0, 0]), 900.0)
        True

    """
    return bool(wrench[2] < LIGHT_SHARE * load_n)


def on_edge(wrench: FloatArray, rectangle: Hull, load_n: float) -> bool:
    """Whether a sole carrying its wrench (6,) (force N, torque N m, its frame) stands on its edge.

    It does when it carries at least ``LIGHT_SHARE`` of the soles' vertical load ``load_n``
    and its centre of pressure lies within ``EDGE_M`` of its ``rectangle`` (its frame, m).

    Example:
        >>> sole = Hull.of(np.array([[-0.1, -0.067], [-0.1, 0.067], [0.1, 0.067], [0.1, -0.067]]))
        >>> on_edge(np.array([0, 0, 700.0, -0.065 * 700.0, 0, 0]), sole, 900.0)  # pressed at y = -0.065 m
        True

    """
    if is_light(wrench, load_n):
        return False
    return rectangle.margin(centre_of_pressure(wrench[2], wrench[3:5])) < EDGE_M  # the sole's frame


def tilt_error(measured: FloatArray, planned: FloatArray) -> FloatArray:
    """(2,) rad: the roll and pitch (world x, y) that turn the planned orientation (3, 3) into the measured one."""
    error = measured @ planned.T
    return 0.5 * np.array([error[2, 1] - error[1, 2], error[0, 2] - error[2, 0]])


class Stabilizer:
    """Each sole's twist relative to the base that keeps the robot balanced with both soles flat.

    Example:
        >>> stabilizer = Stabilizer(scene, robot)
        >>> twists = stabilizer.step(soles, hand_wrenches, (imu, planned), reference, dt_s=0.002)

    """

    def __init__(self, scene: Scene, robot: NominalRobot, glued_feet: bool = False) -> None:
        self.robot = robot
        self.glued_feet = glued_feet  # welded soles: no admittance (their sensors read the welds)
        self._limit = TORQUE_RATIO * np.nan_to_num(scene.effort_limit, nan=np.inf)  # (nj,) N m
        self.margin_m = scene.margins.zmp_m  # the reference ZMP is kept this far inside the polygon
        (x0, x1), (y0, y1) = scene.stance.foot_x_m, scene.stance.foot_y_m
        self._corners = np.array([[x, y, 0.0, 1.0] for x in (x0, x1) for y in (y0, y1)]).T  # (4, 4) sole frame
        self._rectangle = Hull.of(self._corners[:2].T)  # a sole, its frame
        first, second = (scene.sole_poses[f] for f in scene.stance.sole_frames)  # (4, 4) each; a stance has two
        self._feet = PlannedFeet((first, second), np.array([*scene.stance.foot_centre_m, 0.0]))
        self._com: FloatArray | None = None
        self._hull: Hull | None = None
        self._steps = 0
        self._velocity = np.zeros(2)
        self.zmp_desired: FloatArray = np.zeros(2)
        self.dcm_error: FloatArray = np.zeros(2)  # m, the DCM less its reference
        self.com_bias: FloatArray = np.zeros(2)  # m, the true CoM less the model's, as the soles measure it

    def _polygon(self) -> Hull:
        """The soles' support polygon where the robot believes they are (renewed every ``POLYGON_EVERY`` steps)."""
        if self._hull is None or self._steps % POLYGON_EVERY == 0:
            points = np.hstack([(pose @ self._corners)[:2] for pose in self.robot.sole_poses]).T
            self._hull = Hull.of(points)
        return self._hull

    def _desired_zmp(self, zmp: FloatArray, reference: FloatArray, velocity: FloatArray, dt_s: float) -> FloatArray:
        """The ZMP (2,) that brings the DCM back to its reference (the ZMP ``zmp``, the CoM ``reference`` moving)."""
        com = self.robot.com()
        com[:2] += self.com_bias
        if self._com is not None:
            blend = dt_s / (VELOCITY_FILTER_S + dt_s)
            self._velocity += blend * ((com[:2] - self._com) / dt_s - self._velocity)
        self._com = com[:2].copy()
        omega = np.sqrt(-GRAVITY[2] / max(float(com[2]), 0.1))
        self.dcm_error = com[:2] + self._velocity / omega - reference - velocity / omega
        desired = zmp + (1.0 + K_DCM_PER_S / omega) * self.dcm_error
        return clamp_into(self._polygon(), desired, ZMP_MARGIN_M)

    def step(
        self,
        soles: SoleReadings,
        hand_wrenches: dict[str, FloatArray],
        attitude: tuple[FloatArray, FloatArray],
        planned: Reference,
        dt_s: float,
        holding: bool = False,
    ) -> list[FloatArray]:
        """Each sole's twist (6,) relative to the base (world axes at the sole), the robot updated at its sensors.

        Args:
            soles: The soles' sensor readings.
            hand_wrenches: Chain -> the table's measured wrench on its hand (6,), world axes at its contact frame.
            attitude: The base's orientation (3, 3) as its IMU reads it, and as planned.
            planned: The plan's CoM, CoM velocity and ZMP at this sample.
            dt_s: The control period.
            holding: A hand holds a contact: the stabilizer rests while the robot is balanced.

        """
        robot = self.robot
        self._steps += 1
        planned = self._as_stood(planned)
        zmp, reference = references(robot, hand_wrenches, planned, self._polygon(), self.margin_m)
        self.zmp_desired = self._desired_zmp(zmp, reference, planned.com_velocity, dt_s)
        total = robot.soles_total(soles.wrenches)
        measured = centre_of_pressure(max(float(total[2]), 1.0), total[3:5])  # the ZMP (2,), floor at z = 0
        if not any(float(w[2]) > 0.0 for w in hand_wrenches.values()):
            expected = robot.com()[:2] + self.com_bias + planned.zmp - planned.com  # the plan's motion at our CoM
            self.com_bias += dt_s / BIAS_S * (measured - expected)
        balanced = np.linalg.norm(self.dcm_error) < REST_DCM_M and self._polygon().margin(measured) > REST_MARGIN_M
        if self.glued_feet or (holding and balanced):
            return [np.zeros(6) for _ in robot.soles]
        self.zmp_desired, shares = self._within_torques(total, zmp, self.zmp_desired)
        shift = np.zeros(3)  # the soles move back: the base moves on
        shift[2] = K_HEIGHT_PER_S * float(beyond(float(robot.q[2] - planned.pelvis_z), HEIGHT_BAND_M))
        com_error = beyond(reference - robot.com()[:2] - self.com_bias, COM_BAND_M)  # (2,) m
        shift[:2] = -saturate(K_COM_PER_S * com_error, MAX_COM_SPEED)
        level = np.zeros(3)  # turning both soles by the base's tilt, relative to it, turns the base back
        tilt = beyond(tilt_error(*attitude), ATTITUDE_BAND_RAD)
        level[:2] = saturate(K_ATTITUDE_PER_S * tilt, MAX_TURN_RAD_S)
        if any(on_edge(wrench, self._rectangle, float(total[2])) for wrench in soles.wrenches):
            shift[:2], level[:2] = 0.0, 0.0  # the admittance turns the sole flat first
        return [
            _sole_twist(pose, wrench, share, shift, level, float(total[2]))
            for pose, wrench, share in zip(robot.sole_poses, soles.wrenches, shares, strict=True)
        ]

    def _as_stood(self, planned: Reference) -> Reference:
        """The plan's CoM and ZMP moved with the soles to where the robot believes they stand."""
        first, second = self.robot.sole_poses  # (4, 4) each, where the robot believes they stand
        com, zmp = (self._feet.follow(point, (first, second)) for point in (planned.com, planned.zmp))
        return Reference(com, planned.com_velocity, zmp, planned.pelvis_z)

    def _split_at(self, total: FloatArray, zmp: FloatArray) -> tuple[list[FloatArray], FloatArray]:
        """The soles' shares (6,) LOCAL each of the total wrench (6,) moved to the ZMP (2,), and their torques (nj,)."""
        desired = total.copy()
        desired[3:5] = [zmp[1] * total[2], -zmp[0] * total[2]]
        shares = self.robot.sole_split(desired)
        return shares, np.abs(self.robot.sole_torques(shares))

    def _within_torques(
        self, total: FloatArray, reference: FloatArray, desired: FloatArray
    ) -> tuple[FloatArray, list[FloatArray]]:
        """The desired ZMP (2,) moved back toward the reference until its split asks no joint past its limit.

        A joint is held within ``TORQUE_RATIO`` of its effort, or within what the reference ZMP's
        split asks of it, if more: a stance leg at its effort limit yields, and its body falls
        (a ZMP the feet make by loading one hip past its effort is not one they can make).
        Returns the ZMP and the soles' shares (6,) LOCAL each.
        """
        shares, torques = self._split_at(total, desired)
        if (torques <= self._limit).all():
            return desired, shares
        kept, at_reference = self._split_at(total, reference)
        bound = np.maximum(self._limit, at_reference)
        low, high = 0.0, 1.0
        for _ in range(TORQUE_STEPS):
            middle = 0.5 * (low + high)
            shares, torques = self._split_at(total, reference + middle * (desired - reference))
            if (torques <= bound).all():
                low, kept = middle, shares
            else:
                high = middle
        return reference + low * (desired - reference), kept


def _sole_twist(
    pose: FloatArray, wrench: FloatArray, share: FloatArray, shift: FloatArray, level: FloatArray, load: float
) -> FloatArray:
    """A sole's twist (6,) relative to the base: its admittance, the CoM's shift and height, the attitude's turn.

    ``pose`` (4, 4) where the nominal model puts it; ``wrench`` and ``share`` (6,) in its frame;
    ``load`` the soles' total vertical force, N.
    """
    excess = beyond((wrench - share) * ADMITTED, BAND)  # along the normal, about the horizontal axes
    if is_light(wrench, load):
        excess[3:] = 0.0
    local = np.concatenate([K_FOOT_SHEAR * excess[:2], K_FOOT_FORCE * excess[2:3], K_FOOT_TORQUE * excess[3:]])
    local = saturate(local, MAX_FOOT_SPEED)
    rotation = pose[:3, :3]
    return np.concatenate([rotation @ local[:3] + shift, rotation @ local[3:] + level])
