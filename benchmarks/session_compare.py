"""The session benchmark's figures: per-seed results, the table, the fixed-design comparison, the plot, the raw JSON.

Imported by ``benchmarks/session_bench.py``, which rehearses and judges; this module only
summarises what it measured (medians and min-max over robot seeds), so each figure is
computed from the same per-seed numbers that are written to the JSON.
"""

from __future__ import annotations

import json
import math
import statistics
import sys
import textwrap
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

ORDERS = ("session (its recordings)", "session postures", "IROC", "random")
DELIVERABLES = ("urdf", "compensated")  # the URDF alone; the URDF with its compliance compensation (NaN: none)


@dataclass(frozen=True)
class SeedResult:
    """One robot seed's figures (errors in mm, true mean absolute held-out height error of the worst chain)."""

    seed: int
    counts: list[int]  # the session's contacts after each assessed batch
    errors: dict[str, dict[str, list[float]]]  # deliverable -> order -> error at each of ``counts``
    fixed_contacts: int  # contacts of the fixed exact-k IROC design (its postures that settled)
    fixed_error: dict[str, float]  # deliverable -> error of the fixed design
    predicted_mm: dict[str, float]  # deliverable -> CV-predicted error at the last batch (worst chain; NaN: none)
    noisy_true_mm: dict[str, float]  # deliverable -> true error there, on held-out contacts with contact noise
    robot_s: float  # robot time the session's bags recorded (joint states), s
    robot_contacts: int  # contacts measured in those bags

    @property
    def s_per_contact(self) -> float:
        """The session's robot time per contact, s."""
        return self.robot_s / self.robot_contacts


def _cell(values: Sequence[float]) -> str:
    """``median (min-max)``, NaN-aware: a seed with no such deliverable is left out and counted."""
    kept = [v for v in values if not math.isnan(v)]
    if not kept:
        return "n/a"
    missing = f" [{len(values) - len(kept)} n/a]" if len(kept) < len(values) else ""
    return f"{statistics.median(kept):.2f} ({min(kept):.2f}-{max(kept):.2f}){missing}"


def _median(values: Sequence[float]) -> float:
    kept = [v for v in values if not math.isnan(v)]
    return statistics.median(kept) if kept else math.nan


def batches_of(trials: Sequence[SeedResult]) -> int:
    """Batches every seed reached (the table's rows)."""
    return min(len(t.counts) for t in trials)


def print_table(trials: Sequence[SeedResult], deliverable: str) -> None:
    """The true-error table of one deliverable: a row per batch, a column per order, and the fixed design."""
    fixed = _cell([t.fixed_error[deliverable] for t in trials])
    k = sorted({t.fixed_contacts for t in trials})
    print(f"\n{deliverable} deliverable; fixed IROC design ({'/'.join(map(str, k))} contacts): {fixed} mm\n")
    print("| contacts | " + " | ".join(f"{name}: median (min-max) mm" for name in ORDERS) + " |")
    print("|---" * (len(ORDERS) + 1) + "|")
    for b in range(batches_of(trials)):
        cells = [_cell([t.errors[deliverable][name][b] for t in trials]) for name in ORDERS]
        shown = sorted({t.counts[b] for t in trials})
        print(f"| {'/'.join(str(c) for c in shown)} | " + " | ".join(cells) + " |")


def print_paired(trials: Sequence[SeedResult], deliverable: str) -> None:
    """The session's error minus each other order's and the fixed design's on the same robot, per batch.

    Paired by seed: the robots differ more from one another (3-7 mm) than the orders do, so
    a difference of column medians says little; the median of the per-seed differences and
    the seeds where the session is lower say what the choice does.
    """
    session = ORDERS[0]
    others = [*ORDERS[1:], "fixed"]
    print(f"\n{deliverable}: the session's recordings minus each, paired by seed (median mm; seeds where lower)\n")
    print("| contacts | " + " | ".join(others) + " |")
    print("|---" * (len(others) + 1) + "|")
    for b in range(batches_of(trials)):
        cells = []
        for other in others:
            differences = [
                t.errors[deliverable][session][b]
                - (t.fixed_error[deliverable] if other == "fixed" else t.errors[deliverable][other][b])
                for t in trials
            ]
            kept = [d for d in differences if not math.isnan(d)]
            lower = sum(d < 0 for d in kept)
            cells.append(f"{statistics.median(kept):+.2f} ({lower} of {len(kept)})" if kept else "n/a")
        shown = sorted({t.counts[b] for t in trials})
        print(f"| {'/'.join(str(c) for c in shown)} | " + " | ".join(cells) + " |")


def reach(
    trials: Sequence[SeedResult], deliverable: str, order: str = ORDERS[0]
) -> tuple[int | None, list[int | None]]:
    """Contacts at which an order first reaches the fixed design's error.

    Returns:
        The median contacts of the first batch whose median error is <= the fixed design's
        median (None: never within the batches run), and per seed the first count whose
        error is <= that seed's fixed-design error (None: never).

    """
    fixed = _median([t.fixed_error[deliverable] for t in trials])
    first: int | None = None
    for b in range(batches_of(trials)):
        if _median([t.errors[deliverable][order][b] for t in trials]) <= fixed:
            first = int(statistics.median(t.counts[b] for t in trials))
            break
    per_seed: list[int | None] = []
    for t in trials:
        hits = [
            c for c, e in zip(t.counts, t.errors[deliverable][order], strict=True) if e <= t.fixed_error[deliverable]
        ]
        per_seed.append(hits[0] if hits else None)
    return first, per_seed


def print_comparison(trials: Sequence[SeedResult], k: int = 60) -> None:
    """The fixed design's comparison against its ``k`` planned postures (contacts to reach, robot time saved).

    And the stopping rule's ratio.
    """
    pace = statistics.median(t.s_per_contact for t in trials)
    print(
        f"\nrobot time per contact (the session's bags: joint-state span / contacts, median over seeds): {pace:.1f} s"
    )
    for deliverable in DELIVERABLES:
        for order in (ORDERS[0], "IROC"):
            first, per_seed = reach(trials, deliverable, order)
            seeds = ", ".join("-" if c is None else str(c) for c in per_seed)
            if first is None:
                verdict = "not reached within the batches run"
            else:
                fewer = 100 * (k - first) / k
                change = f"{fewer:.0f} % fewer than {k}" if fewer >= 0 else f"{-fewer:.0f} % more than {k}"
                verdict = f"{first} contacts ({change}; robot time {(k - first) * pace:+.0f} s saved)"
            print(f"- {deliverable}, {order} order reaches the fixed design's median: {verdict}; per seed: {seeds}")
    print("\nat the last batch: predicted (CV, worst chain) / true held-out error (worst chain, with contact noise)")
    for deliverable in DELIVERABLES:
        ratios = [t.predicted_mm[deliverable] / t.noisy_true_mm[deliverable] for t in trials]
        kept = [r for r in ratios if not math.isnan(r)]
        within = sum(abs(r - 1) <= 0.25 for r in kept)
        print(
            f"- {deliverable}: {', '.join(f'{r:.2f}' for r in ratios)} (median {_median(ratios):.2f}; "
            f"{within} of {len(kept)} within 25 %)"
        )


def print_seeds(trials: Sequence[SeedResult]) -> None:
    """Per seed: the fixed design's and the session's first and last errors, its robot time, the stopping ratios."""
    print(
        "\n| seed | fixed IROC: urdf / compensated mm | session, first batch | session, last batch | s per contact "
        "| predicted / true at the last batch: urdf, compensated |"
    )
    print("|---" * 6 + "|")
    for t in trials:
        ratio = {d: t.predicted_mm[d] / t.noisy_true_mm[d] for d in DELIVERABLES}
        first, last = (" / ".join(f"{t.errors[d][ORDERS[0]][b]:.2f}" for d in DELIVERABLES) for b in (0, -1))
        print(
            f"| {t.seed} | {' / '.join(f'{t.fixed_error[d]:.2f}' for d in DELIVERABLES)} ({t.fixed_contacts}) "
            f"| {first} ({t.counts[0]}) | {last} ({t.counts[-1]}) | {t.s_per_contact:.1f} "
            f"| {ratio['urdf']:.2f}, {ratio['compensated']:.2f} |"
        )


def write_json(trials: Sequence[SeedResult], settings: dict[str, object], path: Path) -> None:
    """The raw per-seed numbers and the settings they were measured with."""
    path.parent.mkdir(parents=True, exist_ok=True)
    data = {"settings": settings, "seeds": [asdict(t) for t in trials]}
    path.write_text(json.dumps(data, indent=1, allow_nan=True) + "\n")


def plot_curves(trials: Sequence[SeedResult], title: str, path: Path) -> None:
    """Median and min-max band of each order against contacts, the fixed design as a point; one panel a deliverable."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(DELIVERABLES), figsize=(11, 4.2), sharex=True)
    n = batches_of(trials)
    x = [statistics.median(t.counts[b] for t in trials) for b in range(n)]
    for ax, deliverable in zip(axes, DELIVERABLES, strict=True):
        for name in ORDERS:
            rows = [[t.errors[deliverable][name][b] for t in trials] for b in range(n)]
            kept = [[v for v in r if not math.isnan(v)] or [math.nan] for r in rows]
            line = ax.plot(x, [statistics.median(r) for r in kept], marker="o", label=name)[0]
            ax.fill_between(x, [min(r) for r in kept], [max(r) for r in kept], color=line.get_color(), alpha=0.12)
        fixed = [t.fixed_error[deliverable] for t in trials if not math.isnan(t.fixed_error[deliverable])]
        if fixed:
            k = statistics.median(t.fixed_contacts for t in trials)
            med = statistics.median(fixed)
            ax.axhline(med, color="black", linestyle="--", linewidth=1, label=f"fixed IROC k={k:g} (median)")
            ax.errorbar([k], [med], yerr=[[med - min(fixed)], [max(fixed) - med]], color="black", marker="s", capsize=4)
        ax.set_title(f"{deliverable} deliverable")
        ax.set_xlabel("contacts")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("true held-out height error, worst chain (mm)")
    axes[0].legend(fontsize=8)
    fig.suptitle(textwrap.fill(title, 150), fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report(trials: Sequence[SeedResult], machine: str, about: str, plot: Path | None = None, k: int = 60) -> None:
    """Print every table and figure of the session benchmark; draw its curves into ``plot`` (PNG) if given."""
    print(f"\n### session: true held-out height error at fixed contact counts ({machine})\n\n{about}\n")
    print("true error: mean abs height, worst chain, on held-out contacts without contact noise (the model's)")
    for deliverable in DELIVERABLES:
        print_table(trials, deliverable)
        print_paired(trials, deliverable)
    print_comparison(trials, k)
    print_seeds(trials)
    if plot is not None:
        plot_curves(trials, about, plot)


def read_json(path: Path) -> tuple[list[SeedResult], dict[str, object]]:
    """The per-seed figures and settings ``write_json`` wrote (to report them again)."""
    data = json.loads(path.read_text())
    return [SeedResult(**seed) for seed in data["seeds"]], data["settings"]


if __name__ == "__main__":  # report a run again from its JSON: session_compare.py JSON [PNG]
    again, facts = read_json(Path(sys.argv[1]))
    report(
        again,
        str(facts.get("machine", "partial run")),
        str(facts.get("about", "partial run")),
        Path(sys.argv[2]) if len(sys.argv) > 2 else None,
        int(facts.get("fixed_k", 60)),  # type: ignore[call-overload]
    )
