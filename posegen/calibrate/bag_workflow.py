"""The calibrate stage's rosbag2 commands: ``posegen simulate ROUTE --bag`` and ``posegen measure``.

``simulate --bag`` simulates a recording (:mod:`posegen.calibrate.simulated_recording`) and writes it
as a real robot would: ``sensor_msgs/JointState`` at the recording rate and one
``geometry_msgs/WrenchStamped`` topic per wrist (the chains' ``wrench_topic``). ``measure``
reads such a bag, finds the contact windows (:mod:`posegen.calibrate.contact_windows`)
and writes posegen measurements, one contact per accepted window.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.arguments import check_seed, check_within
from posegen.calibrate.contact_windows import (
    PlannedContact,
    Rejection,
    Window,
    find_windows,
    match_windows,
    still_shares,
)
from posegen.calibrate.simulated_recording import Motion, SensorSettings, route_motion, simulate_recording
from posegen.calibrate.stream_topics import check_stream_topics, wrench_topics
from posegen.calibrate.tool_gravity import ToolGravity, wrist_forces
from posegen.calibrate.workflow import check_compliance, contact_noise_record, perturbation_of, truth_record
from posegen.errors import ArgumentError, InputError, unknown_name
from posegen.io import (
    JointStates,
    OutputKind,
    RecordedBag,
    Wrenches,
    check_apart,
    check_bag_destination,
    check_writable,
    claim_output,
    dump_yaml,
    read_route,
    write_recording,
    write_yaml,
)
from posegen.model import LIMIT_TOLERANCE_RAD, ContactModel, Contacts, measurements_to_dict, planned_kinds
from posegen.robot import FloatArray, Scene, load_config, scene_for

TRUTH_FILE = "truth.yaml"  # a simulated session's true parameters, inside its bag folder
MIN_RATE_HZ = 50.0  # a simulated recording's lowest rate: measure's joint speed spans 0.04 s (two samples)
MAX_RATE_HZ = 2000.0  # a simulated recording's highest rate: twice a 1 kHz control loop; memory grows with it


@dataclass(frozen=True)
class SimulatedBag:
    """What ``posegen simulate --bag`` wrote."""

    bag: Path
    truth: Path  # the true parameters, in the bag's folder (written with it, as one)
    contacts: int
    duration_s: float  # of the recording
    samples: int  # joint states


@dataclass(frozen=True)
class Measured:
    """What ``posegen measure`` found and wrote."""

    output: Path
    windows: tuple[Window, ...]  # accepted, one contact each
    rejected: tuple[Rejection, ...]
    wrench_topics: dict[str, str]  # chain -> topic ({} when measured on joint speed alone)
    duration_s: float  # of the joint states
    tools: tuple[ToolGravity, ...] = ()  # per wrist: the tool's weight removed from its readings


def _sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _route(route_path: str, scene: Scene | None, config_path: str | None = None) -> tuple[Motion, Scene]:
    """A route's motion, and the scene it runs in (``scene``, or the route's own config or ``config_path``)."""
    route = read_route(route_path)
    scene = scene or scene_for(route.provenance, config_path)
    scene.check_made_for(route.provenance, route_path)
    route.joint_columns(scene.joint_names, route_path)  # the robot's joints, each once, in any order (as check)
    route.check_chains([c.name for c in scene.config.chains], route_path)  # its contacts' arms (as check)
    return route_motion(route).in_order(scene.joint_names), scene


def simulate_route_bag(
    route_path: str,
    bag: str,
    *,
    config_path: str | None,
    seed: int,
    error_mm: float,
    error_deg: float,
    noise_deg: float,
    session: str,
    rate_hz: float,
    joint_topic: str,
    compliance_rad_per_knm: float = 0.0,
    every_chain: bool = False,
    contact_noise_mm: float = 0.0,
    contact_noise_deg: float = 0.0,
) -> SimulatedBag:
    """Record a perturbed robot executing a route, as a rosbag2 with the truth in its folder.

    Args:
        route_path: Route file.
        bag: Bag directory to write (with ``truth.yaml`` in it, swapped in as one).
        config_path: Scene config; None: the one saved in the route.
        seed: Seed of the robot's errors (the robot ``posegen simulate`` makes) and of the noise.
        error_mm: Sigma of placement length errors (mm).
        error_deg: Sigma of placement angle errors (deg, clipped at 1.5 deg).
        noise_deg: Sigma of the encoder noise, per sample (deg).
        session: Table session (names the true plane).
        rate_hz: Recording rate of the joint states and wrenches (Hz, from ``MIN_RATE_HZ`` to ``MAX_RATE_HZ``).
        joint_topic: Topic of the joint states.
        compliance_rad_per_knm: True compliance of the config's first compliance group.
        every_chain: The robot drawn with every chain of the config (the same robot for
            every route of a seed); False: with the route's chains, as ``posegen simulate``.
        contact_noise_mm: Sigma of each contact's local table height (mm).
        contact_noise_deg: Sigma of each contact's local table roll and pitch (deg).

    Raises:
        PosegenError: Not a route, a route without contacts or for another robot, or a
            contact that does not settle on the true plane.

    """
    check_seed(seed, "seed")
    perturbation = perturbation_of(
        error_mm, error_deg, noise_deg, compliance_rad_per_knm, contact_noise_mm, contact_noise_deg
    )
    check_within(rate_hz, "rate_hz", MIN_RATE_HZ, MAX_RATE_HZ)
    bag_path = Path(bag)
    truth = bag_path / TRUTH_FILE
    check_writable(bag_path, OutputKind.FOLDER)
    check_apart([bag_path], [route_path, config_path])
    check_bag_destination(bag_path)
    motion, scene = _route(route_path, None, config_path)
    check_compliance(scene, compliance_rad_per_knm)
    check_stream_topics(scene, joint_topic)  # before the simulation: every wrist needs a topic of its own
    if not motion.contacts:
        raise InputError(f"{route_path}: the route makes no contact")
    settings = SensorSettings(rate_hz=rate_hz)
    with claim_output(bag_path, OutputKind.FOLDER):
        recorded = simulate_recording(scene, motion, session, perturbation, settings, seed, every_chain)
        prov = scene.provenance(seed)
        prov["simulation"] = {
            "route": route_path,
            "route_sha256": _sha256(route_path),
            "session": session,
            "error_mm": error_mm,
            "error_deg": error_deg,
            "encoder_noise_deg": noise_deg,
            "compliance_rad_per_knm": compliance_rad_per_knm,
            "every_chain": every_chain,
            **contact_noise_record(contact_noise_mm, contact_noise_deg),
            "sensors": dataclasses.asdict(settings),
        }
        wrenches = {
            topic: Wrenches(recorded.times_s, recorded.forces[chain], recorded.torques[chain])
            for chain, topic in wrench_topics(scene).items()
        }
        joints = JointStates(scene.joint_names, recorded.times_s, recorded.positions)
        true = dump_yaml(truth_record(recorded.model, recorded.theta, prov))
        write_recording(bag_path, joints, joint_topic, wrenches, prov, extra={TRUTH_FILE: true})
    return SimulatedBag(bag_path, truth, len(motion.contacts), float(recorded.times_s[-1]), len(recorded.times_s))


def _columns(scene: Scene, joints: JointStates, where: str) -> tuple[list[int], list[str]]:
    """Model index of each recorded joint, and the locked joints the recording lacks."""
    unknown = [n for n in joints.names if n not in scene.joint_names]
    if unknown:
        raise InputError(f"{where}: {unknown_name('joint', unknown[0], scene.joint_names)}")
    columns = [scene.joint_names.index(n) for n in joints.names]
    absent = [i for i in range(len(scene.joint_names)) if i not in set(columns)]
    free = [scene.joint_names[i] for i in absent if not scene.locked[i]]
    if free:
        raise InputError(f"{where}: no {', '.join(free)} (every joint the config does not lock is needed)")
    return columns, [scene.joint_names[i] for i in absent]


def _heights(scene: Scene, windows: list[Window], motion: Motion, columns: list[int], base: FloatArray) -> list[float]:
    """Height (m, nominal kinematics) of each window's contact frame, on the arm of its nearest planned contact.

    Only compared between windows of one contact: an approach posture is
    ``approach_standoff_m`` above its contact whatever the robot's kinematic errors.
    """
    if not windows:
        return []
    targets = np.array([c.posture[columns] for c in motion.contacts])  # (m, nw)
    chains = tuple(motion.contacts[int(np.argmin(np.abs(targets - w.joints).max(axis=1)))].chain for w in windows)
    held = np.repeat(base[None, :], len(windows), axis=0)
    held[:, columns] = [w.joints for w in windows]
    model = ContactModel(scene, sorted(set(chains)), ["nominal"])
    contacts = Contacts(held, chains, ("nominal",) * len(chains), ("",) * len(chains), planned_kinds(scene, chains))
    return [float(h) for h in model.residuals(model.nominal(), contacts)[:, 0]]


def _within_limits(
    scene: Scene, windows: list[Window], columns: list[int], base: FloatArray, rejected: list[Rejection]
) -> tuple[list[Window], list[FloatArray]]:
    """The windows whose angles are finite and within the limits (widened as for recorded files).

    Returns:
        Those windows, and their joint angles (nj,) in the robot's order (joints the
        recording lacks at their locked value); the others are reported in ``rejected``.

    """
    accepted: list[Window] = []
    full: list[FloatArray] = []
    for window in windows:
        values = base.copy()
        values[columns] = window.joints
        outside = ~np.isfinite(values) | (values < scene.lower - LIMIT_TOLERANCE_RAD)
        outside |= values > scene.upper + LIMIT_TOLERANCE_RAD
        if np.any(outside):
            name = scene.joint_names[int(np.flatnonzero(outside)[0])]
            rejected.append(Rejection(window.start_s, window.end_s, f"{name} outside its limits"))
            continue
        accepted.append(window)
        full.append(values)
    return accepted, full


def measure_bag(
    bag: str,
    output: str,
    *,
    config_path: str,
    route_path: str | None,
    session: str | None,
    joint_topic: str,
    use_wrench: bool,
) -> Measured:
    """Turn a recorded session into posegen measurements, one contact per static contact window.

    Args:
        bag: rosbag2 directory.
        output: Measurement file to write.
        config_path: Scene config (joints, chains' wrench topics, thresholds in ``recording``).
        route_path: The route the robot ran: names the arm and posture of each window,
            aligned in order. Needed without a wrench topic.
        session: Table session of the contacts (default: the bag's directory name).
        joint_topic: ``sensor_msgs/JointState`` topic.
        use_wrench: Read the wrist wrenches (the config's topics); False: joint speed alone.

    Raises:
        PosegenError: Not a readable rosbag2, a missing topic or a message of another type,
            joints the robot does not have, a route other than the one a simulated bag ran, or no
            contact window.

    """
    if route_path is None and not use_wrench:
        raise InputError(
            "without a wrench topic, route_path is needed to tell contacts from pauses", parameter="route_path"
        )
    if session is not None and not session.strip():
        raise ArgumentError("session: give a session name", parameter="session")
    check_writable(output)
    check_apart([output], [bag, route_path, config_path])
    recorded = RecordedBag(bag)  # checked first: a bad bag is the likeliest mistake, and cheap to find
    scene = Scene(load_config(config_path))
    planned_motion = None if route_path is None else _route(route_path, scene)[0]
    route_digest = _sha256(route_path) if route_path else None
    route_sha = ((recorded.provenance or {}).get("simulation") or {}).get("route_sha256")
    if route_sha and route_digest and route_sha != route_digest:
        raise InputError(
            f"{bag}: a recording of another route than {route_path} (posegen simulated it from a route of sha256 "
            f"{str(route_sha)[:12]}): give that route",
            parameter="route_path",
        )
    topics = wrench_topics(scene, measuring=True) if use_wrench else {}
    with claim_output(output):
        joints, wrenches, digest = recorded.read_and_hash(joint_topic, list(topics.values()))
        columns, absent = _columns(scene, joints, f"{bag}: topic '{joint_topic}'")
        base = np.where(scene.locked, scene.locked_values, scene.reference)
        found = _contact_windows(scene, joints, columns, base, dict(zip(topics, wrenches, strict=True)), planned_motion)
        if not found.accepted:
            rejected = found.rejected
            first = f"; first rejected: {rejected[0].start_s:.2f} s, {rejected[0].reason}" if rejected else ""
            raise InputError(f"{bag}: no contact window found ({len(rejected)} rejected{first}; {found.shares})")
        name = session or Path(bag).resolve().name
        duration = float(joints.times_s[-1] - joints.times_s[0])
        prov = scene.provenance(None)
        prov["recording"] = {
            "bag": str(bag),
            "bag_sha256": digest,
            "storage": recorded.storage,
            "session": name,
            "topics": {"joint_states": joint_topic, "wrenches": topics},
            "thresholds": dataclasses.asdict(scene.config.recording),
            "route": route_path,
            "route_sha256": route_digest,
            "joint_states": {"samples": len(joints.times_s), "duration_s": duration},
            "joints_not_recorded": absent,
            "tool_gravity": {tool.chain: _tool_fields(tool) for tool in found.tools},
        }
        write_yaml(output, _measurements(scene, found, bag, name, prov))
        return Measured(Path(output), found.accepted, found.rejected, topics, duration, found.tools)


@dataclass(frozen=True)
class _Found:
    """The contact windows of a recording."""

    accepted: tuple[Window, ...]
    joints: FloatArray  # (n, nj) rad: each accepted window's angles in the robot's order
    rejected: tuple[Rejection, ...]  # by time
    tools: tuple[ToolGravity, ...]  # each wrist's tool model (none without wrench topics)
    shares: str  # without an accepted window: how much of the recording was still and pressed (for the message)


def _contact_windows(
    scene: Scene,
    joints: JointStates,
    columns: list[int],
    base: FloatArray,
    wrenches: dict[str, Wrenches],
    planned_motion: Motion | None,
) -> _Found:
    """A recording's windows: on the wrists' compensated force (or the joints alone), matched to the route."""
    settings = scene.config.recording
    forces: dict[str, FloatArray] | None = None
    tools: tuple[ToolGravity, ...] = ()
    if wrenches:
        angles = np.repeat(base[None, :], len(joints.times_s), axis=0)  # (n, nj) in the robot order
        angles[:, columns] = joints.positions
        forces, tools = wrist_forces(scene, joints.times_s, angles, wrenches, settings.force_threshold_n)
    windows, rejected = find_windows(joints.times_s, joints.positions, forces, settings)
    if planned_motion is not None:
        planned = [PlannedContact(c.chain, c.label, c.posture[columns]) for c in planned_motion.contacts]
        heights = None if wrenches else _heights(scene, windows, planned_motion, columns, base)
        windows = match_windows(windows, planned, settings.match_tolerance_rad, rejected, heights, settings.match_ratio)
    accepted, full = _within_limits(scene, windows, columns, base, rejected)
    rejected.sort(key=lambda r: r.start_s)
    shares = "" if accepted else still_shares(joints.times_s, joints.positions, forces, settings)
    return _Found(tuple(accepted), np.array(full), tuple(rejected), tools, shares)


def _measurements(scene: Scene, found: _Found, bag: str, session: str, provenance: dict[str, Any]) -> dict[str, Any]:
    """The measurement file's data: one contact per accepted window, with its times, and the windows left out."""
    labels = tuple(f"{Path(bag).name}:{w.label or 'contact'}@{w.start_s:.2f}s" for w in found.accepted)
    made = tuple(w.chain for w in found.accepted)
    sessions = (session,) * len(made)
    contacts = Contacts(found.joints, made, sessions, labels, planned_kinds(scene, made))
    data = measurements_to_dict(scene, contacts, provenance)
    for entry, window in zip(data["contacts"], found.accepted, strict=True):
        entry.update(_window_fields(window))
    data["rejected"] = [{"start_s": r.start_s, "end_s": r.end_s, "reason": r.reason} for r in found.rejected]
    return data


def _tool_fields(tool: ToolGravity) -> dict[str, Any]:
    return {
        "fitted": tool.fitted,
        "mass_kg": round(tool.mass_kg, 4),
        "com_distance_m": round(tool.com_distance_m, 4),
        "free_fraction": round(tool.free_fraction, 4),
        "note": tool.note,
    }


def _window_fields(window: Window) -> dict[str, Any]:
    return {
        "start_s": round(window.start_s, 6),
        "end_s": round(window.end_s, 6),
        "samples": window.samples,
        "joint_std_rad": float(window.std_rad),
        "force_n": None if np.isnan(window.force_n) else round(window.force_n, 3),
    }
