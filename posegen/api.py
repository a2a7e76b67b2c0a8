"""posegen's public API: every command from Python, files in and out, artefacts as frozen objects.

One function per command, in one shape: the input path(s) first, the output path second,
then keyword-only options whose defaults are the command line's. Each returns the artefact
it wrote (or what a check found) as a frozen object. The names are re-exported at
``posegen.`` (``import posegen; posegen.generate_pool(...)``) and are the supported API;
the subpackages' names are internal and may change between versions.

Example:
    >>> import posegen
    >>> pool = posegen.generate_pool("configs/talos_table.yaml", "plans/pool.yaml", n=200, seed=1)
    >>> chosen = posegen.select_postures("plans/pool.yaml", "plans/selected.yaml")
    >>> posegen.plan_route("plans/selected.yaml", "plans/route.yaml")

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from posegen.arguments import check_path, check_paths, check_type
from posegen.calibrate import (
    CALIBRATION_FORMAT,
    Calibrated,
    CalibrationSummary,
    Measured,
    Simulated,
    SimulatedBag,
    calibrate_files,
    file_lines,
    format_table,
    load_line,
    measure_bag,
    read_summary,
    simulate_postures_file,
    simulate_route_bag,
)
from posegen.calibrate import Settings as CalibrationSettings
from posegen.errors import ArgumentError, InputError
from posegen.io import POOL_FORMAT, ROUTE_FORMAT, SELECTION_FORMAT, Pool, Route, load_pool, read_route, read_yaml
from posegen.model import MEASUREMENT_FORMAT, Measurements, read_measurements
from posegen.parallel import Backend
from posegen.pool import check_pool_file, generate_pool_file
from posegen.resources import DEFAULT_CONFIG
from posegen.robot import Scene, Verification, load_config, scene_for
from posegen.route import Exported, Routed, check_route_file, export_route_bag, route_postures_file
from posegen.select import Selection, SelectionSettings, follow_up_pool_file, read_selection, select_pool_file

JOINT_STATES_TOPIC = "/joint_states"  # ROS 2 convention (joint_state_broadcaster)
TRAJECTORY_TOPIC = "/joint_trajectory_controller/joint_trajectory"  # ros2_control's trajectory controller
SEGMENTS_TOPIC = "/posegen/segments"
CALIBRATION_FILE = "calibration.yaml"


@dataclass(frozen=True)
class SimulatedRobot:
    """A perturbed robot for :func:`simulate` and :func:`simulate_recording` (``posegen simulate``'s options).

    Example:
        >>> robot = posegen.SimulatedRobot(seed=7, error_mm=2.0, contact_noise_mm=3.0)

    """

    seed: int = 0  # of its errors and noise
    error_mm: float = 2.0  # sigma of placement length errors, mm
    error_deg: float = 0.5  # sigma of placement angle errors, deg (clipped at 1.5)
    noise_deg: float = 0.005  # encoder noise sigma, deg
    compliance_rad_per_knm: float = 0.0  # true compliance of the config's first compliance group
    contact_noise_mm: float = 0.0  # sigma of each contact's local table height, mm (the real data: ~3)
    contact_noise_deg: float = 0.0  # sigma of each contact's local table roll and pitch, deg (~0.3)

    def options(self) -> dict[str, Any]:
        """The robot as the keyword arguments of the simulate functions.

        Example:
            >>> posegen.SimulatedRobot().options()["error_mm"]
            2.0

        """
        return {
            "seed": self.seed,
            "error_mm": self.error_mm,
            "error_deg": self.error_deg,
            "noise_deg": self.noise_deg,
            "compliance_rad_per_knm": self.compliance_rad_per_knm,
            "contact_noise_mm": self.contact_noise_mm,
            "contact_noise_deg": self.contact_noise_deg,
        }


def load_scene(config: str | Path = DEFAULT_CONFIG) -> Scene:
    """The robot at its table, from a scene config (``configs/*.yaml``; a draft of ``posegen robot init``).

    Example:
        >>> scene = posegen.load_scene("configs/talos_table.yaml")
        >>> scene.joint_names[:2]

    """
    return Scene(load_config(check_path(config, "config")))


def load(path: str | Path) -> Pool | Selection[Any] | Route | Measurements | CalibrationSummary:
    """Any posegen artefact, as its object: a pool, a selection, a route, measurements or a calibration folder.

    A route is read with its arrays, checked; measurements with the scene their
    provenance names.

    Raises:
        InputError: Not a posegen artefact, or one its reader refuses.

    Example:
        >>> pool = posegen.load("plans/pool.yaml")
        >>> len(pool.postures)

    """
    where = Path(check_path(path, "path"))
    if where.is_dir():
        return read_summary(where / CALIBRATION_FILE)
    header = read_yaml(where, (POOL_FORMAT, SELECTION_FORMAT, ROUTE_FORMAT, MEASUREMENT_FORMAT, CALIBRATION_FORMAT))
    kind = header["format"]
    if kind == POOL_FORMAT:
        return load_pool(where)
    if kind == SELECTION_FORMAT:
        return read_selection(where)
    if kind == ROUTE_FORMAT:
        return read_route(where)
    if kind == MEASUREMENT_FORMAT:
        return read_measurements(where, scene_for(header.get("provenance") or {}, None))
    if kind == CALIBRATION_FORMAT:
        return read_summary(where)
    raise InputError(f"{where}: not a posegen artefact (format: {kind!r})")


def generate_pool(
    config: str | Path, output: str | Path, *, n: int = 1500, seed: int = 0, workers: int | Backend = 1
) -> Pool:
    """``posegen pool``: feasible contact postures (balance, contact, limits, collisions), written to ``output``.

    Example:
        >>> pool = posegen.generate_pool("configs/talos_table.yaml", "plans/pool.yaml", n=200, seed=1)
        >>> pool.postures[0].chain

    """
    return generate_pool_file(
        check_path(config, "config"), check_path(output, "output"), n=n, seed=seed, workers=workers
    )


def check_pool(pool: str | Path, *, config: str | Path | None = None, workers: int | Backend = 1) -> Verification:
    """``posegen check POOL``: every posture re-verified from scratch on the robot's meshes.

    Example:
        >>> posegen.check_pool("plans/pool.yaml").ok
        True

    """
    return check_pool_file(check_path(pool, "pool"), _optional(config), workers=workers)


def select_postures(
    pool: str | Path,
    output: str | Path,
    *,
    settings: SelectionSettings | None = None,
    config: str | Path | None = None,
) -> Selection[Any]:
    """``posegen select``: the postures of a pool that identify the kinematics best (IROC, DETMAX, exact k).

    Example:
        >>> chosen = posegen.select_postures("plans/pool.yaml", "plans/selected.yaml",
        ...                                  settings=posegen.SelectionSettings(k=40))
        >>> len(chosen.postures)
        40

    """
    return select_pool_file(
        check_path(pool, "pool"),
        check_path(output, "output"),
        check_type(settings, SelectionSettings, "settings"),
        _optional(config),
    )


def follow_up(
    pool: str | Path,
    output: str | Path,
    given: Sequence[str | Path],
    *,
    k: int = 10,
    calibration: str | Path | None = None,
    weakest: str | None = None,
    config: str | Path | None = None,
) -> Selection[Any]:
    """``posegen select --given``: the next ``k`` postures that shrink the weakest chain's predicted error.

    Example:
        >>> more = posegen.follow_up("plans/pool.yaml", "plans/next.yaml", ["recorded.yaml"], k=6)

    """
    return follow_up_pool_file(
        check_path(pool, "pool"),
        check_path(output, "output"),
        check_paths(given, "given"),
        _optional(calibration, "calibration"),
        k=k,
        config_path=_optional(config),
        weakest=weakest,
    )


def plan_route(
    postures: str | Path,
    output: str | Path,
    *,
    seed: int = 0,
    workers: int | Backend = 1,
    pool: str | Path | None = None,
    csv: bool = False,
    config: str | Path | None = None,
) -> Routed:
    """``posegen route``: the order, the free motions and the timing through a selection (or pool).

    ``pool``: the selection's pool, to replace a posture that cannot be reached.

    Example:
        >>> routed = posegen.plan_route("plans/selected.yaml", "plans/route.yaml", seed=0)

    """
    return route_postures_file(
        check_path(postures, "postures"),
        check_path(output, "output"),
        seed=seed,
        config_path=_optional(config),
        workers=workers,
        pool_path=_optional(pool, "pool"),
        csv=csv,
    )


def check_route(route: str | Path, *, config: str | Path | None = None, workers: int | Backend = 1) -> Verification:
    """``posegen check ROUTE``: every point of a route re-checked (limits, balance, collisions, speeds).

    Example:
        >>> posegen.check_route("plans/route.yaml").ok
        True

    """
    return check_route_file(check_path(route, "route"), _optional(config), workers=workers)


def export_route(
    route: str | Path, bag: str | Path, *, topic: str = TRAJECTORY_TOPIC, segments_topic: str = SEGMENTS_TOPIC
) -> Exported:
    """``posegen export --bag``: a route as a rosbag2 of JointTrajectory messages (needs ``posegen[ros]``).

    Example:
        >>> posegen.export_route("plans/route.yaml", "plans/route_bag")

    """
    return export_route_bag(check_path(route, "route"), check_path(bag, "bag"), topic, segments_topic)


def simulate(
    postures: str | Path,
    output: str | Path,
    *,
    robot: SimulatedRobot | None = None,
    session: str = "sim",
    config: str | Path | None = None,
) -> Simulated:
    """``posegen simulate``: the contacts a perturbed robot makes at planned postures (truth written beside).

    Example:
        >>> posegen.simulate("plans/selected.yaml", "plans/sim.yaml", robot=posegen.SimulatedRobot(seed=7))

    """
    options = (check_type(robot, SimulatedRobot, "robot") or SimulatedRobot()).options()
    postures, output = check_path(postures, "postures"), check_path(output, "output")
    session = check_type(session, str, "session")
    return simulate_postures_file(postures, output, config_path=_optional(config), session=session, **options)


def simulate_recording(
    route: str | Path,
    bag: str | Path,
    *,
    robot: SimulatedRobot | None = None,
    rate_hz: float = 500.0,
    session: str = "sim",
    joint_topic: str = JOINT_STATES_TOPIC,
    config: str | Path | None = None,
) -> SimulatedBag:
    """``posegen simulate ROUTE --bag``: a perturbed robot running a route, recorded as a rosbag2 (``[ros]``).

    Example:
        >>> posegen.simulate_recording("plans/route.yaml", "plans/recording", rate_hz=100.0)

    """
    options = (check_type(robot, SimulatedRobot, "robot") or SimulatedRobot()).options()
    return simulate_route_bag(
        check_path(route, "route"),
        check_path(bag, "bag"),
        config_path=_optional(config),
        session=session,
        rate_hz=rate_hz,
        joint_topic=joint_topic,
        **options,
    )


def measure(
    bag: str | Path,
    output: str | Path,
    *,
    route: str | Path | None = None,
    config: str | Path = DEFAULT_CONFIG,
    session: str | None = None,
    joint_topic: str = JOINT_STATES_TOPIC,
    use_wrench: bool = True,
) -> Measured:
    """``posegen measure``: the static contacts of a recorded rosbag2, as measurements (``posegen[ros]``).

    ``route``: the route the robot ran (names each contact's arm and posture).

    Example:
        >>> found = posegen.measure("plans/recording", "plans/measured.yaml", route="plans/route.yaml")
        >>> len(found.windows)

    """
    return measure_bag(
        check_path(bag, "bag"),
        check_path(output, "output"),
        config_path=check_path(config, "config"),
        route_path=_optional(route, "route"),
        session=check_type(session, str, "session"),
        joint_topic=joint_topic,
        use_wrench=use_wrench,
    )


def calibrate_robot(
    measurements: Sequence[str | Path],
    output: str | Path,
    *,
    held_out: Sequence[str | Path] = (),
    settings: CalibrationSettings | None = None,
    config: str | Path | None = None,
) -> CalibrationSummary:
    """``posegen calibrate``: the kinematics identified, chosen by cross-validation; the folder a robot loads.

    Measurement files may name a table session as ``FILE@SESSION``.

    Example:
        >>> summary = posegen.calibrate_robot(["plans/measured.yaml"], "plans/calibration")
        >>> summary.deliverables  # each file written: its predicted error, and its error as a stack loading it sees it

    """
    calibrated: Calibrated = calibrate_files(
        check_paths(measurements, "measurements"),
        check_paths(held_out, "held_out"),
        check_path(output, "output"),
        check_type(settings, CalibrationSettings, "settings", "posegen.CalibrationSettings") or CalibrationSettings(),
        _optional(config),
    )
    return calibrated.summary


def describe_calibration(summary: CalibrationSummary) -> str:
    """What ``posegen calibrate`` prints of its files: each one's errors as a stack sees them, then what to load.

    Example:
        >>> print(posegen.describe_calibration(posegen.load("plans/calibration")))

    """
    if not isinstance(summary, CalibrationSummary):
        raise ArgumentError(f"summary must be a CalibrationSummary (posegen.load(FOLDER)), got {summary!r}")
    return "\n".join([*file_lines(summary), format_table(summary), load_line(summary)])


def write_view(artefact: str | Path, html: str | Path, *, config: str | Path | None = None) -> Path:
    """``posegen view ARTEFACT --html FILE``: a pool, selection, route or calibration as one 3D HTML page.

    Needs ``posegen[view]``; the page opens in any browser, offline.

    Example:
        >>> posegen.write_view("plans/route.yaml", "plans/route.html")

    """
    from posegen.view import write_html_file  # the viewer's packages are an extra: loaded only here

    write_html_file(check_path(artefact, "artefact"), check_path(html, "html"), _optional(config))
    return Path(html)


def _optional(path: str | Path | None, name: str = "config") -> str | None:
    return None if path is None else check_path(path, name)
