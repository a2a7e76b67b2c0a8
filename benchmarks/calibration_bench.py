"""Calibration benchmarks: the real TALOS recordings, a corrupted row, and a simulated robot (truth known).

Imported by ``benchmarks/run.py`` (``make bench``); each function prints Markdown tables.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from posegen.calibrate import CvResult, Perturbation, Settings, calibrate, estimate, held_out_residuals, simulate
from posegen.calibrate.calibration import FLOOR_NOISE
from posegen.calibrate.estimation import Noise, held_at_urdf
from posegen.model import DEFAULT_NOISE, Contacts, Kind, candidate_spec, read_measurements, start_point
from posegen.robot import CandidateConfig, Pool, Scene

SHOW = np.array([1e3, 180 / np.pi, 180 / np.pi])  # m, rad, rad -> mm, deg, deg
SESSIONS = ["left_train", "right_train", "left_validation"]


def _fmt(values: np.ndarray) -> str:
    return f"{values[0]:.2f} / {values[1]:.2f} / {values[2]:.2f}"


def _real(scene: Scene, data: Path) -> tuple[Contacts, Contacts]:
    train = read_measurements(data / "left_train.csv", scene).contacts.concat(
        read_measurements(data / "right_train.csv", scene).contacts
    )
    return train, read_measurements(data / "left_validation.csv", scene).contacts


def bench_real(scene: Scene, data: Path, machine: str) -> tuple[str, float]:
    """The whole ``calibrate`` on the real data: model selection, predicted error, held-out figures."""
    train, held_out = _real(scene, data)
    start = time.perf_counter()
    cal = calibrate(scene, train, SESSIONS)
    total = time.perf_counter() - start
    selection = cal.selection
    print(f"\n### calibration: real TALOS data, two chains ({machine})\n")
    print(f"whole `posegen calibrate` (screening, {len(selection.results)} CV pairs, final fit): {total:.0f} s\n")
    print("| candidate (best prior scale) | free | CV score +- SE | left z mm / roll / pitch deg | right |")
    print("|---|---|---|---|---|")
    best: dict[str, CvResult] = {}
    for r in selection.results:
        if r.plausible and (r.candidate not in best or r.score < best[r.candidate].score):
            best[r.candidate] = r
    for r in sorted(best.values(), key=lambda r: r.score):
        left, right = (np.array(r.chains[c].mean_abs) * SHOW for c in ("left", "right"))
        score = f"{r.score:.1f} +- {r.se:.1f}"
        print(f"| {r.candidate} (x{r.prior_scale:g}) | {r.free} | {score} | {_fmt(left)} | {_fmt(right)} |")
    chosen = selection.chosen
    picks = ", ".join(f"{c} x{s:g}" for c, s in selection.seed_picks)
    print(
        f"\nchosen: **{chosen.candidate} x{chosen.prior_scale:g}** (best {selection.best.candidate} "
        f"x{selection.best.prior_scale:g}); same pick on {selection.stability:.0%} of the seeds ({picks}); "
        f"{sum(not r.plausible for r in selection.results)} implausible pairs left out"
    )
    for flag in cal.flags:
        print(f"- left out: {flag.label} ({flag.reason}, {flag.value:.2f})")
    compliance = {
        g: round(v * 1e3, 3) for g, v in cal.model.compliances(cal.after.x).items() if g in cal.candidate.compliance
    }
    print(f"- compliance (rad/kN m): {compliance}; noise {_fmt(np.array(cal.after.noise.contact) * SHOW)}")
    res = held_out_residuals(cal, held_out)
    print("\n| left_validation (9 contacts), mean abs z mm / roll / pitch deg | before (URDF) | after |")
    print("|---|---|---|")
    for protocol in ("training_plane", "refitted_plane"):
        b = np.mean(np.abs(res[protocol]["before"]), axis=0) * SHOW
        a = np.mean(np.abs(res[protocol]["after"]), axis=0) * SHOW
        print(f"| {protocol.replace('_', ' ')} | {_fmt(b)} | {_fmt(a)} |")
    return chosen.candidate, chosen.prior_scale


def bench_corrupted_row(scene: Scene, data: Path, candidate: str) -> None:
    """One arm joint of one training row off by 0.3 rad: flagged, and the held-out error hardly moves."""
    train, held_out = _real(scene, data)
    joints = train.joints.copy()
    row = 5
    joints[row, scene.joint_index(f"arm_{train.chains[row]}_4_joint")] += 0.3
    bad = Contacts(joints, train.chains, train.sessions, train.labels)
    settings = Settings(candidates=(candidate,))
    where = f"candidate {candidate}; arm joint 4 of row {train.labels[row]} + 0.3 rad"
    print(f"\n### one corrupted row (real data, {where})\n")
    print("| training set | rows left out | CV-predicted left / right z (mm) | left_validation z mm / roll / pitch |")
    print("|---|---|---|---|")
    for name, data_ in (("clean", train), ("corrupted", bad)):
        cal = calibrate(scene, data_, SESSIONS, settings)
        chains = cal.selection.chosen.chains
        after = np.mean(np.abs(held_out_residuals(cal, held_out)["training_plane"]["after"]), axis=0) * SHOW
        left_out = ", ".join(f.label.split(":", 2)[1] for f in cal.flags) or "none"
        predicted = f"{chains['left'].mean_abs[0] * 1e3:.2f} / {chains['right'].mean_abs[0] * 1e3:.2f}"
        print(f"| {name} | lines {left_out} | {predicted} | {_fmt(after)} |")


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
                est = estimate(model, observations, spec, Noise(DEFAULT_NOISE, FLOOR_NOISE), start)
                error = np.mean(np.abs(model.evaluate(est.x, test_obs, floor=False).contact), axis=0) * SHOW
                value = f"{est.x[hip[0]] * 1e3:.3f}" if compliance else "-"
                name = ("full" if fit == ("*.*",) else "offsets + legs") + (" + hip pitch" if compliance else "")
                print(f"| {name} | {'yes' if floor else 'no'} | {_fmt(error)} | {value} |")
