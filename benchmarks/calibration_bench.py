"""Calibration benchmarks: the real TALOS recordings, a corrupted row, and a simulated robot (truth known).

Imported by ``benchmarks/run.py`` (``make bench``); each function prints Markdown tables.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from posegen.calibrate import (
    Calibration,
    CvResult,
    DeliverableKind,
    Perturbation,
    ScaleSearch,
    Settings,
    calibrate,
    estimate,
    simulate,
    write_calibration,
)
from posegen.calibrate.estimation import Noise, held_at_urdf
from posegen.io import Pool
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    Contacts,
    Kind,
    candidate_spec,
    read_measurements,
    start_point,
)
from posegen.parallel import ProcessBackend
from posegen.robot import CandidateConfig, Scene

ROOT = Path(__file__).resolve().parents[1]
POSEGEN = str(Path(sys.executable).with_name("posegen"))
EXHAUSTIVE_PICK = ROOT / "tests" / "calibrate" / "real_exhaustive_pick.yaml"
CORRUPTIONS = {  # as in tests/calibrate/test_screening.py: (file, line, joint, rad)
    1: [("right_train.csv", 12, "arm_right_4_joint", 0.3)],
    2: [("right_train.csv", 12, "arm_right_4_joint", 0.3), ("left_train.csv", 9, "arm_left_2_joint", -0.05)],
    3: [
        ("right_train.csv", 12, "arm_right_4_joint", -0.1),
        ("left_train.csv", 9, "arm_left_2_joint", 0.05),
        ("right_train.csv", 20, "torso_2_joint", 0.08),
    ],
}

SHOW = np.array([1e3, 180 / np.pi, 180 / np.pi])  # m, rad, rad -> mm, deg, deg
SESSIONS = ["left_train", "right_train", "left_validation"]


def _fmt(values: np.ndarray) -> str:
    return f"{values[0]:.2f} / {values[1]:.2f} / {values[2]:.2f}"


def _real(scene: Scene, data: Path) -> tuple[Contacts, Contacts]:
    train = read_measurements(data / "left_train.csv", scene).contacts.concat(
        read_measurements(data / "right_train.csv", scene).contacts
    )
    return train, read_measurements(data / "left_validation.csv", scene).contacts


def _cli_seconds(data: Path, out: Path, runs: int = 3) -> list[float]:
    """Wall time of the whole ``posegen calibrate`` command on the two training sets (every default candidate)."""
    times = []
    for k in range(runs):
        start = time.perf_counter()
        subprocess.run(
            [
                POSEGEN,
                "calibrate",
                str(data / "left_train.csv"),
                str(data / "right_train.csv"),
                "-q",
                "-o",
                str(out / f"cli{k}"),
            ],
            check=True,
            capture_output=True,
        )
        times.append(time.perf_counter() - start)
    return times


def bench_real(scene: Scene, data: Path, machine: str, workdir: Path) -> None:
    """The whole ``calibrate`` on the real data: timing, model selection, each deliverable alone, exhaustive pick."""
    train, held_out = _real(scene, data)
    times = _cli_seconds(data, workdir)
    print(f"\n### calibration: real TALOS data, two chains ({machine})\n")
    print(
        f"whole `posegen calibrate` (2 workers), wall: median {np.median(times):.1f} s "
        f"(runs {', '.join(f'{t:.1f}' for t in times)} s; target 20 s)\n"
    )
    with ProcessBackend(2) as backend:
        cal = calibrate(scene, train, SESSIONS, Settings(), backend=backend)
        exhaustive = calibrate(scene, train, SESSIONS, Settings(search=ScaleSearch.EXHAUSTIVE), backend=backend)
    record_pick(exhaustive, EXHAUSTIVE_PICK)
    same = pick_of(cal) == pick_of(exhaustive)
    print(
        f"valley search: {sum(r.plausible for r in cal.selection.results)} of "
        f"{sum(r.plausible for r in exhaustive.selection.results)} plausible pairs cross-validated; "
        f"same pick as the exhaustive search: {same} (recorded in {EXHAUSTIVE_PICK.name})\n"
    )
    print("| candidate (best prior scale) | free | CV score +- SE | left z mm / roll / pitch deg | right |")
    print("|---|---|---|---|---|")
    best: dict[str, CvResult] = {}
    for r in exhaustive.selection.results:
        if r.plausible and (r.candidate not in best or r.score < best[r.candidate].score):
            best[r.candidate] = r
    for r in [*sorted(best.values(), key=lambda r: r.score), exhaustive.selection.nominal]:
        left, right = (np.array(r.chains[c].mean_abs) * SHOW for c in ("left", "right"))
        score = f"{r.score:.1f} +- {r.se:.1f}"
        print(f"| {r.candidate} (x{r.prior_scale:g}) | {r.free} | {score} | {_fmt(left)} | {_fmt(right)} |")
    chosen = cal.selection.chosen
    print(
        f"\nmodel (one-SE rule): **{chosen.candidate} x{chosen.prior_scale:g}**; same pick on "
        f"{cal.selection.stability:.0%} of the seeds; rows left out: "
        f"{', '.join(f.label.rsplit(':', 1)[0] for f in cal.flags) or 'none'}\n"
    )
    out = workdir / "real"
    files = write_calibration(cal, held_out, out, 0).document["deliverables"]  # each file judged as a stack sees it
    print(
        "| file (left_validation, plane from training, as a stack loading it sees it) | model | CV-predicted left |"
        " CV-predicted right | left_validation z mm / roll / pitch deg |"
    )
    print("|---|---|---|---|---|")
    rows = [("nominal URDF", cal.selection.nominal, files["nominal_urdf"])]
    for d in cal.deliverables.all():
        name = "`calibrated.urdf`" if d.kind == DeliverableKind.URDF else "`with_compliance/` (+ compliance.yaml)"
        rows.append((name, d.result, files[d.kind.value]))
    for name, result, entry in rows:
        left, right = (np.array(result.chains[c].mean_abs) * SHOW for c in ("left", "right"))
        judged = entry["held_out"]["all"]["mean_abs"]
        label = f"{result.candidate} x{result.prior_scale:g}"
        shown = f"{judged['z_mm']:.2f} / {judged['roll_deg']:.2f} / {judged['pitch_deg']:.2f}"
        print(f"| {name} | {label} | {_fmt(left)} | {_fmt(right)} | {shown} |")


def pick_of(cal: Calibration) -> dict[str, list[object]]:
    """The choices a calibration made: the model and each deliverable, (candidate, prior scale)."""
    out: dict[str, list[object]] = {"model": [cal.selection.chosen.candidate, cal.selection.chosen.prior_scale]}
    for d in cal.deliverables.all():
        out[d.kind.value] = [d.candidate.name, d.result.prior_scale]
    return out


def record_pick(cal: Calibration, path: Path) -> None:
    """Record the exhaustive search's pick on the real data (tests compare the valley search's with it)."""
    path.write_text(
        yaml.safe_dump(
            {"note": "written by make bench (exhaustive scale search, real data)", **pick_of(cal)}, sort_keys=False
        )
    )


def bench_corrupted_rows(scene: Scene, data: Path, workdir: Path) -> None:
    """One to three corrupted rows (every default candidate): never an error, every one flagged, held-out kept.

    Held-out errors as ``calibrate`` reports them: each file (and the interpretable model) as a stack loading it
    sees it.
    """
    train, held_out = _real(scene, data)
    print("\n### corrupted rows (real data, every candidate)\n")
    print(
        "| corrupted rows | rows left out | model | left_validation z mm / roll / pitch deg (model; URDF; URDF + "
        "compensation) |"
    )
    print("|---|---|---|---|")
    with ProcessBackend(2) as backend:
        for edits in ([], *CORRUPTIONS.values()):
            joints = train.joints.copy()
            for file, line, joint, error in edits:
                row = next(i for i, label in enumerate(train.labels) if label.startswith(f"{file}:{line}:"))
                joints[row, scene.joint_index(joint)] += error
            cal = calibrate(scene, train.at(joints), SESSIONS, Settings(), backend=backend)
            out = Path(tempfile.mkdtemp(dir=workdir))
            report = write_calibration(cal, held_out, out, 0).document
            figures = [report["model"]["held_out"]["all"]["mean_abs"]] + [
                report["deliverables"][d.kind.value]["held_out"]["all"]["mean_abs"] for d in cal.deliverables.all()
            ]
            shown = "; ".join(f"{f['z_mm']:.2f} / {f['roll_deg']:.2f} / {f['pitch_deg']:.2f}" for f in figures)
            flags = ", ".join(f.label.rsplit(":", 1)[0] for f in cal.flags)
            name = "clean" if not edits else "; ".join(f"{f}:{n} {j} {e:+g} rad" for f, n, j, e in edits)
            print(
                f"| {name} | {flags} | {cal.selection.chosen.candidate} x{cal.selection.chosen.prior_scale:g} | "
                f"{shown} |"
            )


def bench_recovery(scene: Scene, pool: Pool) -> None:
    """A simulated compliant robot (every placement perturbed): held-out error with and without floor and compliance."""
    rows = list(range(200))
    chains = tuple(pool.postures[i].chain for i in rows)
    plan = Contacts(pool.joints()[rows], chains, ("sim",) * 200, tuple(f"sim:{i}:c{i}" for i in rows))
    truth_compliance = 3e-4
    perturbation = Perturbation(encoder_noise_rad=np.deg2rad(0.005), compliance_rad_per_nm=truth_compliance)
    recorded, model, _ = simulate(scene, plan, perturbation, seed=3)
    train, test = recorded.subset(range(100)), recorded.subset(range(100, len(recorded)))
    print(
        "\n### simulated recovery (truth known: 2 mm / 0.5 deg on every placement, hip pitch compliance "
        f"{truth_compliance * 1e3:g} rad/kN m, encoder noise 0.005 deg; 100 training, {len(test)} held-out contacts)\n"
    )
    print(
        "| model (prior x10) | floor equations | held-out z mm / roll / pitch deg | hip pitch compliance (rad/kN m) |"
    )
    print("|---|---|---|---|")
    observations = model.observations(train)
    test_obs = model.observations(test)
    hip = [i for i, d in enumerate(model.directions) if d.kind == Kind.COMPLIANCE and d.owner == "hip_pitch"]
    for fit in (("*.*",), ("*.joint_offset", "leg.*")):
        for compliance in ((), ("hip_pitch",)):
            for floor in (False, True):
                candidate = CandidateConfig("c", fit, floor, compliance)
                spec = candidate_spec(model, candidate, scene.calibration.prior, 10.0)
                start = held_at_urdf(model, spec, start_point(model, observations))
                est = estimate(model, observations, spec, Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE), start)
                error = np.mean(np.abs(model.evaluate(est.x, test_obs, floor=False).contact), axis=0) * SHOW
                value = f"{est.x[hip[0]] * 1e3:.3f}" if compliance else "-"
                name = ("full" if fit == ("*.*",) else "offsets + legs") + (" + hip pitch" if compliance else "")
                print(f"| {name} | {'yes' if floor else 'no'} | {_fmt(error)} | {value} |")
