"""The figures of a design chosen from a pool, as a :class:`~posegen.io.selection_file.Selection`, and its plots."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from posegen.io import (
    Certificate,
    DesignFigures,
    DetmaxFigures,
    IrocFigures,
    Pool,
    Selection,
    SelectionMethod,
    atomic_path,
    chosen_from_pool,
)
from posegen.model import Design
from posegen.select.selection import Iroc
from posegen.select.subset_selection import Subset


def design_selection(
    pool: Pool,
    pool_path: str,
    design: Design,
    result: Iroc,
    chosen: Subset,
    method: SelectionMethod,
    detmax: tuple[Subset, ...],
    seed: int,
) -> Selection[DesignFigures]:
    """The selection of ``chosen`` from a pool, with its provenance and figures."""
    provenance = dict(pool.provenance)
    provenance["seed"] = seed
    provenance["pool"] = pool_path
    provenance["pool_sha256"] = hashlib.sha256(Path(pool_path).read_bytes()).hexdigest()
    rank_of = {row: r + 1 for r, row in enumerate(result.ranking)}
    weights = result.weights
    postures = tuple(chosen_from_pool(pool, row, rank_of[row], float(weights.weights[row])) for row in chosen.rows)
    figures = DesignFigures(
        base_parameters=design.n_params,
        pool_postures=design.size,
        selected=len(chosen.rows),
        rank=chosen.rank,
        o1=chosen.o1,
        o1_star=result.o1_star,
        o1_over_o1_star=chosen.o1 / result.o1_star if result.o1_star > 0 else 0.0,
        certificate=Certificate(weights.gap, weights.efficiency_bound, weights.o1_ratio_bound, weights.iterations),
        iroc=IrocFigures(
            selected_k=len(result.selected.rows),
            selected_o1=result.selected.o1,
            k_reaching_fraction_of_o1_star={str(f): k for f, k in result.fractions.items()},
            support=result.support,
            weight_drop_after_rank=result.weight_drop_k,
            o1_curve=tuple(result.curve),
        ),
        detmax=DetmaxFigures(tuple(s.o1 for s in detmax), tuple(s.rank for s in detmax)),
    )
    return Selection(provenance, method, pool.joint_names, figures, postures)


def plot_o1(result: Iroc, path: Path) -> None:
    """O1(k) of the IROC ranking over the sorted weights (the paper's Fig. 3)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4.5))
    k_max = max(k for k, _ in result.curve)
    ranks = np.arange(1, k_max + 1)
    sorted_w = result.weights.weights[list(result.ranking[:k_max])]
    ax.bar(ranks, sorted_w, color="tab:gray", alpha=0.6, label="IROC weight")
    ax.set_xlabel("postures stacked, by decreasing weight (k)")
    ax.set_ylabel("weight")
    twin = ax.twinx()
    ks = [k for k, _ in result.curve]
    twin.plot(ks, [v for _, v in result.curve], color="tab:blue", label="O1(k)")
    twin.axhline(result.o1_star, color="tab:blue", ls=":", label="O1* (optimal weights)")
    selected = len(result.selected.rows)
    twin.axvline(selected, color="tab:red", ls="--", label=f"selected k = {selected}")
    twin.set_ylabel("O1")
    lines = ax.get_legend_handles_labels()
    more = twin.get_legend_handles_labels()
    twin.legend(lines[0] + more[0], lines[1] + more[1], loc="lower right")
    ax.set_title(f"IROC: O1 of the top-k postures (gap {result.weights.gap:.1e})")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def plot_detmax(iroc_subset: Subset, chosen: Subset, detmax: tuple[Subset, ...], path: Path) -> None:
    """O1 of IROC, of the final selection and of every DETMAX run (the paper's Fig. 4)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    runs = np.arange(1, len(detmax) + 1)
    ax.plot(runs, [s.o1 for s in detmax], "o", color="tab:orange", label=f"DETMAX runs (k = {len(detmax[0].rows)})")
    ax.axhline(iroc_subset.o1, color="tab:blue", label=f"IROC top-k (k = {len(iroc_subset.rows)})")
    ax.axhline(chosen.o1, color="tab:green", ls="--", label=f"selection (k = {len(chosen.rows)})")
    ax.set_xlabel("DETMAX run (seeded random start)")
    ax.set_ylabel("O1")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
