"""Rehearsals on every shipped robot and on drafts: what ``simulate`` keeps (``make bench``, stage ``simulation``).

Per robot: a pool (``posegen pool --n N``), then the perturbed robot of ``simulate``
(default errors 2 mm / 0.5 deg, and TALOS with 3 mm) settles every posture at three
seeds; the table gives the postures kept per seed, and why any was left out.
"""

from __future__ import annotations

import logging
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
POSEGEN = str(Path(sys.executable).with_name("posegen"))
SHIPPED = ("talos", "talos_full", "romeo", "icub", "human", "jvrc")
DRAFTS = {"human (draft)": "human", "JVRC-1 (draft)": "package://jvrc_description/urdf/jvrc1.urdf"}
SEEDS = (7, 8, 9)


def _posegen(*argv: str) -> None:
    subprocess.run([POSEGEN, *argv], check=True, cwd=ROOT, capture_output=True, text=True)


def robot_pools(workdir: Path, n: int) -> list[tuple[str, Path, Path]]:
    """(name, config, pool) of every shipped robot and of each draft; pools made once (``--seed 1``)."""
    workdir.mkdir(parents=True, exist_ok=True)
    robots = [(name, ROOT / "configs" / f"{name}_table.yaml") for name in SHIPPED]
    for name, source in DRAFTS.items():
        config = workdir / f"draft_{source.rsplit('/', 1)[-1].split('.')[0]}.yaml"
        if not config.exists():
            _posegen("robot", "init", source, "-q", "-o", str(config))
        robots.append((name, config))
    out = []
    for name, config in robots:
        pool = workdir / f"{config.stem}_pool.yaml"
        if not pool.exists():
            _posegen(
                "pool", "--config", str(config), "--n", str(n), "--seed", "1", "--workers", "2", "-q", "-o", str(pool)
            )
        out.append((name, config, pool))
    return out


def kept(config: Path, pool_path: Path, length_m: float, seed: int) -> tuple[int, int, list[str]]:
    """Postures ``simulate`` keeps of a pool (one seed), how many were planned, and why any was left out."""
    from posegen.calibrate import Perturbation, simulate
    from posegen.io import load_pool
    from posegen.model import Contacts, planned_kinds
    from posegen.robot import Scene, load_config

    scene = Scene(load_config(config))
    pool = load_pool(pool_path)
    chains = tuple(p.chain for p in pool.postures)
    n = len(chains)
    plan = Contacts(
        pool.joints(), chains, ("s",) * n, tuple(p.spot for p in pool.postures), planned_kinds(scene, chains)
    )
    reasons: list[str] = []

    class Reasons(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            reasons.append(record.getMessage().split(" left out: ", 1)[-1])

    handler = Reasons(logging.WARNING)
    logging.getLogger("posegen.calibrate.simulation").addHandler(handler)
    try:
        recorded, _, _ = simulate(scene, plan, Perturbation(length_m=length_m), seed)
    finally:
        logging.getLogger("posegen.calibrate.simulation").removeHandler(handler)
    return len(recorded), n, reasons


def bench_kept(workdir: Path, machine: str, n: int = 100) -> None:
    """Postures kept by ``simulate`` on every shipped robot and on drafts; one Markdown table."""
    start = time.perf_counter()
    cases = [(name, config, pool, 2e-3) for name, config, pool in robot_pools(workdir, n)]
    talos = next(c for c in cases if c[0] == "talos")
    cases.insert(1, ("talos, 3 mm errors", talos[1], talos[2], 3e-3))
    print(f"\n### simulated postures kept ({machine}; seeds {', '.join(map(str, SEEDS))})\n")
    print("| robot | errors | postures | kept per seed | kept | left out, why |")
    print("|---|---|---|---|---|---|")
    for name, config, pool, length in cases:
        runs = [kept(config, pool, length, seed) for seed in SEEDS]
        planned = runs[0][1]
        share = 100.0 * sum(k for k, _, _ in runs) / (planned * len(runs))
        why = "; ".join(sorted({r for _, _, reasons in runs for r in reasons})) or "-"
        counts = ", ".join(str(k) for k, _, _ in runs)
        print(f"| {name} | {length * 1e3:g} mm / 0.5 deg | {planned} | {counts} | {share:.1f} % | {why} |")
    print(f"\n({time.perf_counter() - start:.0f} s)")
