"""Physics rehearsal benchmark (issue 31, items 4 and 5): ``posegen simulate ROUTE --physics --bag``.

For each robot: a pool, a selection of K postures, its route, then the route rehearsed in
MuJoCo by the perturbed robot standing free (and, for TALOS, glued to the floor), each bag
measured back. Prints one Markdown table: wall time and robot time of the run, whether it
completed, the holds whose normal force stayed within [10, 60] N, the worst ZMP margin,
sole slip, pelvis deviation from the plan and torque over effort, the unwanted contacts,
and the contacts ``posegen measure`` finds in the bag.

    python benchmarks/physics_run.py [--only talos icub jvrc] [--error-mm 2 --error-deg 0.5] [--workdir DIR]

Run from the repository root with the venv's ``posegen`` (2 cores: ``OPENBLAS_NUM_THREADS=1``).
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

from run import machine  # benchmarks/run.py, beside this file

ROOT = Path(__file__).resolve().parents[1]
POSEGEN = [sys.executable, "-m", "posegen.cli"]


@dataclass(frozen=True)
class Case:
    """A robot and its experiment: pool size and seed, selected postures, the contacts routed."""

    name: str
    config: str
    pool: int
    seed: int
    k: int  # 0: the fewest select accepts
    contacts: int  # the selection's first (by rank) routed; 0: all


CASES = {
    "talos": Case("talos", "configs/talos_table.yaml", 300, 5, 41, 0),
    "icub": Case("icub", "configs/icub_table.yaml", 200, 5, 0, 10),
    "jvrc": Case("jvrc", "configs/jvrc_table.yaml", 200, 5, 0, 10),
    "human": Case("human", "configs/human_table.yaml", 200, 5, 0, 10),
}


def posegen(*args: str) -> tuple[float, subprocess.CompletedProcess[str]]:
    start = time.perf_counter()
    done = subprocess.run([*POSEGEN, *args], cwd=ROOT, capture_output=True, text=True)
    return time.perf_counter() - start, done


def _run(case: Case, *argv: str) -> subprocess.CompletedProcess[str]:
    _, done = posegen(*argv)
    if done.returncode != 0:
        raise SystemExit(f"{case.name}: posegen {argv[0]} failed: {done.stderr.strip()}")
    return done


def _select(case: Case, folder: Path) -> Path:
    """The selection of K postures (or of the fewest the robot's model accepts)."""
    selected = folder / "selected.yaml"
    k = case.k
    if not k:
        _, done = posegen("select", str(folder / "pool.yaml"), "--k", "1", "-q", "-o", str(selected))
        found = re.search(r"choose between (\d+)", done.stderr)
        k = int(found.group(1)) if found else 1
    _run(case, "select", str(folder / "pool.yaml"), "--k", str(k), "-q", "-o", str(selected))
    return selected


def _first(case: Case, folder: Path, selected: Path) -> Path:
    """A pool file of the selection's first ``case.contacts`` postures by rank."""
    import yaml

    from posegen.io import load_pool, write_yaml

    ranked = sorted(yaml.safe_load(selected.read_text())["postures"], key=lambda p: p["rank"])
    ids = {p["pool_id"] for p in ranked[: case.contacts]}
    data = load_pool(folder / "pool.yaml").to_dict()
    data["postures"] = [p for p in data["postures"] if p["id"] in ids]
    out = folder / "first.yaml"
    write_yaml(out, data)
    return out


def config(case: Case, folder: Path) -> str:
    """The case's config; where a chain names no wrist force/torque topic, a copy naming ``/<chain>_wrist_ft``.

    A recording (``simulate --bag``, ``--physics``) has one wrench topic per wrist; the iCub
    and drafted configs name none (their robots' sensors are not known): the copy adds them.
    """
    import yaml

    data = yaml.safe_load((ROOT / case.config).read_text())
    missing = [name for name, chain in data["chains"].items() if not chain.get("wrench_topic")]
    if not missing:
        return case.config
    for name in missing:
        data["chains"][name]["wrench_topic"] = f"/{name}_wrist_ft"
    out = folder / "config.yaml"
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return str(out)


def plan(case: Case, folder: Path) -> Path:
    """Pool, selection and route of a case (made once per work folder)."""
    route = folder / "route.yaml"
    if route.is_file():
        return route
    pool = ["--config", config(case, folder), "--n", str(case.pool), "--seed", str(case.seed), "-q"]
    _run(case, "pool", *pool, "-o", str(folder / "pool.yaml"))
    postures = _select(case, folder)
    if case.contacts:
        postures = _first(case, folder, postures)
    _run(case, "route", str(postures), "-q", "-o", str(route))
    return route


def rehearse(case: Case, route: Path, folder: Path, errors: list[str], glued: bool) -> str:
    """One run and its measurement, as a table row."""
    from posegen.physics import read_physics

    bag = folder / ("bag_glued" if glued else "bag")
    subprocess.run(["rm", "-rf", str(bag)], check=True)
    argv = ["simulate", str(route), "--physics", "--bag", str(bag), "--seed", "7", *errors, "-q"]
    wall, done = posegen(*argv, *(["--glued-feet"] if glued else []))
    if not (bag / "physics.yaml").is_file():
        return f"| {case.name}{' (glued)' if glued else ''} | failed: {done.stderr.strip()} |" + " |" * 9
    s = read_physics(bag / "physics.yaml").summary
    _, measured = posegen(
        "measure", str(bag), "--route", str(route), "--config", config(case, folder), "-o", str(folder / "m.yaml")
    )
    found = measured.stdout.split(":", 1)[1].split("contact")[0].strip() if measured.returncode == 0 else "0"
    state = "yes" if s.completed else f"fell at {s.fell_at_s:.1f} s"
    return (
        f"| {case.name}{' (glued)' if glued else ''} | {wall:.1f} | {s.duration_s:.1f} | {state} | "
        f"{s.holds_in_range}/{s.contacts} | {1e3 * s.zmp_margin_min_m:.1f} | {s.slip_max_mm:.2f} | "
        f"{1e3 * s.pelvis_deviation_max_m:.1f} | {s.torque_ratio_max:.2f} ({s.torque_joint}) | "
        f"{s.unwanted_contacts} | {found}/{s.contacts} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=["talos", "icub", "jvrc"], choices=sorted(CASES))
    parser.add_argument("--error-mm", default=None, help="placement length errors (default: simulate's)")
    parser.add_argument("--error-deg", default=None, help="placement angle errors (default: simulate's)")
    parser.add_argument("--workdir", default=None, help="keep the pools, routes and bags here")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))  # the in-process reads use this checkout's posegen, as the runs (cwd ROOT) do
    errors = [
        *(["--error-mm", args.error_mm] if args.error_mm else []),
        *(["--error-deg", args.error_deg] if args.error_deg else []),
    ]
    work = Path(args.workdir) if args.workdir else Path(tempfile.mkdtemp(prefix="physics_bench_"))
    before = os.getloadavg()[0]
    rows = []
    for name in args.only:
        case = CASES[name]
        folder = work / name
        folder.mkdir(parents=True, exist_ok=True)
        route = plan(case, folder)
        rows.append(rehearse(case, route, folder, errors, glued=False))
        if name == "talos":
            rows.append(rehearse(case, route, folder, errors, glued=True))
    label = " ".join(errors) or "simulate's default errors (2 mm, 0.5 deg)"
    print(f"\n### physics rehearsal ({machine()}; load {before:.1f} -> {os.getloadavg()[0]:.1f}; {label})\n")
    print(
        "| robot | wall (s) | robot time (s) | completed | holds in [10, 60] N | ZMP margin min (mm) | "
        "sole slip max (mm) | pelvis vs plan max (mm) | torque / effort max | unwanted contacts | measure finds |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        print(row)


if __name__ == "__main__":
    main()
