"""Benchmarks of issue 15: a pool on a Dask cluster, and pools, checks and selections at scale.

Called by ``run.py`` (``--only dask scale``). Wall times on a shared machine vary: each
table states the load average before and after its runs.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from posegen.io import load_pool, sidecars_of

ROOT = Path(__file__).resolve().parents[1]
POSEGEN = str(Path(sys.executable).with_name("posegen"))
_MEASURE = (  # runs a command and prints the peak resident memory of its largest process (kB)
    "import resource, subprocess, sys; code = subprocess.run(sys.argv[1:]).returncode; "
    "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); sys.exit(code)"
)


def load() -> str:
    """The 1-minute load average (2 means both cores of a 2-core machine busy)."""
    return f"{os.getloadavg()[0]:.1f}"


def measured(*args: str) -> tuple[float, float]:
    """Run ``posegen ARGS``: wall time (s) and peak memory of its largest process (MB)."""
    start = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", _MEASURE, POSEGEN, *args],
        check=True,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    return time.perf_counter() - start, int(out.stdout.split()[-1]) / 1024


def size_mb(*paths: Path) -> float:
    """Total size of some files (MB)."""
    return sum(p.stat().st_size for p in paths if p.exists()) / 1e6


def bench_dask(pool_path: Path, workdir: Path, machine: str) -> None:
    """The 1500 pool again through a 2-worker LocalCluster on 127.0.0.1: time and identical bytes."""
    from distributed import LocalCluster

    n = len(load_pool(pool_path).postures)
    before = load()
    start = time.perf_counter()
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0"
    ) as cluster:
        t_cluster = time.perf_counter() - start
        out = workdir / "dask" / pool_path.name  # same file name: the header names its sidecar
        wall, _ = measured("pool", "--n", str(n), "-q", "--scheduler", cluster.scheduler_address, "-o", str(out))
        same = all(
            a.read_bytes() == b.read_bytes()
            for a, b in ((out, pool_path), *zip(sidecars_of(out), sidecars_of(pool_path), strict=True))
        )
        start = time.perf_counter()
        subprocess.run(
            [POSEGEN, "check", str(out), "-q", "--scheduler", cluster.scheduler_address],
            check=True,
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
        )
        t_check = time.perf_counter() - start
    print(f"\n### pool of {n} on a 2-worker Dask LocalCluster, 127.0.0.1 ({machine}; load {before} -> {load()})\n")
    print("| figure | value |\n|---|---|")
    print(f"| LocalCluster start (2 worker processes) | {t_cluster:.1f} s |")
    print(f"| wall time, `posegen pool --n {n} --scheduler ...` (incl. start-up, cluster up) | {wall:.1f} s |")
    print(f"| same bytes as the local 2-process pool (header and sidecar) | {'yes' if same else 'NO'} |")
    print(f"| `posegen check --scheduler ...` on meshes | {t_check:.1f} s |")


def bench_scale(workdir: Path, n: int, measured_n: int, machine: str) -> Path:
    """A large pool (or its projection from a smaller run): time, memory, size; select and check on it."""
    before = load()
    out = workdir / f"pool_{measured_n}.yaml"
    wall, peak = measured("pool", "--n", str(measured_n), "--workers", "2", "-q", "-o", str(out))
    pool = load_pool(out)
    inline = workdir / "inline.yaml"
    from posegen.io import write_yaml

    write_yaml(inline, pool.to_dict())
    start = time.perf_counter()
    load_pool(out)
    t_load = time.perf_counter() - start
    start = time.perf_counter()
    load_pool(inline)
    t_inline = time.perf_counter() - start
    scale = n / measured_n
    label = f"{n}" if scale == 1 else f"{n} (projected from {measured_n}, x{scale:g})"
    print(f"\n### pool of {label} ({machine}; load {before} -> {load()})\n")
    print("| figure | value |\n|---|---|")
    print(
        f"| wall time, `posegen pool --n {measured_n} --workers 2` | {wall:.1f} s"
        + (f" -> projected {wall * scale:.0f} s for {n}" if scale != 1 else "")
        + " |"
    )
    print(f"| samples attempted / accepted | {pool.attempted} / {len(pool.postures)} |")
    print(f"| peak memory, largest process | {peak:.0f} MB |")
    print(
        f"| file: YAML header + .npz sidecar | {size_mb(out):.2f} + {size_mb(sidecars_of(out)[0]):.2f} MB "
        f"(all inline in YAML: {size_mb(inline):.1f} MB) |"
    )
    print(f"| load (`load_pool`) | {t_load:.2f} s (inline YAML: {t_inline:.1f} s) |")
    inline.unlink()
    wall, peak = measured("check", str(out), "--workers", "2", "-q")
    print(f"| `posegen check` on meshes, 2 workers | {wall:.1f} s, peak {peak:.0f} MB |")
    wall, peak = measured("select", str(out), "-q", "-o", str(workdir / f"selected_{measured_n}.yaml"))
    print(f"| `posegen select` (IROC, certificate, plot) | {wall:.1f} s, peak {peak:.0f} MB |")
    return out


def bench_sample_cost(machine: str, samples: int = 1000) -> None:
    """CPU time per sample in one process: what a loaded machine cannot hide."""
    from posegen.pool import PostureSampler
    from posegen.robot import Scene, load_config

    sampler = PostureSampler(Scene(load_config(ROOT / "configs" / "talos_table.yaml")), 0)
    start = time.process_time()
    outcomes = [sampler.evaluate(i) for i in range(samples)]
    cpu = (time.process_time() - start) / samples
    accepted = sum(not isinstance(o, str) for o in outcomes)
    print(f"\n### cost of a sample, samples 0-{samples - 1} of seed 0, one process ({machine}; load {load()})\n")
    print("| figure | value |\n|---|---|")
    print(f"| CPU time per sample | {1000 * cpu:.2f} ms ({accepted / samples:.1%} accepted) |")
    print(f"| CPU time per accepted posture | {1000 * cpu * samples / accepted:.1f} ms |")
