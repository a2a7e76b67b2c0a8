"""The force-controlled go-to-contact, hold and release: an admittance at the hand.

Each hand moves by a twist the stabilizer makes its joints give (:mod:`posegen.physics.stabilizer`),
computed from its wrist sensor: the reading less the tool's weight (the nominal URDF's
tool, turned with the wrist as the encoders say) and less a tare taken while the hand is
free just before its approach (the sensor's offset, the tool's model error), moved to
the contact frame's origin in world axes.

A contact of the route runs, in route time:

* **approach** (the route's): the hand gives way to any force above ``GUARD_FORCE_N``,
  at up to ``GUARD_SPEED_M_S``, the plan's descent undone while the table's normal force
  is above it (a table higher than planned is met, not pushed);
* **go-to-contact and hold**: force control along the table normal to the target force
  ``force_n``: once touching, ``dz/dt = K_FORCE (f - force_n)``, down at most
  ``MAX_SPEED_M_S``, up (pressed harder than the target) at up to ``GUARD_SPEED_M_S``
  (still within ``FORCE_BAND`` of the target: the contact is measured with the joints
  still), and the plan's own descent undone (a guarded move: the go-to-contact descends
  at up to about 0.1 m/s, and a table met before its end was pressed at that speed, up to 380 N);
  ``SEARCH_SPEED_M_S`` down before touching (a table lower than planned is searched
  for, below the route's overshoot); the route waits at the end of its go-to-contact
  until ``SETTLE_S`` after the force first reached its band (``REACHED``;
  ``SEARCH_TIMEOUT_S`` at most), so that the
  hold lasts the planned time in contact; in contact a hand that touches with a point also
  turns to zero roll and pitch torque about its contact frame's origin;
* **flush** (a hand that touches the table with fingertips): the hand turns about its
  contact origin, by the roll and pitch torque there (low-passed over ``TORQUE_FILTER_S``:
  the sensor reads 0.1-0.2 N m of noise), until the centre of pressure lies
  a few millimetres inside the fingertips' polygon (:mod:`posegen.physics.fingertips`), every tip
  loaded; then it stays as it is. Through the hold it does not turn, and the route does not
  wait for it (a wait of its own, with the force on, tipped the standing robot on routes it
  otherwise completes: the arm pushes on the table the longer). The true hand meets the table
  turned by up to 5 deg from where the nominal model puts it: pressed down, it rests on two
  tips, its contact frame tilted 1-2 deg on average against the table, and the calibration
  reads that tilt as the kinematics' (a flush contact pins the frame's roll and pitch);
* an arm whose joint loop is at its effort limit (its tracking error past the loop's
  saturation) neither presses further nor turns, nor, away from the table, holds its
  hand's pose in the world: neither loop winds up (the pose loop, integrating a shoulder's
  lag of 0.06-0.35 rad, turned the torso 0.9 rad off its plan in 4 s); away from the table
  the other hand's twist does not move that arm either (:class:`JointOffsets`);
* **release**: the target force falls to zero over the first ``UNLOAD_SHARE`` of the route's
  release (``UNLOAD_S`` at least; :func:`unload_s`), then the hand's offset fades back to the
  plan over the rest of the release. The floor takes back the hand's load gradually: a hand
  unloaded at once moves the floor's ZMP toward it by ``F h / W`` in a step (about 1 cm for
  30 N at 0.3 m), which a robot leaning on its hand near the polygon's edge does not survive.

A free hand outside these phases stays where the plan puts it (zero twist) unless a force
above ``GUARD_FORCE_N`` pushes it: it gives way as in the approach, at up to
``GUARD_SPEED_M_S``, five times the contact's ``MAX_SPEED_M_S``: the true hand may pass
centimetres lower than the nominal one, and an arm that keeps moving while its hand yields at
the contact's speed presses 100 N and more on the table, enough to push the robot over.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.io import Route, SegmentType
from posegen.physics.fingertips import TORQUE_FILTER_S, flush_turn, loads_every_tip, tip_polygon
from posegen.physics.nominal import NominalRobot
from posegen.physics.shaping import beyond, bounded_rate, saturate
from posegen.robot import FloatArray

K_FORCE = 3e-3  # m/s per N of normal force error
FORCE_BAND = 0.1  # within this fraction of the target force, the hand stays where it is
HOLD_BAND = 0.3  # and during the hold (only a force far from the target moves it: the contact is measured still)
K_TORQUE = 0.01  # rad/s per N m of roll or pitch torque about the contact origin
TORQUE_BAND_NM = 0.5  # roll and pitch torques below this leave the hand's tilt as it is
MAX_TILT_RAD = 0.05  # the hand turns at most this far from the plan
SEARCH_SPEED_M_S = 0.02
MAX_SPEED_M_S = 0.02
GUARD_SPEED_M_S = 0.1  # a hand that meets the table unplanned gives way this fast at most (the arm moves on)
MAX_TURN_RAD_S = 0.2  # a hand turns at most this fast (its admittance, settling flush)
GUARD_FORCE_N = 10.0
TOUCH_FORCE_N = 3.0  # in contact: above this normal force
UNLOAD_S = 0.1  # s, the shortest unloading
UNLOAD_SHARE = 0.5  # the force is taken off over this share of the release (at least UNLOAD_S)
TARE_S = 0.1
REACHED = 0.9  # a hold starts once the normal force is this fraction of the target (in the force band)
SEARCH_TIMEOUT_S = 4.0  # the route waits at most this long for a contact before its hold
SETTLE_S = 0.25  # and this long after the force first reached its band (the arm settles)
MAX_OFFSET_M = 0.05  # the search and the force control move the hand at most this far from the plan
K_HOLD_PER_S = 5.0  # the hand's pose error to its target (the plan plus the admittance's offset) -> twist
POSE_BAND = np.array([5e-4, 5e-4, 5e-4, 2e-3, 2e-3, 2e-3])  # m, rad: a smaller pose error is left as it is
HOLD_EVERY = 5  # control periods between two computations of the hands' pose errors


class Phase(enum.Enum):
    """What a hand's controller is doing."""

    FREE = "free"
    APPROACH = "approach"
    PRESS = "press"  # go-to-contact and hold: force control
    RELEASE = "release"


@dataclass(frozen=True)
class ContactTimes:
    """When the route makes one contact (route time, s)."""

    chain: str
    label: str  # "posture 3 (pool 17)"
    approach_s: float
    press_s: float  # go-to-contact starts
    hold_s: float
    lift_s: float  # release starts
    free_s: float  # release ends


def contact_times(route: Route) -> tuple[ContactTimes, ...]:
    """The route's contacts (approach, go-to-contact, hold and release each), in time order."""
    steps: dict[int | None, dict[SegmentType, tuple[float, float, str, int | None]]] = {}
    for s in route.segments:
        if s.type != SegmentType.FREE and s.chain is not None:
            steps.setdefault(s.posture, {})[s.type] = (s.start_s, s.end_s, s.chain, s.pool_id)
    out = []
    kinds = (SegmentType.APPROACH, SegmentType.GO_TO_CONTACT, SegmentType.HOLD, SegmentType.RELEASE)
    for posture, found in steps.items():
        if any(k not in found for k in kinds):
            continue  # a route always has the four; a hand-edited one may not
        approach, press, hold, release = (found[k] for k in kinds)
        label = f"posture {posture}" + ("" if hold[3] is None else f" (pool {hold[3]})")
        out.append(ContactTimes(hold[2], label, approach[0], press[0], hold[0], release[0], release[1]))
    return tuple(sorted(out, key=lambda c: c.hold_s))


def unload_s(contact: ContactTimes) -> float:
    """How long (s) a contact's release takes its force off: ``UNLOAD_SHARE`` of the release, ``UNLOAD_S`` at least.

    Example:
        >>> unload_s(ContactTimes("left", "posture 0", 0.0, 0.3, 0.6, 1.6, 2.2))
        0.30000000000000004

    """
    return max(UNLOAD_S, UNLOAD_SHARE * (contact.free_s - contact.lift_s))


@dataclass
class _Hand:
    """One hand's controller state."""

    tare: FloatArray  # (6,) sensor frame
    tare_sum: FloatArray
    tare_count: int
    offset: FloatArray  # (6,) the twist integrated so far (world axes; angles small)
    torque: FloatArray  # (2,) N m, the roll and pitch torques at the contact origin, low-passed (world axes)


class HandControl:
    """Both hands' admittance, from their wrist sensors and the route's contact times.

    Example:
        >>> hands = HandControl(robot, contact_times(route), force_n=30.0)
        >>> twists = hands.step(route_time_s, wrists, planned_hands, commanded, dt_s=0.002)

    """

    def __init__(self, robot: NominalRobot, contacts: tuple[ContactTimes, ...], force_n: float) -> None:
        self.robot = robot
        self.force_n = force_n
        self.contacts = {c: [k for k in contacts if k.chain == c] for c in robot.tools}
        self.hands = {c: _Hand(np.zeros(6), np.zeros(6), 0, np.zeros(6), np.zeros(2)) for c in robot.tools}
        self.tips = {c: tip_polygon(robot.scene, c) for c in robot.tools}  # chain -> its fingertips' polygon
        self.wrenches: dict[str, FloatArray] = {c: np.zeros(6) for c in robot.tools}  # the last, at the contact
        self.waited_s: dict[str, float] = {}  # contact label -> how long the route waited for it
        self.saturated: dict[str, bool] = {}  # chain -> an arm joint lags its command past its effort limit
        self._settled: dict[str, float] = {}  # contact label -> time since its force first reached its band
        self._errors: dict[str, FloatArray] = {}  # chain -> its pose error beyond the band, renewed every HOLD_EVERY
        self._steps = 0
        self._current_t = np.nan  # the route time of _current_of: chain -> its contact then
        self._current_of: dict[str, ContactTimes | None] = {}
        self._planned_z: dict[str, float] = {}  # chain -> its contact frame's planned height at the last step, m

    def _current(self, chain: str, t: float) -> ContactTimes | None:
        """The contact of ``chain`` whose time (tare to free) holds ``t``, if any (kept for the last ``t`` asked)."""
        if t != self._current_t:
            self._current_t, self._current_of = t, {}
        if chain not in self._current_of:
            self._current_of[chain] = next(
                (c for c in self.contacts[chain] if c.approach_s - TARE_S <= t < c.free_s), None
            )
        return self._current_of[chain]

    def phase(self, chain: str, t: float) -> Phase:
        """A hand's phase at route time ``t``."""
        contact = self._current(chain, t)
        if contact is None or t < contact.approach_s:
            return Phase.FREE
        if t < contact.press_s:
            return Phase.APPROACH
        return Phase.PRESS if t < contact.lift_s else Phase.RELEASE

    def holds_back(self, t: float, t_next: float, dt_s: float) -> bool:
        """Whether the route's clock waits at ``t`` rather than go on to ``t_next``.

        A hold starts when its force is reached, as a robot's contact controller starts it:
        the route waits, at the end of its go-to-contact, while the hand searches for the
        table, for at most ``SEARCH_TIMEOUT_S``.
        """
        for chain in self.hands:
            contact = self._current(chain, t)
            if contact is None or not t < contact.hold_s <= t_next:
                continue
            waited = self.waited_s.get(contact.label, 0.0)
            settled = self._settled.get(contact.label)  # since the force first reached its band
            force = self.wrenches[chain][2]
            at_limit = self.saturated.get(chain, False) and force > GUARD_FORCE_N  # pressing as hard as it can
            if settled is not None or force >= REACHED * self.force_n or at_limit:
                settled = (settled or 0.0) + dt_s
                self._settled[contact.label] = settled
            if (settled is None or settled < SETTLE_S) and waited < SEARCH_TIMEOUT_S:
                self.waited_s[contact.label] = waited + dt_s
                return True
        return False

    def in_contact(self, t: float) -> bool:
        """Whether a hand is at the table at route time ``t`` (go-to-contact, hold or release)."""
        return any(self.phase(chain, t) in (Phase.PRESS, Phase.RELEASE) for chain in self.hands)

    def holding(self, t: float) -> bool:
        """Whether a hand holds a contact at route time ``t`` (its hold, as the route's clock has it)."""
        current = (self._current(chain, t) for chain in self.hands)  # a hold lies within its contact's time
        return any(c is not None and c.hold_s <= t < c.lift_s for c in current)

    def planned_push(self, chain: str, t: float) -> float:
        """The force (N) the plan has a hand push on the table at route time ``t``: the target, ramped in and out."""
        contact = self._current(chain, t)
        if contact is None or t < contact.press_s:
            return 0.0
        if t < contact.lift_s:
            return self.force_n * min((t - contact.press_s) / max(contact.hold_s - contact.press_s, 1e-3), 1.0)
        return self.force_n * max(1.0 - (t - contact.lift_s) / unload_s(contact), 0.0)

    def step(
        self,
        t: float,
        wrists: dict[str, FloatArray],
        planned: dict[str, FloatArray],
        commanded: FloatArray,
        dt_s: float,
    ) -> dict[str, FloatArray]:
        """Each hand's twist (6,) relative to the base (world axes at its contact frame) at route time ``t``.

        Away from the table, the twist holds the hand at its target in the world (the planned
        pose moved by the admittance's offset), where the commanded angles put it on the base
        the IMU tilts: the stabilizer's lean and the base's tilt do not carry it (an error
        within ``POSE_BAND`` is left; the error is renewed every ``HOLD_EVERY`` periods). While a hand
        is in contact (go-to-contact, hold, release) the table holds it and only its
        admittance moves it; the other hand stays still (a contact is measured with every
        joint still). (Closed on the commands,
        not on the encoders: a joint that its effort limit or the table holds back does
        not wind the loop up.)

        Args:
            t: Route time, s.
            wrists: Chain -> its wrist sensor's reading (6,).
            planned: Chain -> its contact frame's planned world pose (4, 4).
            commanded: The joint angles (nj,) rad last commanded.
            dt_s: Control period, s.

        """
        out = {}
        hold = not self.in_contact(t)  # in contact, every hand stays still
        self._steps += 1
        if hold and (self._steps % HOLD_EVERY == 0 or not self._errors):
            frames = [self.robot.contact_frames[chain] for chain in self.hands]
            at = dict(zip(self.hands, self.robot.commanded_poses(commanded, frames), strict=True))
            self._errors = {
                c: beyond(self._error(planned[c], h.offset, at[c]), POSE_BAND) for c, h in self.hands.items()
            }
        for chain, hand in self.hands.items():
            contact = self._current(chain, t)
            compensated = wrists[chain] - self.robot.tool_wrench(chain)
            if contact is not None and t < contact.approach_s:  # free, before the approach: tare
                hand.tare_sum += compensated
                hand.tare_count += 1
                hand.tare = hand.tare_sum / hand.tare_count
            else:
                hand.tare_sum, hand.tare_count = np.zeros(6), 0
            wrench = self.robot.at_contact(chain, compensated - hand.tare)
            self.wrenches[chain] = wrench
            hand.torque += dt_s / (TORQUE_FILTER_S + dt_s) * (wrench[3:5] - hand.torque)
            rate = self._twist(chain, contact, t, wrench, hand)
            if self.tips[chain] is not None and self.phase(chain, t) == Phase.PRESS:
                flush = self._flush(chain, wrench[2], hand.torque)
                rate[3:5] = 0.0 if self.saturated.get(chain, False) else self._settle_flush(contact, t, hand, flush)
            rate[2] += self._undone_descent(chain, t, float(planned[chain][2, 3]), dt_s)
            hand.offset += rate * dt_s
            hand.offset[:3] = saturate(hand.offset[:3], MAX_OFFSET_M)
            held = hold and not self.saturated.get(chain, False)  # anti-windup: a lagging arm holds no pose
            out[chain] = rate + (K_HOLD_PER_S * self._errors[chain] if held else 0.0)
        return out

    def _undone_descent(self, chain: str, t: float, planned_z_m: float, dt_s: float) -> float:
        """The plan's descent (m/s, >= 0) a hand on the table undoes: it goes no deeper than its force control.

        On the table: touching in the go-to-contact, a normal force above the guard's in the
        approach (the guard's give-way itself answers the force's size, any direction).
        Both descend at up to 0.1-0.2 m/s; a table met before their end would otherwise be
        pressed at that speed less the admittance's.
        """
        last = self._planned_z.get(chain, planned_z_m)
        self._planned_z[chain] = planned_z_m
        phase, force = self.phase(chain, t), float(self.wrenches[chain][2])
        touching = (phase == Phase.PRESS and force > TOUCH_FORCE_N) or (
            phase == Phase.APPROACH and force > GUARD_FORCE_N
        )
        return max(last - planned_z_m, 0.0) / dt_s if touching else 0.0

    @staticmethod
    def _error(planned: FloatArray, offset: FloatArray, estimated: FloatArray) -> FloatArray:
        """(6,) the hand's target pose less its commanded one (4, 4): translation, rotation vector (world axes)."""
        target_rotation = pin.exp3(offset[3:]) @ planned[:3, :3]
        return np.concatenate(
            [planned[:3, 3] + offset[:3] - estimated[:3, 3], pin.log3(target_rotation @ estimated[:3, :3].T)]
        )

    def _flush(self, chain: str, force_n: float, torque: FloatArray) -> bool:
        """Whether every fingertip carries load (a hand not touching, or touching with a point, is flush).

        ``force_n`` the table's normal force on the hand, ``torque`` (2,) N m its roll and pitch
        torques at the contact origin (world axes, turned into the contact frame's here).
        """
        tips = self.tips[chain]
        if tips is None or force_n <= TOUCH_FORCE_N:
            return True
        axes = self.robot.pose(self.robot.contact_frames[chain])[:2, :2]  # the frame's yaw (its tilt is small)
        return loads_every_tip(tips, force_n, axes.T @ torque)

    @staticmethod
    def _settle_flush(contact: ContactTimes | None, t: float, hand: _Hand, flush: bool) -> FloatArray:
        """The roll and pitch rates (2,) rad/s of a pressing hand with fingertips: toward flush, still once flush.

        Still through the hold (a contact is measured with every joint still).
        """
        if flush or (contact is not None and t >= contact.hold_s):
            return np.zeros(2)
        return flush_turn(hand.torque, hand.offset[3:5], MAX_TURN_RAD_S)

    def _twist(self, chain: str, contact: ContactTimes | None, t: float, wrench: FloatArray, hand: _Hand) -> FloatArray:
        phase = self.phase(chain, t)
        if phase == Phase.RELEASE and contact is not None and t >= contact.lift_s + unload_s(contact):
            remaining = max(contact.free_s - t, 0.05)
            return -hand.offset / remaining  # back to the plan by the release's end
        if phase in (Phase.FREE, Phase.APPROACH):
            size = float(np.linalg.norm(wrench[:3]))
            if size <= GUARD_FORCE_N:
                return np.zeros(6) if phase == Phase.APPROACH else -hand.offset / 0.5
            return self._give_way(wrench * (size - GUARD_FORCE_N) / size, 0.0, hand.offset, 0.0, GUARD_SPEED_M_S)
        target = self.planned_push(chain, t) if phase == Phase.RELEASE else self.force_n  # the release's ramp
        band = HOLD_BAND if contact is not None and contact.hold_s <= t < contact.lift_s else FORCE_BAND
        twist = self._give_way(wrench, target, hand.offset, band)
        if self.saturated.get(chain, False):  # anti-windup: an arm at its effort limit pushes no further
            twist[2] = max(twist[2], 0.0)
            twist[3:] = 0.0
        return twist

    @staticmethod
    def _give_way(
        wrench: FloatArray, target_n: float, offset: FloatArray, band: float = FORCE_BAND, speed: float = MAX_SPEED_M_S
    ) -> FloatArray:
        """The admittance twist (6,): along the normal to the target force, roll and pitch to zero torque.

        The tangent and the yaw are held (the fingertips' friction holds them; the
        measurement needs neither); the hand turns at most ``MAX_TILT_RAD`` from the plan.
        """
        twist = np.zeros(6)
        if wrench[2] <= TOUCH_FORCE_N:  # not touching: search down (or stay, when unloaded)
            twist[2] = -SEARCH_SPEED_M_S if target_n > TOUCH_FORCE_N else 0.0
            return twist
        error = wrench[2] - target_n
        if abs(error) <= band * target_n:  # close enough: the hand stays still (a contact is measured still)
            return twist
        twist[2] = min(max(K_FORCE * error, -speed), max(speed, GUARD_SPEED_M_S))  # gives way as fast as a guard
        torque = np.where(np.abs(wrench[3:5]) > TORQUE_BAND_NM, wrench[3:5], 0.0)
        twist[3:5] = bounded_rate(K_TORQUE * torque, MAX_TURN_RAD_S, offset[3:5], MAX_TILT_RAD)
        return twist
