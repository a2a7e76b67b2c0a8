"""The whole pipeline's artefacts, at small sizes, are byte-identical to a committed manifest.

A refactoring must not change a byte of what posegen writes: this runs every stage from the
command line (robot init, pool, select, route, check, export, simulate, measure, calibrate, view) with the
version field held fixed, and compares the SHA-256 of every file written against
``tests/data/artefact_manifest.json``. A deliberate change of a format regenerates the manifest:

    POSEGEN_UPDATE_MANIFEST=1 .venv/bin/python -m pytest tests/test_artefact_bytes.py
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from pathlib import Path

import pytest
from example_robot_data import robots_loader

import posegen.io.artefact
from posegen.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
MANIFEST = ROOT / "tests" / "data" / "artefact_manifest.json"
VERSION = "0.0.0+manifest"  # held fixed: the installed version must not change the bytes
CONFIG = str(ROOT / "configs" / "talos_table.yaml")
ROBOT = ["--seed", "7", "--error-mm", "2", "--error-deg", "0.5", "--noise-deg", "0.005"]


def example_urdf(subpath: str) -> str:
    """A URDF file of example-robot-data (drafted from its path: no SRDF, no loader)."""
    return os.path.normpath(Path(robots_loader.getModelPath(subpath)) / subpath)


ROMEO = example_urdf("romeo_description/urdf/romeo_small.urdf")  # legs bent, capsules added, point contacts
ICUB = example_urdf("icub_description/robots/icub_reduced.urdf")  # soles declared, flush contacts, speeds guessed

PIPELINE = (  # (argv, expected exit code); paths relative to the run's folder
    (["robot", "init", "talos", "--samples", "40", "-o", "talos_draft.yaml"], 0),  # its SRDF's state
    (["robot", "init", ROMEO, "--samples", "30", "-o", "romeo_draft.yaml"], 0),
    (["robot", "init", ICUB, "--samples", "30", "--seed", "2", "-o", "icub_draft.yaml"], 0),
    (["pool", "--config", CONFIG, "--n", "80", "--seed", "3", "--workers", "1", "-o", "pool.yaml"], 0),
    (["select", "pool.yaml", "--k", "40", "-o", "selected.yaml"], 0),
    (["route", "selected.yaml", "--seed", "0", "--workers", "1", "--csv", "-o", "route.yaml"], 0),
    (["check", "route.yaml"], 0),
    (["export", "route.yaml", "--bag", "route_bag"], 0),
    (["simulate", "route.yaml", "--bag", "recording", "--rate", "100", *ROBOT], 0),
    (["simulate", "pool.yaml", "-o", "held_out.yaml", "--session", "check", *ROBOT], 0),
    (["measure", "recording", "--route", "route.yaml", "--config", CONFIG, "-o", "measured.yaml"], 0),
    (["select", "pool.yaml", "--k", "4", "--given", "measured.yaml", "-o", "follow_up.yaml"], 0),
    (
        [
            "calibrate",
            "measured.yaml",
            "--validate",
            "held_out.yaml",
            "--candidates",
            "offsets",
            "--prior-scale",
            "5",
            "--fold-seeds",
            "1",
            "--workers",
            "1",
            "-o",
            "calibration",
        ],
        0,
    ),
    (["view", "route.yaml", "--html", "route.html"], 0),
)


def machine_paths(folder: Path) -> tuple[tuple[bytes, bytes], ...]:
    """The absolute paths a file may name that differ between checkouts, and their placeholders."""
    return (
        (str(folder).encode(), b"<run>"),  # the output folder (the report names it)
        (str(Path(sys.prefix)).encode(), b"<venv>"),  # the nominal URDF a calibrated config points to
        (str(ROOT).encode(), b"<checkout>"),
    )


def digest_tree(folder: Path) -> dict[str, str]:
    """SHA-256 of every file under ``folder`` (machine paths replaced), by its relative path; locks excluded."""
    digests = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file() and not path.name.endswith(".lock"):
            data = path.read_bytes()
            for machine, placeholder in machine_paths(folder):
                data = data.replace(machine, placeholder)
            digests[str(path.relative_to(folder))] = hashlib.sha256(data).hexdigest()
    return digests


def test_the_pipeline_writes_the_manifests_bytes(tmp_path, monkeypatch):
    monkeypatch.setattr(posegen.io.artefact, "__version__", VERSION)
    monkeypatch.chdir(tmp_path)
    for argv, code in PIPELINE:
        assert main([*argv, "-q"] if argv[0] != "check" else argv) == code, argv
    written = digest_tree(tmp_path)
    if os.environ.get("POSEGEN_UPDATE_MANIFEST"):
        MANIFEST.parent.mkdir(parents=True, exist_ok=True)
        MANIFEST.write_text(json.dumps(written, indent=1, sort_keys=True) + "\n")
        pytest.skip(f"manifest rewritten: {MANIFEST}")
    expected = json.loads(MANIFEST.read_text())
    assert sorted(written) == sorted(expected), "another set of files"
    changed = sorted(name for name in expected if written[name] != expected[name])
    assert not changed, f"bytes changed: {changed}"
