"""The select stage's command, from files to files: ``posegen select``."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from posegen.io import write_yaml
from posegen.model import build_design
from posegen.progress import ProgressCallback, Steps, ignore_progress
from posegen.robot import load_pool, scene_for
from posegen.select.report import plot_detmax, plot_o1, selection_to_dict
from posegen.select.selection import detmax_runs, iroc, select_k
from posegen.select.subset_selection import Subset, subset_of


@dataclass(frozen=True)
class SelectionSettings:
    """How postures are chosen."""

    k: int | None = None  # exactly k postures (greedy, IROC top-k, DETMAX, exchange); None: where O1 peaks
    runs: int = 0  # DETMAX runs from seeded random starts (run r draws from seed * 1000 + r)
    seed: int = 0  # seed of the DETMAX starts
    fractions: tuple[float, ...] = (0.9, 0.95)  # report the smallest k reaching these fractions of O1*


def select_pool_file(
    pool_path: str,
    output: str,
    settings: SelectionSettings | None = None,
    config_path: str | None = None,
    progress: ProgressCallback = ignore_progress,
) -> dict[str, Any]:
    """Select postures from a pool file; write the selection file and its plots.

    Args:
        pool_path: Pool file.
        output: Selection file; ``<stem>_o1.png`` (and with DETMAX runs, ``<stem>_detmax.png``)
            go beside it.
        settings: How to choose; defaults if None.
        config_path: Scene config; None: the one saved in the pool.
        progress: Told when each step starts.

    Returns:
        The selection file's content.

    Raises:
        PosegenError: Not a pool, an empty or rank-deficient pool, or k out of range.

    """
    settings = settings or SelectionSettings()
    k, runs, seed = settings.k, settings.runs, settings.seed
    pool = load_pool(pool_path)
    scene = scene_for(pool.provenance, config_path)
    timings: dict[str, float] = {}
    say = Steps(4 + runs, progress)
    start = time.perf_counter()
    say("information matrices")
    design, _ = build_design(scene, pool.joints(), [p.chain for p in pool.postures])
    timings["design"] = time.perf_counter() - start
    start = time.perf_counter()
    say("IROC weights")
    result = iroc(design, fractions=settings.fractions)
    timings["iroc"] = time.perf_counter() - start
    size = k if k else len(result.selected.rows)
    start = time.perf_counter()
    detmax: list[Subset] = []
    for r in range(runs):
        say(f"DETMAX run {r + 1}")
        detmax.extend(detmax_runs(design, size, 1, seed * 1000 + r))
    timings["detmax"] = time.perf_counter() - start
    start = time.perf_counter()
    say("exact design" if k else "write")
    chosen = select_k(design, size, result.ranking, tuple(detmax)) if k else result.selected
    timings["k_selection"] = time.perf_counter() - start
    method = "k" if k else "iroc"
    data = selection_to_dict(pool, pool_path, design, result, chosen, method, tuple(detmax), timings, seed)
    path = Path(output)
    write_yaml(path, data)
    plot_o1(result, path.with_name(path.stem + "_o1.png"))
    if detmax:
        top_k = subset_of(design, result.ranking[:size]) if k else result.selected
        plot_detmax(top_k, chosen, tuple(detmax), path.with_name(path.stem + "_detmax.png"))
    return data
