"""Route benchmark (``make bench``, stage ``route``): issue 10's figures.

For pools of 300 TALOS postures from seeds 5 and 11 and selections of 41 and 60 postures:
postures routed (and substituted), robot time per contact (median and mean) and in total,
``posegen route`` wall time on 2 workers, ``posegen check`` wall time, file size and load
time; then the same check, size and load time for a route of 10 000 points or more
(a selection of ``LONG_K`` postures).
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable
from pathlib import Path

SEEDS = (5, 11)
SIZES = (41, 60)
POOL = 300
LONG_K = 90  # postures of the long route (>= 10 000 points)
WORKERS = 2


def _run(posegen: str, root: Path, *args: str) -> tuple[float, subprocess.CompletedProcess[str]]:
    start = time.perf_counter()
    done = subprocess.run([posegen, *args], cwd=root, capture_output=True, text=True)
    return time.perf_counter() - start, done


def _route_row(posegen: str, root: Path, selection: Path, out: Path, label: str) -> tuple[str, dict[str, float]]:
    from posegen.io import read_route, sidecars_of

    wall, done = _run(posegen, root, "route", str(selection), "--workers", str(WORKERS), "-q", "-o", str(out))
    if done.returncode != 0:
        return f"| {label} | route failed: {done.stderr.strip()} |||||||", {}
    start = time.perf_counter()
    route = read_route(out)
    load = time.perf_counter() - start
    summary = route.summary or {}
    t_check, check = _run(posegen, root, "check", str(out), "--workers", str(WORKERS), "-q")
    verdict = "ok" if check.returncode == 0 else "VIOLATIONS"
    size = (out.stat().st_size + sum(p.stat().st_size for p in sidecars_of(out))) / 1e6
    swaps = "; ".join(
        f"{s['pool_id']} -> {s['substitute_pool_id']} (O1 {s['o1_before']:.2f} -> {s['o1_after']:.2f})"
        for s in route.substitutions
    )
    routed = f"{summary['routed']}/{summary['postures']}"
    if swaps:
        routed += f" ({swaps})"
    if summary["skipped"]:
        routed += f", {summary['skipped']} skipped"
    row = (
        f"| {label} | {routed} | "
        f"{summary['robot_time_per_contact_median_s']:.2f} / {summary['robot_time_per_contact_s']:.2f} s | "
        f"{summary['duration_s']:.0f} s | {wall:.1f} s | {summary['points']} | {t_check:.1f} s ({verdict}) | "
        f"{size:.2f} MB, {1000 * load:.0f} ms |"
    )
    figures = {"points": summary["points"], "check_s": t_check, "size_mb": size, "load_s": load}
    return row, figures


def bench_routes(posegen: str, root: Path, workdir: Path, machine: Callable[[], str]) -> None:
    """Print the route tables (Markdown)."""
    rows = []
    long_route: tuple[str, dict[str, float]] | None = None
    for seed in SEEDS:
        pool = workdir / f"pool_{seed}.yaml"
        _run(
            posegen,
            root,
            "pool",
            "--n",
            str(POOL),
            "--seed",
            str(seed),
            "--workers",
            str(WORKERS),
            "-q",
            "-o",
            str(pool),
        )
        for k in (*SIZES, *((LONG_K,) if seed == SEEDS[0] else ())):
            selection = workdir / f"selected_{seed}_{k}.yaml"
            _run(posegen, root, "select", str(pool), "--k", str(k), "-q", "-o", str(selection))
            row = _route_row(posegen, root, selection, workdir / f"route_{seed}_{k}.yaml", f"seed {seed}, k {k}")
            if k == LONG_K:
                long_route = row
            else:
                rows.append(row[0])
    print(f"\n### route: pools of {POOL} from seeds {SEEDS}, `select --k` ({machine()})\n")
    print(
        "| pool, selection | routed / selected (substitutions) | robot time per contact, median / mean | "
        f"robot time, total | `route` wall, {WORKERS} workers | points | `check` wall, {WORKERS} workers | "
        "file (YAML + npz), load |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for row in rows:
        print(row)
    if long_route is not None:
        print(long_route[0])


def route_of(posegen: str, root: Path, pool: Path, workdir: Path, k: int) -> Path:
    """A route through ``select --k k`` of a pool (planned once per working folder), for other benchmarks."""
    route = workdir / f"route_k{k}.yaml"
    if not route.exists():
        selection = workdir / f"selected_k{k}.yaml"
        _run(posegen, root, "select", str(pool), "--k", str(k), "-q", "-o", str(selection))
        _run(posegen, root, "route", str(selection), "--workers", str(WORKERS), "-q", "-o", str(route))
    return route
