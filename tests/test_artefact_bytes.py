"""The whole pipeline's artefacts, at small sizes, are byte-identical to a committed manifest.

A refactoring must not change a byte of what posegen writes: this runs every stage from the
command line (robot init, pool, select, route, check, export, simulate, measure, calibrate, view) with the
version field held fixed, and compares the SHA-256 of every file written against
``tests/data/artefact_manifests/<fingerprint>.json``. The bytes are those of one machine's
floating point: another CPU's vector instructions (or another BLAS thread count) round the
last bits differently and the projections diverge from there, so each manifest is named by
:func:`tests.numeric_fingerprint.numeric_fingerprint`. On a machine with no manifest the
files written are still compared by name; the bytes are not, and the test says so (skipped).
A deliberate change of a format, or a new machine, (re)writes this machine's manifest:

    POSEGEN_UPDATE_MANIFEST=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python -m pytest tests/test_artefact_bytes.py
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import sys
from pathlib import Path

import pytest
from example_robot_data import robots_loader

import posegen.io.artefact
from posegen.cli.main import main
from tests.numeric_fingerprint import numeric_fingerprint

pytestmark = pytest.mark.slow  # seven minutes (every stage from the command line): `make slow`, a step of .ci/run

ROOT = Path(__file__).resolve().parents[1]
MANIFESTS = ROOT / "tests" / "data" / "artefact_manifests"  # <numeric fingerprint>.json, one per machine
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


def file_kinds(names: list[str]) -> list[str]:
    """The file names with the 12-hex-digit content hashes of companions (``m.yaml.<sha>.truth.yaml``) blanked."""
    return sorted(re.sub(r"\.[0-9a-f]{12}\.", ".<sha>.", name) for name in names)


def test_the_pipeline_writes_the_manifests_bytes(tmp_path, monkeypatch):
    monkeypatch.setattr(posegen.io.artefact, "__version__", VERSION)
    monkeypatch.chdir(tmp_path)
    for argv, code in PIPELINE:
        assert main([*argv, "-q"] if argv[0] != "check" else argv) == code, argv
    written = digest_tree(tmp_path)
    manifest = MANIFESTS / f"{numeric_fingerprint()}.json"  # the fingerprint of this process's floating point
    if os.environ.get("POSEGEN_UPDATE_MANIFEST"):
        MANIFESTS.mkdir(parents=True, exist_ok=True)
        manifest.write_text(json.dumps(written, indent=1, sort_keys=True) + "\n")
        pytest.skip(f"manifest rewritten: {manifest}")
    pinned = sorted(MANIFESTS.glob("*.json"))
    assert pinned, f"no manifest in {MANIFESTS}"
    for other in pinned:  # every machine writes the same files
        assert file_kinds(list(written)) == file_kinds(list(json.loads(other.read_text()))), other.name
    if not manifest.exists():
        pytest.skip(
            f"the same files, bytes not compared: no manifest for this machine's floating point ({manifest.name}; "
            f"pinned: {', '.join(p.name for p in pinned)}); POSEGEN_UPDATE_MANIFEST=1 writes one"
        )
    expected = json.loads(manifest.read_text())
    assert sorted(written) == sorted(expected), "another set of files"
    changed = sorted(name for name in expected if written[name] != expected[name])
    assert not changed, f"bytes changed: {changed}"
