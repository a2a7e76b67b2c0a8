"""The subcommands of ``posegen``: each reads its inputs, runs a stage, writes its outputs.

Library errors propagate as :class:`posegen.errors.PosegenError`; :mod:`posegen.cli`
turns them into exit codes. Printing here is the commands' output to the user.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from posegen.contact_model import Contacts
    from posegen.pool import Pool
    from posegen.scene import Scene

EXIT_VIOLATIONS = 1


def _progress_bar(total: int, unit: str, quiet: bool):  # type: ignore[no-untyped-def]
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, disable=quiet, file=sys.stderr, dynamic_ncols=True)


def run_pool(args: argparse.Namespace) -> int:
    """``posegen pool``: generate (or resume) a pool of feasible contact postures."""
    from posegen.artefact import write_yaml
    from posegen.config import load_config
    from posegen.generation import generate_pool

    config = load_config(args.config)
    output = Path(args.output)
    checkpoint = output.with_name(output.name + ".partial.jsonl")
    with _progress_bar(args.n, "posture", args.quiet) as bar:

        def progress(accepted: int, attempted: int) -> None:
            bar.update(accepted - bar.n)
            bar.set_postfix(attempted=attempted, refresh=False)

        pool = generate_pool(config, args.n, args.seed, args.workers, checkpoint, progress)
    write_yaml(output, pool.to_dict())
    checkpoint.unlink(missing_ok=True)
    rate = 100.0 * len(pool.postures) / max(pool.attempted, 1)
    print(f"pool: {len(pool.postures)} postures accepted of {pool.attempted} samples ({rate:.1f}%) -> {output}")
    print("rejected: " + (", ".join(f"{k} {v}" for k, v in pool.rejected.items()) or "none"))
    for spot, counts in pool.per_spot().items():
        print(f"  {spot}: " + ", ".join(f"{chain} {n}" for chain, n in counts.items()))
    return 0


def _scene_for(provenance: dict[str, Any], config_path: str | None, where: str) -> Scene:
    """The scene an artefact was made for (or the one of ``--config``), model hash checked."""
    from posegen.config import load_config, parse_config
    from posegen.errors import InputError
    from posegen.scene import Scene

    config = load_config(config_path) if config_path else parse_config(provenance.get("config"), "")
    scene = Scene(config)
    recorded = provenance.get("robot_model_sha256")
    if recorded and recorded != scene.files.sha256():
        raise InputError(f"{where} was made for another robot model (sha256 {recorded[:12]}...)")
    return scene


def run_check(args: argparse.Namespace) -> int:
    """``posegen check``: re-verify a pool or a route from scratch; 1 on any violation."""
    from posegen.artefact import read_yaml
    from posegen.errors import InputError
    from posegen.pool import POOL_FORMAT, pool_from_dict
    from posegen.route_check import verify_route
    from posegen.route_io import ROUTE_FORMAT, read_route
    from posegen.verification import verify_postures

    path = Path(args.file)
    try:
        head = path.read_text()[:4096]
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}") from exc
    is_route = path.suffix.lower() == ".json" or f"format: {ROUTE_FORMAT}" in head
    if is_route:
        data = read_route(path)
        scene = _scene_for(data.get("provenance") or {}, args.config, args.file)
        total, unit, what = len(data["trajectory"]["points"]), "point", "points"
    else:
        pool = pool_from_dict(read_yaml(path, POOL_FORMAT), args.file)
        scene = _scene_for(pool.provenance, args.config, args.file)
        if tuple(pool.joint_names) != scene.joint_names:
            raise InputError(f"{args.file}: joint names differ from the robot model's")
        total, unit, what = len(pool.postures), "posture", "postures"
    with _progress_bar(total, unit, args.quiet) as bar:
        step = lambda k: bar.update(k - bar.n)  # noqa: E731
        result = verify_route(scene, data, step) if is_route else verify_postures(scene, pool.postures, step)
    print(f"checked {result.checked} {what} of {args.file} (meshes, pinocchio; not the planner's word)")
    unit = "point" if is_route else "posture"
    for worst in result.worst:
        status = "OK  " if worst.violations == 0 else "FAIL"
        print(
            f"  {status} {worst.invariant.value:<13} violations {worst.violations:>4}  "
            f"worst: {unit} {worst.posture} ({worst.detail})"
        )
    return 0 if result.ok else EXIT_VIOLATIONS


def _load_plan(path: str) -> tuple[Pool, list[dict[str, Any]]]:
    """A pool or selection that has postures."""
    from posegen.errors import InputError
    from posegen.pool import load_plan

    plan, entries = load_plan(path)
    if not plan.postures:
        raise InputError(f"{path}: no postures")
    return plan, entries


def _check_joints(plan: Pool, scene: Scene, path: str) -> None:
    from posegen.errors import InputError

    if tuple(plan.joint_names) != scene.joint_names:
        raise InputError(f"{path}: joint names differ from the robot model's")


def run_route(args: argparse.Namespace) -> int:
    """``posegen route``: order, plan, time and export a trajectory through the postures."""
    import hashlib
    import time

    from posegen.motion import seed_planner
    from posegen.route import plan_route
    from posegen.route_io import route_to_dict, write_route

    plan, entries = _load_plan(args.selection)
    scene = _scene_for(plan.provenance, args.config, args.selection)
    _check_joints(plan, scene, args.selection)
    seed_planner(args.seed)
    start = time.perf_counter()
    with _progress_bar(len(plan.postures), "posture", args.quiet) as bar:
        route = plan_route(scene, plan.postures, args.seed, lambda k: bar.update(k - bar.n))
    elapsed = time.perf_counter() - start
    visited = len(route.visited)
    summary = {
        "postures": len(plan.postures),
        "routed": visited,
        "skipped": len(route.skipped),
        "points": len(route.times),
        "duration_s": float(route.times[-1]),
        "robot_time_per_contact_s": float(route.times[-1]) / max(visited, 1),
        "tsp_length_s": route.order.length_s,
        "nearest_neighbour_length_s": route.order.nearest_neighbour_s,
    }
    provenance = dict(plan.provenance)
    provenance.update(
        {
            "seed": args.seed,
            "selection": args.selection,
            "selection_sha256": hashlib.sha256(Path(args.selection).read_bytes()).hexdigest(),
        }
    )
    output = Path(args.output)
    csv_path = write_route(output, route_to_dict(route, entries, provenance, summary))
    print(
        f"route: {visited} of {len(plan.postures)} postures, {len(route.times)} points, "
        f"{summary['duration_s']:.1f} s of robot time ({summary['robot_time_per_contact_s']:.1f} s per contact), "
        f"planned in {elapsed:.1f} s -> {output} (and {csv_path.name})"
    )
    print(
        f"  order: TSP {route.order.length_s:.1f} s vs nearest neighbour {route.order.nearest_neighbour_s:.1f} s "
        "(time-like distance at the velocity limits)"
    )
    for index, reason in route.skipped:
        print(f"  skipped posture {index}: {reason}")
    return 0


def run_simulate(args: argparse.Namespace) -> int:
    """``posegen simulate``: contacts of a perturbed robot at planned postures."""
    import numpy as np

    from posegen.artefact import provenance, write_yaml
    from posegen.config import load_config
    from posegen.contact_model import Contacts
    from posegen.measurements import write_measurements
    from posegen.scene import Scene
    from posegen.simulation import Perturbation, simulate

    scene = Scene(load_config(args.config))
    plan, _ = _load_plan(args.postures)
    _check_joints(plan, scene, args.postures)
    chains = tuple(p.chain for p in plan.postures)
    planned = Contacts(plan.joints(), chains, (args.session,) * len(chains), tuple(p.spot for p in plan.postures))
    perturbation = Perturbation(
        length_m=args.error_mm * 1e-3,
        angle_rad=float(np.deg2rad(args.error_deg)),
        encoder_noise_rad=float(np.deg2rad(args.noise_deg)),
    )
    recorded, model, theta = simulate(scene, planned, perturbation, args.seed)
    prov = provenance(scene.config.to_dict(), scene.files.sha256(), args.seed)
    prov["simulation"] = {
        "postures": args.postures,
        "error_mm": args.error_mm,
        "error_deg": args.error_deg,
        "encoder_noise_deg": args.noise_deg,
    }
    output = Path(args.output)
    truth = output.with_name(output.stem + ".truth.yaml")
    nominal = model.nominal()
    write_yaml(
        truth,
        {
            "format": "posegen-truth",
            "format_version": 1,
            "provenance": prov,
            "parameters": {
                p.name: {"true": float(theta[i]), "nominal": float(nominal[i])} for i, p in enumerate(model.parameters)
            },
        },
    )
    write_measurements(output, scene, recorded, prov)
    print(f"simulate: {len(recorded)} contacts of a perturbed robot -> {output} (true parameters: {truth})")
    return 0


def _measurement_args(items: list[str], scene: Scene, rejected: list[str]) -> Contacts:
    """Read ``FILE[@SESSION]`` arguments into one set of contacts; rejected rows go to ``rejected``."""
    from posegen.measurements import read_measurements

    contacts: Contacts | None = None
    for item in items:
        path, _, session = item.partition("@")
        part = read_measurements(path, scene, session or None)
        rejected.extend(part.rejected)
        contacts = part.contacts if contacts is None else contacts.concat(part.contacts)
    assert contacts is not None  # argparse requires at least one file
    return contacts


def run_calibrate(args: argparse.Namespace) -> int:
    """``posegen calibrate``: identify the kinematics from recorded contacts."""
    from posegen.calibration import Settings, calibrate
    from posegen.calibration_report import format_table, write_calibration
    from posegen.config import load_config
    from posegen.scene import Scene

    scene = Scene(load_config(args.config))
    rejected: list[str] = []
    train = _measurement_args(args.measurements, scene, rejected)
    held_out = _measurement_args(args.validate, scene, rejected) if args.validate else None
    sessions = list(dict.fromkeys(train.sessions + (held_out.sessions if held_out else ())))
    settings = Settings(kappa=args.prior_scale, drop_outliers=not args.keep_outliers, seed=args.seed)
    steps = 3 + (1 if args.prior_scale else 2 * len(settings.kappas))
    with _progress_bar(steps, "step", args.quiet) as bar:

        def progress(step: str) -> None:
            bar.set_description(step, refresh=False)
            bar.update(1)

        calibration = calibrate(scene, train, sessions, settings, progress)
    report = write_calibration(calibration, held_out, Path(args.output), args.seed, rejected)
    base = report["base_parameters"]
    print(
        f"calibrate: {len(train)} training contacts, {base['total']} base parameters "
        f"(robot per chain: {base['robot_parameters_per_chain']}), prior x{report['weights']['prior_length_mm']:g}"
    )
    for message in rejected:
        print(f"  row left out: {message}")
    for outlier in report["outliers"]:
        print(f"  outlier left out: {outlier['contact']} (normalised CV residual {outlier['normalised_cv_residual']})")
    print(format_table(report))
    print(f"-> {args.output}/ (calibration.yaml, calibrated.urdf, calibrated.yaml, parameters.png, residuals.png)")
    return 0


def run_select(args: argparse.Namespace) -> int:
    """``posegen select``: IROC (and DETMAX, exact k) selection from a pool."""
    import time

    from posegen.artefact import write_yaml
    from posegen.config import load_config, parse_config
    from posegen.design import build_design
    from posegen.pool import load_pool
    from posegen.scene import Scene
    from posegen.selection import detmax_runs, iroc, select_k
    from posegen.selection_report import plot_detmax, plot_o1, selection_to_dict
    from posegen.subset_selection import Subset

    pool = load_pool(args.pool)
    config = load_config(args.config) if args.config else parse_config(pool.provenance.get("config"), "")
    scene = Scene(config)
    timings: dict[str, float] = {}
    with _progress_bar(4 + args.runs, "step", args.quiet) as bar:

        def step(name: str) -> None:
            bar.set_description(name, refresh=False)
            bar.update(1)

        start = time.perf_counter()
        step("information matrices")
        design, _ = build_design(scene, pool.joints(), [p.chain for p in pool.postures])
        timings["design"] = time.perf_counter() - start
        start = time.perf_counter()
        step("IROC weights")
        result = iroc(design, fractions=tuple(args.fraction))
        timings["iroc"] = time.perf_counter() - start
        k = args.k if args.k else len(result.selected.rows)
        start = time.perf_counter()
        runs: list[Subset] = []
        for r in range(args.runs):
            step(f"DETMAX run {r + 1}")
            runs.extend(detmax_runs(design, k, 1, args.seed * 1000 + r))
        timings["detmax"] = time.perf_counter() - start
        start = time.perf_counter()
        step("exact design" if args.k else "write")
        chosen = select_k(design, k, result.ranking, tuple(runs)) if args.k else result.selected
        timings["k_selection"] = time.perf_counter() - start
    data = selection_to_dict(
        pool, args.pool, design, result, chosen, "k" if args.k else "iroc", tuple(runs), timings, args.seed
    )
    output = Path(args.output)
    write_yaml(output, data)
    plot_o1(result, output.with_name(output.stem + "_o1.png"))
    if runs:
        iroc_k = (
            result.selected
            if not args.k
            else type(result.selected)(
                tuple(result.ranking[:k]),
                design.score(result.ranking[:k]),
                design.rank(result.ranking[:k]),
                design.o1(result.ranking[:k]),
            )
        )
        plot_detmax(iroc_k, chosen, tuple(runs), output.with_name(output.stem + "_detmax.png"))
    fig = data["figures"]
    print(
        f"select: {fig['selected']} of {design.size} postures ({data['method']}), O1 {fig['o1']:.2f} = "
        f"{100 * fig['o1_over_o1_star']:.1f}% of O1* {fig['o1_star']:.2f}; identifies {chosen.rank} of "
        f"{design.n_params} base parameters -> {output}"
    )
    cert = fig["certificate"]
    print(
        f"  weights: Kiefer-Wolfowitz gap {cert['kiefer_wolfowitz_gap']:.1e} (D-efficiency >= "
        f"{cert['d_efficiency_at_least']:.5f}); IROC stops at k = {fig['iroc']['selected_k']}; "
        + "; ".join(
            f"{100 * float(f):g}% of O1* at k = {k}" for f, k in fig["iroc"]["k_reaching_fraction_of_o1_star"].items()
        )
    )
    if runs:
        print(f"  DETMAX best of {len(runs)} (k = {k}): O1 {fig['detmax']['best_o1']:.2f}")
    if chosen.rank < design.n_params:
        print(
            f"  warning: {len(chosen.rows)} postures identify only {chosen.rank} of {design.n_params} base "
            "parameters; translation parameters are seen through heights only (one per posture): choose a larger k"
        )
    return 0
