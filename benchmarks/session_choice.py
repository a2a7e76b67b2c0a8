"""The session's choice alone: its batches against the fixed exact-k IROC design and the IROC order, at rest.

``benchmarks/session_bench.py`` rehearses whole sessions (routes, bags, measure); this
script isolates what the session *chooses*. Per robot seed, every posture is simulated at
rest on the same robot (``session_bench.robot_contacts``: every placement off, compliant
hips, contact noise as the real data's), and after each batch the calibration (the same
settings for every order) is judged on the same held-out postures without contact noise:

* the session's choice: the first batch is the exact-k design of (1 + margin) x the fewest
  postures, grown until it identifies every base parameter (as ``session start``; with
  ``--no-grow`` it is not grown), then ``batch`` postures at a time chosen by
  ``posegen.select.follow_up`` for the weakest chain of the URDF deliverable's CV, with the
  calibration's model, prior scale and contact noise (as ``session add``);
* the IROC ranking order's prefix with as many contacts;
* the fixed exact-k IROC design (``select --k``, 60 by default).

Run from the repository (``PYTHONPATH`` picks the posegen it measures, so two commits can be
compared with one script)::

    PYTHONPATH=. .venv/bin/python benchmarks/session_choice.py plans/talos/pool.yaml --seeds 10 -o choice.json
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from session_bench import TABLE, Split, both_errors, split_pool  # beside this script

from posegen.calibrate import Settings, calibrate
from posegen.select import follow_up, select_k
from posegen.session import Robot

CANDIDATES = ("offsets", "offsets_hip_pitch")


def first_rows(split: Split, margin: float, grow: bool) -> list[int]:
    """The first batch's design-pool rows: exact k, grown (10 % at a time) until every base parameter is identified."""
    design = split.design
    k = math.ceil(design.fewest(split.ranking) * (1.0 + margin))
    while True:
        rows = list(select_k(design, k, split.ranking).rows)
        if not grow or design.rank(rows) >= design.n_params or k >= design.size:
            return rows
        k = min(design.size, k + max(1, k // 10))


def greedy_full_rank(split: Split) -> int:
    """Postures a greedy search needs to identify every base parameter (each step: the most new rank, then the score).

    The fewest count (rows >= base parameters) assumes every posture adds 3 independent rows;
    this measures how many the pool's postures actually need.
    """
    design = split.design
    rows: list[int] = []
    while design.rank(rows) < design.n_params and len(rows) < design.size:
        left = [j for j in range(design.size) if j not in rows]
        rows.append(max(left, key=lambda j: (design.rank([*rows, j]), design.score([*rows, j]))))
    return len(rows)


def run_seed(split: Split, seed: int, first: list[int], batches: int, batch: int, settings: Settings) -> dict:
    """One robot: the session's choice batch by batch, the IROC order at the same counts, the fixed design."""
    robot = Robot(seed=seed, compliance_rad_per_knm=0.3)
    held = split.contacts(split.held_rows, replace(robot, contact_noise_mm=0.0, contact_noise_deg=0.0))
    design_joints = split.joints[split.design_rows]
    design_chains = [split.chains[i] for i in split.design_rows]
    planned, counts, session, ranked = list(first), [], [], []
    for number in range(batches + 1):
        contacts = split.contacts([split.design_rows[i] for i in planned], robot)
        calibration = calibrate(split.scene, contacts, [TABLE], settings)
        counts.append(len(contacts))
        session.append(both_errors(calibration, held))
        prefix = split.contacts([split.design_rows[i] for i in split.ranking[: len(contacts)]], robot)
        ranked.append(both_errors(calibrate(split.scene, prefix, [TABLE], settings), held))
        if number == batches:
            break
        predicted = {c: e.mean_abs[0] for c, e in calibration.deliverables.urdf.result.chains.items()}
        weakest = max(sorted(predicted), key=lambda c: predicted[c])
        chosen = follow_up(
            split.scene,
            design_joints,
            design_chains,
            contacts,
            calibration.candidate,
            calibration.selection.chosen.prior_scale,
            calibration.after.noise.contact,
            batch,
            weakest,
            planned,
        )
        planned.extend(chosen.rows)
    fixed = split.contacts([split.design_rows[i] for i in split.fixed], robot)
    fixed_error = both_errors(calibrate(split.scene, fixed, [TABLE], settings), held)
    return {"seed": seed, "counts": counts, "session": session, "iroc": ranked, "fixed": fixed_error}


def report(results: list[dict]) -> str:
    """Medians over seeds (mm) per batch, and the session's paired difference to the fixed design and the IROC order."""
    lines = []
    for deliverable in ("urdf", "compensated"):
        fixed = [r["fixed"][deliverable] for r in results]
        lines += [
            f"\n{deliverable}: the fixed design {statistics.median(fixed):.2f} mm (median)\n",
            "| contacts (median) | session | IROC order | session - fixed (paired median) | session < IROC order |",
            "|---|---|---|---|---|",
        ]
        for i in range(min(len(r["counts"]) for r in results)):
            session = [r["session"][i][deliverable] for r in results]
            ranked = [r["iroc"][i][deliverable] for r in results]
            count = statistics.median(r["counts"][i] for r in results)
            paired = statistics.median(s - f for s, f in zip(session, fixed, strict=True))
            below = sum(s < o for s, o in zip(session, ranked, strict=True))
            lines.append(
                f"| {count:g} | {statistics.median(session):.2f} | {statistics.median(ranked):.2f} "
                f"| {paired:+.2f} | {below} of {len(results)} |"
            )
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    """Parse the options, run every seed, print the tables, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pool")
    parser.add_argument("--seeds", type=int, default=10, help="robot seeds 1..N")
    parser.add_argument("--batches", type=int, default=6, help="follow-up batches after the first")
    parser.add_argument("--batch", type=int, default=10, help="postures per follow-up batch")
    parser.add_argument("--margin", type=float, default=0.2, help="of the first batch")
    parser.add_argument("--no-grow", action="store_true", help="do not grow the first batch to full rank")
    parser.add_argument("--held-out", type=int, default=40)
    parser.add_argument("-o", "--output", type=Path, required=True, help="JSON of the per-seed figures")
    args = parser.parse_args(argv)
    settings = Settings(candidates=CANDIDATES, fold_seeds=1, seed=0)
    with tempfile.TemporaryDirectory() as scratch:
        split, _ = split_pool(Path(args.pool), Path(scratch), args.held_out)
    first = first_rows(split, args.margin, not args.no_grow)
    results = []
    for seed in range(1, args.seeds + 1):
        results.append(run_seed(split, seed, first, args.batches, args.batch, settings))
        print(f"seed {seed}: contacts {results[-1]['counts']}", file=sys.stderr, flush=True)
    options = {**vars(args), "output": str(args.output)}
    args.output.write_text(json.dumps({"first_postures": len(first), "options": options, "results": results}, indent=1))
    print(
        f"first batch: {len(first)} postures (rank {split.design.rank(first)} of {split.design.n_params}); "
        f"fewest by rows {split.design.fewest(split.ranking)}, by a greedy full-rank search {greedy_full_rank(split)}"
    )
    print(report(results))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
