"""``posegen simulate``: contacts of a perturbed robot at planned postures, or a recorded session (``--bag``).

With ``--physics``, the session is rehearsed in MuJoCo: the perturbed robot stands free
on the floor (``--glued-feet``: welded to it) and runs the route with its controllers.
"""

from __future__ import annotations

import argparse

from posegen.cli.options import JOINT_STATES_TOPIC, positive_size, seed, session_name, size
from posegen.cli.progress import ProgressBar

KINEMATIC_RATE_HZ = 500.0  # the default rate of a kinematic recording (simulate --bag)
MEASUREMENTS_FILE = "plans/sim/measurements.yaml"  # the default output without --bag

NAME = "simulate"
HELP = "contacts of a perturbed robot at planned postures, or its recorded run of a route (--bag)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("postures", help="pool or selection file; with --bag, a route file")
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the robot errors and noise (default 0)")
    parser.add_argument("--error-mm", type=size, default=2.0, help="sigma of length errors (default 2 mm)")
    parser.add_argument(
        "--error-deg", type=size, default=0.5, help="sigma of angle errors (default 0.5 deg, clipped 1.5)"
    )
    parser.add_argument("--noise-deg", type=size, default=0.005, help="encoder noise sigma (default 0.005 deg)")
    parser.add_argument("--session", type=session_name, default="sim", help="table session name (default sim)")
    parser.add_argument(
        "--compliance",
        type=size,
        default=0.0,
        help="true compliance, rad/kN m, of the config's first calibration.compliance group (default 0: rigid)",
    )
    parser.add_argument(
        "--contact-noise-mm",
        type=size,
        default=0.0,
        help="sigma of each contact's local table height, mm (default 0; the real recordings: ~3)",
    )
    parser.add_argument(
        "--contact-noise-deg",
        type=size,
        default=0.0,
        help="sigma of each contact's local table roll and pitch, deg (default 0; the real recordings: ~0.3)",
    )
    parser.add_argument(
        "-o", "--output", default=None, help=f"measurement file, without --bag (default {MEASUREMENTS_FILE})"
    )
    bag = parser.add_argument_group("recorded session (a route run by the perturbed robot)")
    bag.add_argument("--bag", metavar="DIR", help="write the session as a rosbag2 (MCAP); truth in DIR/truth.yaml")
    bag.add_argument(
        "--rate",
        type=positive_size,
        default=None,
        help="joint state and wrench rate in Hz (default 500; with --physics 250: its controllers run at this rate)",
    )
    bag.add_argument("--joint-topic", default=None, help=f"JointState topic (default {JOINT_STATES_TOPIC})")
    bag.add_argument(
        "--physics",
        action="store_true",
        help="rehearse the route in MuJoCo: a free-standing robot with its controllers (needs posegen[physics])",
    )
    bag.add_argument("--glued-feet", action="store_true", help="with --physics: the soles welded to the floor")


def run(args: argparse.Namespace) -> int:
    """Simulate, write the measurements (or the bag) and the truth, and say where."""
    from posegen.calibrate import simulate_postures_file, simulate_route_bag

    _check_options(args)
    topic = JOINT_STATES_TOPIC if args.joint_topic is None else args.joint_topic
    robot = {
        "config_path": args.config,
        "seed": args.seed,
        "error_mm": args.error_mm,
        "error_deg": args.error_deg,
        "noise_deg": args.noise_deg,
        "session": args.session,
        "compliance_rad_per_knm": args.compliance,
        "contact_noise_mm": args.contact_noise_mm,
        "contact_noise_deg": args.contact_noise_deg,
    }
    if args.physics or args.glued_feet:
        return _physics(args, topic)
    if args.bag:
        rate = args.rate or KINEMATIC_RATE_HZ
        recorded = simulate_route_bag(args.postures, args.bag, rate_hz=rate, joint_topic=topic, **robot)
        print(
            f"simulate: {recorded.contacts} contacts, {recorded.duration_s:.1f} s recorded at {rate:g} Hz "
            f"({recorded.samples} joint states) -> {recorded.bag}/ (true parameters: {recorded.truth})"
        )
        return 0
    output = MEASUREMENTS_FILE if args.output is None else args.output
    simulated = simulate_postures_file(args.postures, output, **robot)
    print(
        f"simulate: {simulated.contacts} contacts of a perturbed robot -> {simulated.measurements} "
        f"(true parameters: {simulated.truth})"
    )
    return 0


def _check_options(args: argparse.Namespace) -> None:
    """Refuse an option the chosen simulation would ignore (it would otherwise go unnoticed)."""
    from posegen.errors import ArgumentError

    if args.bag and args.output is not None:
        raise ArgumentError(
            "-o/--output is the measurement file of a simulation without --bag; --bag writes DIR (truth in "
            "DIR/truth.yaml): drop -o",
            parameter="output",
        )
    if not args.bag:
        for flag, value in (("--rate", args.rate), ("--joint-topic", args.joint_topic)):
            if value is not None:
                raise ArgumentError(f"{flag} is an option of a recorded session: give --bag DIR, or drop {flag}")


def _physics(args: argparse.Namespace, topic: str) -> int:
    """``--physics``: rehearse the route in MuJoCo, write the bag, its truth and physics.yaml, and say how it went.

    ``topic``: the bag's JointState topic.
    """
    from posegen.errors import ArgumentError

    if not args.physics:
        raise ArgumentError("--glued-feet is an option of --physics")
    if not args.bag:
        raise ArgumentError("--physics writes a recorded session: give --bag DIR")
    if args.contact_noise_mm or args.contact_noise_deg:
        raise ArgumentError(
            "--contact-noise-mm/--contact-noise-deg are the kinematic simulation's: physics makes its own"
        )
    from posegen.physics import PHYSICS_RATE_HZ, PhysicsOptions, simulate_physics_bag

    options = PhysicsOptions(
        seed=args.seed,
        error_mm=args.error_mm,
        error_deg=args.error_deg,
        noise_deg=args.noise_deg,
        session=args.session,
        rate_hz=args.rate or PHYSICS_RATE_HZ,
        joint_topic=topic,
        compliance_rad_per_knm=args.compliance,
        glued_feet=args.glued_feet,
    )
    with ProgressBar(args.quiet) as bar:
        done = simulate_physics_bag(args.postures, args.bag, config_path=args.config, options=options, progress=bar)
    s = done.report.summary
    state = "completed" if s.completed else f"FELL at {s.fell_at_s:.2f} s"
    low, high = s.hold_range_n
    print(
        f"simulate --physics: {state}, {s.duration_s:.1f} s of robot time in {done.wall_s:.1f} s -> {done.bag}/ "
        f"({done.samples} joint states; {done.physics.name}, {done.truth.name})"
    )
    print(
        f"  holds within [{low:g}, {high:g}] N: {s.holds_in_range} of {s.contacts}; "
        f"ZMP margin >= {1e3 * s.zmp_margin_min_m:.1f} mm; "
        f"sole slip <= {s.slip_max_mm:.2f} mm; pelvis within {1e3 * s.pelvis_deviation_max_m:.1f} mm of plan; "
        f"torque <= {s.torque_ratio_max:.2f} x effort ({s.torque_joint}); unwanted contacts {s.unwanted_contacts}"
    )
    return 0 if s.completed else 1
