"""``export --bag`` and ``simulate --bag`` over an existing folder: a recording or a user's files are never replaced.

As ``calibrate`` refuses a folder it did not write, so do the bag writers (issue 33): a
rosbag2 without posegen's provenance (a real recording), or posegen's own bag holding a
file it did not write (a user's ``notes.txt``), stays as it was, with a one-line error.
"""

from __future__ import annotations

import shutil

import pytest
import yaml

from posegen.cli import main
from tests.cli.test_cli import assert_one_line_error, run


@pytest.fixture(scope="module")
def exported(route_file, tmp_path_factory):
    bag = tmp_path_factory.mktemp("exported") / "bag"
    assert main(["export", str(route_file), "--bag", str(bag)]) == 0
    return bag


def _recording(bag, folder):
    """A copy of ``bag`` as a real recording would be: no posegen provenance, a user's notes."""
    copy = folder / "recording"
    shutil.copytree(bag, copy)
    info = yaml.safe_load((copy / "metadata.yaml").read_text())
    info["rosbag2_bagfile_information"].pop("custom_data", None)
    (copy / "metadata.yaml").write_text(yaml.safe_dump(info))
    (copy / "notes.txt").write_text("table 2, left arm only\n")
    return copy


@pytest.mark.parametrize("command", ["export", "simulate"])
@pytest.mark.parametrize("kind", ["recording", "notes"])
def test_an_existing_folder_posegen_did_not_write_is_kept(command, kind, exported, route_file, tmp_path, capsys):
    if kind == "recording":
        target = _recording(exported, tmp_path)
    else:
        target = tmp_path / "ours"
        shutil.copytree(exported, target)
        (target / "notes.txt").write_text("mine\n")
    before = {p.name: p.read_bytes() for p in target.iterdir()}
    argv = [command, str(route_file), "--bag", str(target), *(["--seed", "1"] if command == "simulate" else [])]
    code, _, err = run(argv, capsys)
    assert code == 2
    assert_one_line_error(err)
    assert "posegen did not write" in err, err
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before


def test_posegen_s_own_bag_is_replaced(exported, route_file, tmp_path, capsys):
    target = tmp_path / "ours"
    shutil.copytree(exported, target)
    code, _, err = run(["simulate", str(route_file), "--bag", str(target), "--seed", "1"], capsys)
    assert code == 0, err
    assert sorted(p.name for p in target.iterdir()) == ["metadata.yaml", "ours.mcap", "truth.yaml"]
