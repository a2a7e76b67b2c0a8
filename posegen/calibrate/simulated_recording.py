"""A simulated recording: a perturbed robot executes a route, as its sensors record it (``posegen simulate --bag``).

The true robot is the one ``posegen simulate`` makes from the same seed (same
perturbation model, same chains and session). It follows the route's trajectory,
sampled at the recording rate (cubic Hermite through the route's positions and
velocities). At each contact the force controller carries the arm from the planned
contact posture to the settled one, where the true contact is flush with the true table
(with contact noise: with its local plane, :func:`posegen.calibrate.simulation.contact_offsets`;
the settle step, under gravity if the robot is compliant): the correction grows over
the go-to-contact segment, is held, and fades over the release. The legs follow the
route, as the stance controller holds them (``posegen simulate`` of postures closes the
second leg on the true robot instead). The wrist of that arm reads the normal force, growing and fading
with the correction; both wrists read a constant sensor offset and noise, and the
encoders read the angles plus noise. The recording starts and ends with the robot at rest.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from posegen.calibrate.simulation import Perturbation, contact_offsets, perturbed_robot, settle_true
from posegen.errors import InfeasibleError
from posegen.io import Route, Segment, SegmentType
from posegen.model import CalibrationModel, Contacts, planned_kinds
from posegen.robot import FloatArray, Scene

TORQUE_ARM_M = 0.1  # torque noise = force noise x this lever


@dataclass(frozen=True)
class SensorSettings:
    """What the simulated sensors read."""

    rate_hz: float = 500.0  # joint states and wrenches
    contact_force_n: float = 40.0  # normal force held in contact
    force_noise_n: float = 0.5  # sigma of each force component (torques: x TORQUE_ARM_M)
    force_offset_n: float = 3.0  # sigma of each wrist sensor's constant offset, per component
    rest_s: float = 1.0  # at rest before the route starts and after it ends


@dataclass(frozen=True)
class ContactPhase:
    """When the route makes one contact, and where."""

    chain: str
    label: str  # "posture 3 (pool 17)"
    posture: FloatArray  # (nj,) rad, the planned contact posture (the hold's)
    press_s: float  # go-to-contact starts (route time)
    hold_s: float  # hold starts
    lift_s: float  # release starts
    free_s: float  # release ends


@dataclass(frozen=True)
class Motion:
    """A route's timed trajectory and its contacts."""

    joint_names: tuple[str, ...]
    times: FloatArray  # (m,) s from the route's start, increasing
    positions: FloatArray  # (m, nj) rad
    velocities: FloatArray  # (m, nj) rad/s
    contacts: tuple[ContactPhase, ...]

    def in_order(self, names: Sequence[str]) -> Motion:
        """The same motion with its joint columns in the order of ``names`` (the same joints, reordered)."""
        columns = [self.joint_names.index(name) for name in names]
        return Motion(
            tuple(names),
            self.times,
            self.positions[:, columns],
            self.velocities[:, columns],
            tuple(replace(c, posture=c.posture[columns]) for c in self.contacts),
        )


@dataclass(frozen=True)
class SimulatedRecording:
    """What the robot's sensors recorded, and the robot that made it."""

    times_s: FloatArray  # (n,) s from the recording's start
    positions: FloatArray  # (n, nj) rad, encoder readings
    forces: dict[str, FloatArray]  # per chain, (n, 3) N in the wrist sensor frame
    torques: dict[str, FloatArray]  # per chain, (n, 3) N m
    route_start_s: float  # the route's time 0 on the recording's clock
    model: CalibrationModel
    theta: FloatArray  # (nx,) true parameters


def contact_label(posture: Any, pool_id: Any) -> str:
    """How a route's contact is named in reports: ``posture 3 (pool 17)``."""
    return f"posture {posture}" + ("" if pool_id is None else f" (pool {pool_id})")


def route_motion(route: Route) -> Motion:
    """The trajectory and contacts of a route (as read, and validated, by :func:`posegen.io.read_route`)."""
    times, positions, velocities = route.times, route.positions, route.velocities
    phases: dict[int | None, dict[SegmentType, Segment]] = {}
    for segment in route.segments:
        if segment.type.in_contact:
            phases.setdefault(segment.posture, {})[segment.type] = segment
    contacts = []
    for steps in phases.values():
        go, hold, release = (steps.get(k) for k in (SegmentType.GO_TO_CONTACT, SegmentType.HOLD, SegmentType.RELEASE))
        if go is None or hold is None or release is None:
            continue  # a route always has the three; a hand-edited one may not
        contacts.append(
            ContactPhase(
                chain=str(hold.chain),
                label=contact_label(hold.posture, hold.pool_id),
                posture=positions[hold.first_point].copy(),
                press_s=float(times[go.first_point]),
                hold_s=float(times[hold.first_point]),
                lift_s=float(times[release.first_point]),
                free_s=float(times[release.last_point]),
            )
        )
    contacts.sort(key=lambda c: c.hold_s)
    return Motion(route.joint_names, times, positions, velocities, tuple(contacts))


def hermite(times: FloatArray, positions: FloatArray, velocities: FloatArray, at: FloatArray) -> FloatArray:
    """Cubic Hermite interpolation (n, nj) at ``at`` (n,); constant before and after ``times``."""
    k = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 2)
    h = (times[k + 1] - times[k])[:, None]
    s = np.clip((at - times[k])[:, None] / h, 0.0, 1.0)
    s2, s3 = s * s, s * s * s
    return np.asarray(
        (2 * s3 - 3 * s2 + 1) * positions[k]
        + (s3 - 2 * s2 + s) * h * velocities[k]
        + (3 * s2 - 2 * s3) * positions[k + 1]
        + (s3 - s2) * h * velocities[k + 1]
    )


def _smoothstep(x: FloatArray) -> FloatArray:
    x = np.clip(x, 0.0, 1.0)
    return np.asarray(x * x * (3.0 - 2.0 * x))


def contact_weight(phase: ContactPhase, at: FloatArray) -> FloatArray:
    """(n,) how far the force controller has pressed at route times ``at``: 0 free, 1 flush and held."""
    rise = _smoothstep((at - phase.press_s) / max(phase.hold_s - phase.press_s, 1e-9))
    fall = 1.0 - _smoothstep((at - phase.lift_s) / max(phase.free_s - phase.lift_s, 1e-9))
    return np.where(at < phase.lift_s, rise, fall)


def simulate_recording(
    scene: Scene,
    motion: Motion,
    session: str,
    perturbation: Perturbation,
    settings: SensorSettings,
    seed: int,
    every_chain: bool = False,
) -> SimulatedRecording:
    """Record a perturbed robot executing a route.

    Args:
        scene: Scene of the nominal robot (the route's joints in its order).
        motion: The route.
        session: Table session of the contacts (names the true plane).
        perturbation: Error sizes; the encoder noise is per sample.
        settings: Sensor rate, contact force and noise.
        seed: Seed of the robot's errors (as ``posegen simulate``) and of the sensor noise.
        every_chain: Draw the robot with every chain of the config, whichever the route
            touches with (the same seed is then the same robot for every route: a
            session's batches); False: with the route's chains, as ``posegen simulate``.

    Raises:
        InfeasibleError: The route has no contact, or a contact does not settle on the true plane.

    """
    chains = tuple(c.chain for c in motion.contacts)
    labels = tuple(c.label for c in motion.contacts)
    planned = Contacts(
        np.array([c.posture for c in motion.contacts]),
        chains,
        (session,) * len(chains),
        labels,
        planned_kinds(scene, chains),
    )
    if every_chain:
        every = tuple(c.name for c in scene.config.chains)
        kinds = {c: (scene.chain(c).contact_kind,) for c in every} | planned.kinds_by_chain()
        model, theta = perturbed_robot(scene, every, [session], perturbation, seed, kinds)
    else:
        model, theta = perturbed_robot(scene, chains, [session], perturbation, seed, planned.kinds_by_chain())
    offsets = contact_offsets(planned, perturbation, seed)  # each contact's local plane (contact noise)
    settled, converged, _ = settle_true(model, theta, planned, stand=False, offsets=offsets)  # legs follow the route
    if not np.all(converged):
        label = planned.labels[int(np.flatnonzero(~converged)[0])]
        raise InfeasibleError(f"simulated contact {label!r} does not settle on the true plane")
    step = 1.0 / settings.rate_hz
    times = np.arange(int(np.floor((float(motion.times[-1]) + 2 * settings.rest_s) / step)) + 1) * step
    route_time = times - settings.rest_s
    positions = hermite(motion.times, motion.positions, motion.velocities, route_time)
    pressed = {chain.name: np.zeros(len(times)) for chain in scene.config.chains}
    for k, phase in enumerate(motion.contacts):
        first, stop = np.searchsorted(route_time, [phase.press_s, phase.free_s])
        weight = contact_weight(phase, route_time[first:stop])
        positions[first:stop] += weight[:, None] * (settled.joints[k] - planned.joints[k])
        pressed[phase.chain][first:stop] = np.maximum(pressed[phase.chain][first:stop], weight)
    rng = np.random.default_rng([seed, 2])  # [seed, 1] is ``simulate``'s encoder noise
    readings = positions + rng.normal(0.0, perturbation.encoder_noise_rad, positions.shape)
    forces: dict[str, FloatArray] = {}
    torques: dict[str, FloatArray] = {}
    for name, weight in pressed.items():
        offset = rng.normal(0.0, settings.force_offset_n, 6)
        wrench = offset + rng.normal(0.0, settings.force_noise_n, (len(times), 6))
        wrench[:, 2] -= settings.contact_force_n * weight  # the table pushes the gripper along the sensor's -z
        forces[name], torques[name] = wrench[:, :3], wrench[:, 3:] * TORQUE_ARM_M
    return SimulatedRecording(times, readings, forces, torques, settings.rest_s, model, theta)
