"""Every shipped robot through the whole pipeline (``make bench``, stage ``robots``).

Per robot: pool (wall time, acceptance), check, base parameters per chain, select, route of
20 selected postures (routed / selected, robot time per contact), check, and a simulated
calibration judged on the pool's other postures. One Markdown table for the README.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
POSEGEN = str(Path(sys.executable).with_name("posegen"))
CONFIGS = ("talos_table.yaml", "talos_full_table.yaml", "romeo_table.yaml", "icub_table.yaml")


def _run(*argv: str) -> tuple[float, str]:
    start = time.perf_counter()
    done = subprocess.run([POSEGEN, *argv], check=True, cwd=ROOT, capture_output=True, text=True)
    return time.perf_counter() - start, done.stdout


def _base_per_chain(pool_path: Path) -> dict[str, int]:
    """Base parameters of each chain alone, one table session (robot and plane parameters)."""
    from posegen.io import load_pool
    from posegen.model import ContactModel, Contacts, planned_kinds, structural_base
    from posegen.robot import scene_for

    pool = load_pool(pool_path)
    scene = scene_for(pool.provenance, None)
    out = {}
    for chain in scene.chains:
        rows = [i for i, p in enumerate(pool.postures) if p.chain == chain.name]
        names = (chain.name,) * len(rows)
        kinds = planned_kinds(scene, names)
        contacts = Contacts(pool.joints()[rows], names, ("s",) * len(rows), ("",) * len(rows), kinds)
        out[chain.name] = structural_base(ContactModel(scene, [chain.name], ["s"]), contacts).size
    return out


def _first_of_selection(selection: Path, out: Path, count: int) -> None:
    """A selection file of the first ``count`` postures: ``route`` can then replace a lost one from the pool."""
    from posegen.io import SELECTION_FORMAT, read_yaml, write_yaml

    data = read_yaml(selection, SELECTION_FORMAT)
    data["postures"] = data["postures"][:count]
    write_yaml(out, data)


def bench_robot(config: str, workdir: Path, n: int, routed: int) -> dict[str, str]:
    """Run one robot's pipeline in ``workdir``; its README row."""
    from posegen.io import load_pool, load_postures, write_pool

    pool = workdir / "pool.yaml"
    t_pool, _ = _run("pool", "--n", str(n), "--config", f"configs/{config}", "--workers", "2", "-q", "-o", str(pool))
    made = load_pool(pool)
    attempted, accepted = made.attempted, len(made.postures)
    t_check, out = _run("check", str(pool), "-q")
    assert "FAIL" not in out, out
    base = _base_per_chain(pool)
    selection = workdir / "selected.yaml"
    t_select, out = _run("select", str(pool), "-q", "-o", str(selection))
    selected, _ = load_postures(selection)
    k = len(selected.postures)
    subset = workdir / "route_input.yaml"  # the first postures of the selection, still a selection of its pool
    _first_of_selection(selection, subset, routed)
    route = workdir / "route.yaml"
    t_route, _ = _run("route", str(subset), "-q", "-o", str(route))
    summary = yaml.load(route.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))["summary"]
    t_route_check, out = _run("check", str(route), "-q")
    assert "FAIL" not in out, out
    train, held = workdir / "train.yaml", workdir / "held.yaml"
    chosen = {p.sample for p in selected.postures}
    others = workdir / "not_selected.yaml"  # held out: the pool's postures the selection left
    write_pool(others, dataclasses.replace(made, postures=tuple(p for p in made.postures if p.sample not in chosen)))
    _run("simulate", str(selection), "--seed", "7", "-o", str(train))  # one seed: one simulated robot
    _run("simulate", str(others), "--seed", "7", "-o", str(held))
    t_cal, _ = _run("calibrate", str(train), "--validate", str(held), "-q", "-o", str(workdir / "calibration"))
    report = yaml.safe_load((workdir / "calibration" / "calibration.yaml").read_text())
    return {
        "robot": config.removesuffix("_table.yaml"),
        "joints": str(len(made.joint_names)),
        "pool": f"{accepted} of {attempted} ({100 * accepted / attempted:.0f} %), {t_pool:.0f} s",
        "check": f"{t_check:.0f} s, clean",
        "base per chain": ", ".join(f"{c} {b}" for c, b in base.items()),
        "select": f"k = {k} (IROC), {t_select:.0f} s",
        "route": f"{summary['routed']} of {routed} ({summary['substituted']} from the pool), "
        f"{summary['robot_time_per_contact_s']:.1f} s per contact, "
        f"planned in {t_route:.0f} s; check {t_route_check:.0f} s, clean",
        "held-out": _held_out(report),
        "calibrate": f"{t_cal:.0f} s",
    }


def _held_out(report: dict) -> str:
    """Held-out mean absolute errors, nominal URDF -> calibrated.urdf, each as a stack loading it sees it."""
    files = report["deliverables"]
    held = files["nominal_urdf"]["held_out"]["all"]
    before, after = held["mean_abs"], files["urdf"]["held_out"]["all"]["mean_abs"]
    shown = [f"z {before['z_mm']:.2f} -> {after['z_mm']:.3f} mm"]
    for component in ("roll", "pitch"):  # not measured by point contacts (None)
        if before[f"{component}_deg"] is not None:
            shown.append(f"{component} {before[f'{component}_deg']:.2f} -> {after[f'{component}_deg']:.3f} deg")
    return ", ".join(shown) + f" ({held['contacts']} contacts)"


def bench_robots(workdir: Path, machine: str, n: int = 300, routed: int = 20) -> None:
    """Every shipped robot; prints one Markdown table."""
    rows = []
    for config in CONFIGS:
        folder = workdir / config.removesuffix(".yaml")
        folder.mkdir(parents=True, exist_ok=True)
        rows.append(bench_robot(config, folder, n, routed))
    print(f"\n### robots: pool of {n}, route of {routed} selected postures ({machine})\n")
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |\n|" + "---|" * len(keys))
    for row in rows:
        print("| " + " | ".join(row[k] for k in keys) + " |")
