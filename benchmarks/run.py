"""posegen benchmarks (``make bench``): timings and quality figures for the README.

Run from the repository root. Each stage prints a Markdown table; ``--only`` picks stages.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import scale  # benchmarks/scale.py, beside this file

ROOT = Path(__file__).resolve().parents[1]


def real_data() -> Path:
    """The real TALOS recordings: ``$POSEGEN_REAL_DATA``, else ``shared/data/talos_real`` beside the checkout."""
    if os.environ.get("POSEGEN_REAL_DATA"):
        return Path(os.environ["POSEGEN_REAL_DATA"])
    return next(
        (p / "shared" / "data" / "talos_real" for p in ROOT.parents if (p / "shared" / "data" / "talos_real").is_dir()),
        ROOT.parent / "shared" / "data" / "talos_real",
    )


POSEGEN = str(Path(sys.executable).with_name("posegen"))


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {cpu}, Python {platform.python_version()}"


def bench_pool(workdir: Path, n: int) -> Path:
    from posegen.io import load_pool

    out = workdir / "pool.yaml"
    before = os.getloadavg()[0]
    start = time.perf_counter()
    subprocess.run(
        [POSEGEN, "pool", "--n", str(n), "--workers", "2", "-q", "-o", str(out)],
        check=True,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - start
    pool = load_pool(out)
    joints = pool.joints()
    names = pool.joint_names
    config = pool.provenance["config"]
    free = [i for i, name in enumerate(names) if name not in config["robot"]["locked_joints"]]
    spread = joints[:, free].std(axis=0)
    counts = [c for per in pool.per_spot().values() for c in per.values()]
    print(f"\n### pool: {n} postures ({machine()}; load {before:.1f} -> {os.getloadavg()[0]:.1f})\n")
    print("| figure | value |\n|---|---|")
    print(f"| wall time, `posegen pool --n {n}` (2 workers, incl. start-up) | {wall:.1f} s |")
    print(
        f"| samples attempted / accepted | {pool.attempted} / {len(pool.postures)} "
        f"({100 * len(pool.postures) / pool.attempted:.1f}%) |"
    )
    print("| rejections | " + ", ".join(f"{k} {v}" for k, v in pool.rejected.items()) + " |")
    chains = sorted({p.chain for p in pool.postures})
    print(
        "| postures per chain | " + ", ".join(f"{c} {sum(p.chain == c for p in pool.postures)}" for c in chains) + " |"
    )
    print(
        f"| postures per (spot, chain) | min {min(counts)}, median {int(np.median(counts))}, max {max(counts)} "
        f"over {len(counts)} pairs |"
    )
    print(
        f"| per-joint std of the free joints | min {spread.min():.3f}, median {np.median(spread):.3f}, "
        f"max {spread.max():.3f} rad |"
    )
    print(
        f"| min collision distance (hulls) | min {min(p.min_distance_m for p in pool.postures) * 1000:.1f} mm, "
        f"median {np.median([p.min_distance_m for p in pool.postures]) * 1000:.1f} mm |"
    )
    start = time.perf_counter()
    subprocess.run([POSEGEN, "check", str(out), "-q"], check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    print(f"| `posegen check` on meshes | {time.perf_counter() - start:.1f} s, no violation |")
    return out


def bench_select(pool_path: Path, workdir: Path) -> None:
    from posegen.io import load_pool
    from posegen.robot import Scene, parse_config
    from posegen.select import build_design, detmax_runs, iroc, select_k

    start = time.perf_counter()
    subprocess.run(
        [POSEGEN, "select", str(pool_path), "-q", "-o", str(workdir / "selected.yaml")],
        check=True,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
    )
    total = time.perf_counter() - start
    pool = load_pool(pool_path)
    scene = Scene(parse_config(pool.provenance["config"]))
    start = time.perf_counter()
    design, _ = build_design(scene, pool.joints(), [p.chain for p in pool.postures])
    t_design = time.perf_counter() - start
    start = time.perf_counter()
    result = iroc(design)
    t_iroc = time.perf_counter() - start
    print(f"\n### select: {design.size}-posture pool, {design.n_params} base parameters ({machine()})\n")
    print("| figure | value |\n|---|---|")
    print(f"| total `posegen select` (IROC, incl. start-up and pool loading) | {total:.1f} s |")
    print(f"| information matrices | {t_design:.2f} s |")
    print(
        f"| IROC weights + O1 curve | {t_iroc:.2f} s, gap {result.weights.gap:.1e}, {result.weights.iterations} steps |"
    )
    print(
        f"| IROC selection | k = {len(result.selected.rows)}, O1 {result.selected.o1:.2f} "
        f"({100 * result.selected.o1 / result.o1_star:.1f}% of O1* {result.o1_star:.2f}) |"
    )
    print(f"| smallest k reaching 90% / 95% of O1* | {result.fractions[0.9]} / {result.fractions[0.95]} |")
    for k in (41, 60):
        start = time.perf_counter()
        runs = detmax_runs(design, k, 10, 0)
        t_detmax = time.perf_counter() - start
        start = time.perf_counter()
        chosen = select_k(design, k, result.ranking, runs)
        t_k = time.perf_counter() - start
        best = max(runs, key=lambda r: r.score)
        top = design.o1(result.ranking[:k])
        print(f"| k = {k}: IROC top-k | O1 {top:.2f}, identifies {design.rank(result.ranking[:k])}/{design.n_params} |")
        print(
            f"| k = {k}: DETMAX best of 10 | O1 {best.o1:.2f}, identifies {best.rank}/{design.n_params}, "
            f"{t_detmax:.1f} s for 10 runs |"
        )
        print(
            f"| k = {k}: `--k` (greedy, top-k, DETMAX, exchange) | O1 {chosen.o1:.2f}, identifies "
            f"{chosen.rank}/{design.n_params}, {t_k:.1f} s after DETMAX |"
        )


def _timed(argv: list[str]) -> tuple[float, float, float]:
    """Run a posegen command in a fresh process: wall s, CPU s (user + system), peak resident MB."""
    # The peak is VmHWM (reset by exec), not ru_maxrss, which counts the forked copy of this process.
    code = (
        "import resource, sys, time; from posegen.cli import main; start = time.perf_counter(); "
        f"code = main({argv!r}); wall = time.perf_counter() - start; u = resource.getrusage(resource.RUSAGE_SELF); "
        "hwm = next(int(l.split()[1]) for l in open('/proc/self/status') if l.startswith('VmHWM')); "
        "print(wall, u.ru_utime + u.ru_stime, hwm / 1024, file=sys.stderr); sys.exit(code)"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    wall, cpu, peak = (float(v) for v in done.stderr.strip().splitlines()[-1].split())
    return wall, cpu, peak


def _ten_minutes(bag: Path, out: Path, minutes: float = 10.0) -> tuple[int, int, float]:
    """A long session: the simulated one repeated back to back; returns samples, joints, size in MB."""
    from posegen.io import JointStates, RecordedBag, Wrenches, write_recording

    recorded = RecordedBag(bag)
    topics = sorted(t for t, m in recorded.topics.items() if m.endswith("WrenchStamped"))
    joints, wrenches = recorded.read("/joint_states", topics)
    period = joints.times_s[-1] + joints.times_s[1] - joints.times_s[0]
    repeats = int(np.ceil(minutes * 60 / period))
    n = round(minutes * 60 / (joints.times_s[1] - joints.times_s[0]))

    def tile(times: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        stretched = np.concatenate([times + r * period for r in range(repeats)])[:n]
        return stretched, np.tile(values, (repeats, 1))[:n]

    times, positions = tile(joints.times_s, joints.positions)
    long = {}
    for topic, series in zip(topics, wrenches, strict=True):
        at, forces = tile(series.times_s, series.forces)
        long[topic] = Wrenches(at, forces, tile(series.times_s, series.torques)[1])
    write_recording(out, JointStates(joints.names, times, positions), "/joint_states", long, {"bench": "tiled"})
    return n, len(joints.names), sum(f.stat().st_size for f in out.iterdir()) / 1e6


def bench_bag(pool_path: Path, workdir: Path, k: int = 41) -> None:
    from route_bench import route_of

    from posegen.io import read_route

    route = route_of(POSEGEN, ROOT, pool_path, workdir, k)

    start = time.process_time()
    read_route(route)
    reading = time.process_time() - start
    export = _timed(["export", str(route), "--bag", str(workdir / "route_bag")])
    simulate = _timed(["simulate", str(route), "--bag", str(workdir / "session"), "--seed", "7"])
    measure_route = _timed(
        ["measure", str(workdir / "session"), "--route", str(route), "-o", str(workdir / "measured.yaml")]
    )
    samples, joints, size = _ten_minutes(workdir / "session", workdir / "ten_minutes")
    runs = [_timed(["measure", str(workdir / "ten_minutes"), "-o", str(workdir / "ten.yaml")]) for _ in range(3)]
    wall, cpu, peak = min(runs)
    from rosbags.rosbag2 import Reader

    start = time.perf_counter()
    with Reader(workdir / "ten_minutes") as reader:
        connections = [c for c in reader.connections if c.topic == "/joint_states"]
        count = sum(1 for _ in reader.messages(connections=connections))
    iterate = time.perf_counter() - start
    load = os.getloadavg()[0]
    print(f"\n### rosbag2: {k}-posture route, simulated session, 10-minute bag ({machine()}, load {load:.1f})\n")
    print("| figure | value |\n|---|---|")
    print(f"| reading the route file alone (CPU; YAML points, read by each command below) | {reading:.1f} s |")
    print(f"| `posegen export ROUTE --bag` (wall / CPU, incl. start-up) | {export[0]:.1f} s / {export[1]:.1f} s |")
    print(
        f"| `posegen simulate ROUTE --bag` at 500 Hz (wall / CPU) | {simulate[0]:.1f} s / {simulate[1]:.1f} s, "
        f"peak {simulate[2]:.0f} MB |"
    )
    print(
        f"| `posegen measure` of that session with `--route` (wall / CPU) | "
        f"{measure_route[0]:.1f} s / {measure_route[1]:.1f} s |"
    )
    print(
        f"| `posegen measure` of a 10-min bag ({samples} joint states x {joints} joints at 500 Hz, 2 wrench "
        f"topics, {size:.0f} MB): wall / CPU, best of 3 | **{wall:.1f} s** / {cpu:.1f} s (goal 5 s); "
        f"all runs {', '.join(f'{r[0]:.1f}' for r in runs)} s |"
    )
    print(f"| its peak memory (resident) | {peak:.0f} MB |")
    print(f"| for comparison: rosbags iterating the {count} raw JointState messages alone | {iterate:.1f} s |")


def bench_calibration(workdir: Path) -> None:
    from calibration_bench import bench_corrupted_rows, bench_real, bench_recovery  # beside this script

    from posegen.io import load_pool
    from posegen.robot import Scene, load_config

    scene = Scene(load_config(ROOT / "configs" / "talos_table.yaml"))
    data = real_data()
    bench_real(scene, data, machine(), workdir / "calibration")
    bench_corrupted_rows(scene, data, workdir / "calibration")
    bench_recovery(scene, load_pool(ROOT / "plans" / "talos" / "pool.yaml"))


def first_frame_s(browser: Any, page: Path, runs: int = 3) -> float:
    """Median time (s) from opening a page to the first screenshot showing the robot."""
    times = []
    for _ in range(runs):
        browser.open("about:blank")
        start = time.perf_counter()
        browser.open(page.as_uri())
        browser.wait_for_robot()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def bench_view(pool_path: Path, workdir: Path) -> None:
    """Viewer pages of a 60-posture selection, a 41-posture route and a calibration report."""
    sys.path.insert(0, str(ROOT))
    from posegen.view import open_artefact, write_html, write_report
    from tests.view.chromium import Browser, find_browser

    def posegen(*args: str) -> None:
        subprocess.run([POSEGEN, *args], check=True, cwd=ROOT, stdout=subprocess.DEVNULL)

    selection = workdir / "selected_k60.yaml"
    route = workdir / "route.yaml"  # from the route benchmark, when it ran
    if not selection.exists():
        posegen("select", str(pool_path), "--k", "60", "-q", "-o", str(selection))
    if not route.exists():
        posegen("select", str(pool_path), "--k", "41", "-q", "-o", str(workdir / "selected_k41.yaml"))
        posegen("route", str(workdir / "selected_k41.yaml"), "-q", "-o", str(route))
    executable = find_browser()
    print(f"\n### viewer pages ({machine()})\n")
    print("| page | size | scene + steps | serialize | wall (`posegen view --html`) | first frame |")
    print("|---|---|---|---|---|---|")
    for label, path in (("selection, 60 postures (1 s each)", selection), ("route, 41 postures (15 fps)", route)):
        html = workdir / f"{path.stem}.html"
        page = write_html(open_artefact(path), html)
        start = time.perf_counter()
        posegen("view", str(path), "--html", str(workdir / "cli.html"))
        wall = time.perf_counter() - start
        first = "no browser"
        if executable:
            with Browser(executable) as browser:
                first = f"{first_frame_s(browser, html):.1f} s"
        print(
            f"| {label}: {page.steps} steps, {page.duration_s:.0f} s | {page.size_bytes / 1e6:.2f} MB | "
            f"{page.build_s:.1f} s | {page.serialize_s:.1f} s | {wall:.1f} s | {first} |"
        )
    measurements, calibration = workdir / "sim60.yaml", workdir / "calibration"
    posegen("simulate", str(selection), "--seed", "7", "-o", str(measurements))
    posegen(
        "calibrate",
        str(measurements),
        "--prior-scale",
        "5",
        "--candidates",
        "offsets_legs",
        "-q",
        "-o",
        str(calibration),
    )
    start = time.perf_counter()
    report = write_report(calibration)
    took = time.perf_counter() - start
    size = report.stat().st_size / 1e6
    print(f"| calibration `report.html`, 60 contacts (in-process) | {size:.2f} MB | | | {took:.1f} s | |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--only",
        nargs="*",
        default=[
            "pool",
            "dask",
            "select",
            "route",
            "bag",
            "calibration",
            "simulation",
            "session",
            "view",
            "scale",
            "robots",
        ],
        help="stages to run",
    )
    parser.add_argument("--n", type=int, default=1500, help="pool size")
    parser.add_argument("--large-n", type=int, default=20000, help="size of the large pool (stage scale)")
    parser.add_argument(
        "--measure-n", type=int, default=None, help="make a pool of this size and project to --large-n (stage scale)"
    )
    parser.add_argument("--session-seeds", type=int, default=3, help="robot seeds of the session stage")
    parser.add_argument("--session-workers", type=int, default=2, help="worker processes of the session stage")
    parser.add_argument("--session-batches", type=int, default=6, help="batches each rehearsal adds at most")
    parser.add_argument("--session-pool", default=None, help="pool of the session stage (default: the stage pool's)")
    parser.add_argument("--session-plot", default=None, help="draw the session stage's curves into this PNG")
    parser.add_argument("--keep", default=None, help="keep the generated files in this folder")
    args = parser.parse_args()
    workdir = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="posegen-bench-"))
    workdir.mkdir(parents=True, exist_ok=True)
    pool_path = workdir / "pool.yaml"
    if "pool" in args.only:
        scale.bench_sample_cost(machine())
        pool_path = bench_pool(workdir, args.n)
    if "dask" in args.only:
        scale.bench_dask(pool_path, workdir, machine())
    if "select" in args.only:
        bench_select(pool_path, workdir)
    if "route" in args.only:
        from route_bench import bench_routes

        bench_routes(POSEGEN, ROOT, workdir, machine)
    if "bag" in args.only:
        bench_bag(pool_path, workdir)
    if "calibration" in args.only:
        bench_calibration(workdir)
    if "simulation" in args.only:
        from simulation_bench import bench_kept  # benchmarks/simulation_bench.py, beside this script

        bench_kept(workdir / "simulation", machine())
    if "session" in args.only:
        from session_bench import bench_session  # benchmarks/session_bench.py, beside this script

        seeds = tuple(range(1, args.session_seeds + 1))
        bench_session(
            Path(args.session_pool) if args.session_pool else pool_path,
            workdir,
            machine(),
            seeds=seeds,
            workers=args.session_workers,
            max_batches=args.session_batches,
            plot=Path(args.session_plot) if args.session_plot else None,
        )
    if "view" in args.only:
        bench_view(pool_path, workdir)
    if "scale" in args.only:
        scale.bench_scale(workdir, args.large_n, args.measure_n or args.large_n, machine())
    if "robots" in args.only:
        from robots import bench_robots  # benchmarks/robots.py, beside this script

        bench_robots(workdir / "robots", machine())


if __name__ == "__main__":
    main()
