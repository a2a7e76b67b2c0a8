"""No output may be, contain, lie inside or share a file with an input: one check before any work.

Each row runs a command whose output is one of its inputs, a file read with an input (a
header's ``.npz`` sidecar), a file inside an input folder (a recorded bag), or a folder
holding an input. It must fail with one ``posegen: error:`` line, exit 2, and leave every
file of its folder as it was.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from posegen.cli import main
from posegen.io import JointStates, Wrenches, load_pool, sidecars_of, write_pool, write_recording, write_yaml
from tests.conftest import CONFIG, EXAMPLE_POOL
from tests.robustness.test_cli_faults import assert_one_line_error, tree_state


@pytest.fixture(scope="module")
def originals(tmp_path_factory, route_file) -> Path:
    """A v2 pool, a route, a recorded bag, measurements and a config, to copy into each row's folder."""
    folder = tmp_path_factory.mktemp("originals")
    pool = load_pool(EXAMPLE_POOL)
    write_pool(folder / "pool.yaml", pool)
    shutil.copy(route_file, folder / "route.yaml")
    for sidecar in sidecars_of(route_file) or [route_file.with_suffix(".npz")]:
        shutil.copy(sidecar, folder / sidecar.name.replace(route_file.name, "route.yaml"))
    times = np.linspace(0.0, 1.0, 20)
    joints = JointStates(("j_a",), times, times[:, None])
    write_recording(
        folder / "bag", joints, "/joint_states", {"/ft": Wrenches(times, np.ones((20, 3)), np.zeros((20, 3)))}, {}
    )
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][:6]
    write_yaml(folder / "six.yaml", data)
    assert main(["simulate", str(folder / "six.yaml"), "-q", "-o", str(folder / "m.yaml")]) == 0
    shutil.copy(CONFIG, folder / "config.yaml")
    return folder


ROWS = {  # what: argv ({here}: the row's folder, holding copies of the originals), what the error says
    "route -o its pool": (["route", "{here}/pool.yaml", "-o", "{here}/pool.yaml"], "not overwriting"),
    "simulate -o its pool's sidecar": (["simulate", "{here}/pool.yaml", "-o", "{pool_npz}"], "not overwriting"),
    "simulate -o its pool": (["simulate", "{here}/pool.yaml", "-o", "{here}/pool.yaml"], "not overwriting"),
    "view --html its route's sidecar": (["view", "{here}/route.yaml", "--html", "{route_npz}"], "not overwriting"),
    "view --html its pool": (["view", "{here}/pool.yaml", "--html", "{here}/pool.yaml"], "not overwriting"),
    "measure -o a file of its bag": (["measure", "{here}/bag", "-o", "{here}/bag/metadata.yaml"], "inside the input"),
    "measure -o inside its bag": (["measure", "{here}/bag", "-o", "{here}/bag/m.yaml"], "inside the input"),
    "measure -o its route": (
        ["measure", "{here}/bag", "--route", "{here}/route.yaml", "-o", "{here}/route.yaml"],
        "not overwriting",
    ),
    "pool -o its config": (["pool", "--n", "2", "--config", "{here}/config.yaml", "-o", "{here}/config.yaml"], "not"),
    "select -o its pool": (["select", "{here}/pool.yaml", "--k", "3", "-o", "{here}/pool.yaml"], "not overwriting"),
    "select --given -o its measurements": (
        ["select", "{here}/pool.yaml", "--given", "{here}/m.yaml", "--k", "3", "-o", "{here}/m.yaml"],
        "not overwriting",
    ),
    "export --bag a folder holding its route": (["export", "{here}/route.yaml", "--bag", "{here}"], "holds the input"),
    "simulate --bag a folder holding its route": (
        ["simulate", "{here}/route.yaml", "--bag", "{here}"],
        "holds the input",
    ),
    "robot init -o its --srdf": (
        ["robot", "init", "talos", "--srdf", "{here}/config.yaml", "-o", "{here}/config.yaml"],
        "not overwriting",
    ),
    "calibrate -o a folder holding its measurements": (
        ["calibrate", "{here}/m.yaml", "-o", "{here}"],
        "holds the input",
    ),
    "calibrate -o a folder holding its held-out file": (
        ["calibrate", "{here}/m.yaml", "--validate", "{here}/cal/m2.yaml", "-o", "{here}/cal"],
        "holds the input",
    ),
}


@pytest.mark.parametrize("row", sorted(ROWS))
def test_an_output_that_is_an_input_is_refused(row, originals, tmp_path, capsys):
    here = tmp_path / "here"
    shutil.copytree(originals, here)
    (here / "cal").mkdir()
    shutil.copy(here / "m.yaml", here / "cal" / "m2.yaml")
    names = {
        "here": str(here),
        "pool_npz": str(sidecars_of(here / "pool.yaml")[0]),
        "route_npz": str((sidecars_of(here / "route.yaml") or [here / "route.npz"])[0]),
    }
    template, expect = ROWS[row]
    before = tree_state(tmp_path)
    code = main([a.format(**names) for a in template] + ["-q"])
    err = capsys.readouterr().err
    assert_one_line_error(code, err)
    assert expect in err, err
    assert tree_state(tmp_path) == before
