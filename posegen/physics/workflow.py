"""``posegen simulate ROUTE --physics --bag DIR``: a route rehearsed in MuJoCo by the perturbed robot, files to files.

The robot ``posegen simulate --bag`` draws for the seed (:mod:`posegen.physics.true_robot`)
stands free on the floor (or glued to it) at the table and runs the route with its
controllers (:mod:`posegen.physics.run`). The bag holds what its sensors recorded, as
``simulate --bag`` writes it: ``sensor_msgs/JointState`` on the joint topic and one
``geometry_msgs/WrenchStamped`` per wrist (the chains' ``wrench_topic``), the raw
readings (its tool's weight, an offset and noise included). Beside it, as one:
``truth.yaml`` (the true parameters, the plane and the floor constants as the robot
stood) and ``physics.yaml`` (:mod:`posegen.physics.physics_file`).
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from posegen.arguments import check_seed, check_size
from posegen.calibrate import (
    TRUTH_FILE,
    Perturbation,
    check_compliance,
    check_stream_topics,
    perturbation_of,
    truth_record,
)
from posegen.errors import ArgumentError, InputError
from posegen.io import (
    JointStates,
    OutputKind,
    Route,
    Wrenches,
    check_apart,
    check_bag_destination,
    check_writable,
    claim_output,
    dump_yaml,
    read_route,
    write_recording,
)
from posegen.physics.builder import TIMESTEP_S, build
from posegen.physics.contact_control import contact_times
from posegen.physics.figures import physics_report
from posegen.physics.gains import joint_gains
from posegen.physics.physics_file import PHYSICS_FILE, PhysicsReport, physics_to_dict
from posegen.physics.plan import sample_plan
from posegen.physics.run import Run, RunResult
from posegen.physics.sensors import SensorNoise, Sensors
from posegen.physics.tool import wrist_tool
from posegen.physics.true_robot import as_stood, draw_true_robot
from posegen.progress import ProgressCallback, ignore_progress
from posegen.robot import Scene, scene_for

REST_S = 1.0  # at rest before the route starts and after it ends (as simulate --bag)
PHYSICS_RATE_HZ = (
    250.0  # the default recording rate, at which the controllers run (whole-body controllers: 200-1000 Hz)
)


@dataclass(frozen=True)
class PhysicsBag:
    """What ``posegen simulate --physics --bag`` wrote."""

    bag: Path
    truth: Path  # the true parameters, in the bag's folder
    physics: Path  # the run's figures, in the bag's folder
    report: PhysicsReport
    samples: int  # joint states recorded
    wall_s: float  # wall time of the simulation


@dataclass(frozen=True)
class PhysicsOptions:
    """How the rehearsal runs (the command line's options)."""

    seed: int = 0
    error_mm: float = 2.0
    error_deg: float = 0.5
    noise_deg: float = 0.005
    session: str = "sim"
    rate_hz: float = PHYSICS_RATE_HZ
    joint_topic: str = "/joint_states"
    compliance_rad_per_knm: float = 0.0
    glued_feet: bool = False


def _stride(rate_hz: float) -> int:
    """Simulator steps per control period (the recording rate must divide the simulator's).

    Raises:
        ArgumentError: A rate that is not 500 Hz divided by a whole number from 1 to 10.

    """
    check_size(rate_hz, "rate_hz", positive=True)
    stride = round(1.0 / (rate_hz * TIMESTEP_S))
    if not 1 <= stride <= 10 or abs(stride * rate_hz * TIMESTEP_S - 1.0) > 1e-9:
        rates = ", ".join(f"{1.0 / (k * TIMESTEP_S):g}" for k in (1, 2, 4, 5, 10))
        raise ArgumentError(
            f"rate_hz={rate_hz:g}: the physics controllers run at the recording rate, which must divide "
            f"{1.0 / TIMESTEP_S:g} Hz, at least {1.0 / (10 * TIMESTEP_S):g} Hz ({rates})",
            parameter="rate_hz",
        )
    return stride


def _sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _provenance(scene: Scene, route_path: str, options: PhysicsOptions) -> dict[str, Any]:
    prov = scene.provenance(options.seed)
    settings = asdict(options)
    del settings["seed"]
    prov["simulation"] = {
        "route": route_path,
        "route_sha256": _sha256(route_path),
        "physics": {
            **settings,
            "engine": f"mujoco {mujoco.__version__}",
            "timestep_s": TIMESTEP_S,
            "rest_s": REST_S,
            "sensors": asdict(SensorNoise()),
        },
    }
    return prov


def _check(route_path: str, bag: Path, config_path: str | None, options: PhysicsOptions) -> tuple[int, Perturbation]:
    """Every argument and the output checked before any work; returns the stride and the perturbation."""
    check_seed(options.seed, "seed")
    perturbation = perturbation_of(
        options.error_mm, options.error_deg, options.noise_deg, options.compliance_rad_per_knm
    )
    stride = _stride(options.rate_hz)
    check_writable(bag, OutputKind.FOLDER)
    check_apart([bag], [route_path, config_path])
    check_bag_destination(bag)
    return stride, perturbation


def simulate_physics_bag(
    route_path: str,
    bag: str,
    *,
    config_path: str | None,
    options: PhysicsOptions,
    progress: ProgressCallback = ignore_progress,
) -> PhysicsBag:
    """Rehearse a route in MuJoCo on the perturbed robot and write its recording, truth and figures.

    Args:
        route_path: Route file.
        bag: Bag directory to write (``truth.yaml`` and ``physics.yaml`` in it, swapped in as one).
        config_path: Scene config; None: the one saved in the route.
        options: The robot's errors and noise, the recording, glued feet.
        progress: Told the robot time simulated, in seconds.

    Raises:
        PosegenError: Bad arguments or output, not a route, a route without contacts or
            for another robot, a robot MuJoCo cannot build.

    Example:
        >>> done = simulate_physics_bag("plans/route.yaml", "plans/physics", config_path=None, options=PhysicsOptions())
        >>> done.report.summary.completed

    """
    bag_path = Path(bag)
    stride, perturbation = _check(route_path, bag_path, config_path, options)
    route = read_route(route_path)
    scene = scene_for(route.provenance, config_path)
    scene.check_made_for(route.provenance, route_path)
    route.joint_columns(scene.joint_names, route_path)
    check_compliance(scene, options.compliance_rad_per_knm)
    topics = check_stream_topics(scene, options.joint_topic)
    contacts = contact_times(route)
    if not contacts:
        raise InputError(f"{route_path}: the route makes no contact")
    with claim_output(bag_path, OutputKind.FOLDER):
        started = time.perf_counter()
        result, truth = _run(scene, route, options, perturbation, stride, progress)
        wall = time.perf_counter() - started
        prov = _provenance(scene, route_path, options)
        report = physics_report(
            prov,
            route,
            result.plan,
            result.truth,
            result.route_index,
            scene.joint_names,
            contacts,
            result.fell_at_s,
            scene.route.contact_force_n,
        )
        recorded = result.recorded
        joints = JointStates(scene.joint_names, recorded.times_s, recorded.encoders)
        wrenches = {
            topic: Wrenches(recorded.times_s, recorded.wrists[chain][:, :3], recorded.wrists[chain][:, 3:])
            for chain, topic in topics.items()
        }
        extra = {TRUTH_FILE: dump_yaml(truth | {"provenance": prov}), PHYSICS_FILE: dump_yaml(physics_to_dict(report))}
        write_recording(bag_path, joints, options.joint_topic, wrenches, prov, extra=extra)
    return PhysicsBag(bag_path, bag_path / TRUTH_FILE, bag_path / PHYSICS_FILE, report, len(recorded.times_s), wall)


def _run(
    scene: Scene,
    route: Route,
    options: PhysicsOptions,
    perturbation: Perturbation,
    stride: int,
    progress: ProgressCallback,
) -> tuple[RunResult, dict[str, Any]]:
    """Build the true robot, run the route, and the truth record (plane and floor as the robot stood)."""
    robot = draw_true_robot(scene, options.session, perturbation, options.seed)
    gains = joint_gains(scene)
    tools = {c.name: wrist_tool(scene, c.sensor_frame) for c in scene.chains}
    built = build(scene, robot.urdf, robot.table_top, gains, tools, robot.springs, options.glued_feet)
    period = stride * TIMESTEP_S
    plan = sample_plan(scene, route, period, REST_S)
    noise = SensorNoise(encoder_rad=float(np.deg2rad(options.noise_deg)))
    sensors = Sensors(built.layout, noise, options.seed)
    run = Run(scene, built, gains, plan, contact_times(route), sensors, tools, scene.route.contact_force_n, stride)
    result = run.run(progress)
    stood = as_stood(robot, result.soles_at_start) if result.soles_at_start else robot.x
    return result, truth_record(robot.model, stood, {})
