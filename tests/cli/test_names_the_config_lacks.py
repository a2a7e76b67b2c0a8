"""Names the robot or the config lacks, and a sidecar's name for an output: refused, not accepted silently (issue 33).

``export`` reads a route as ``check`` does (a joint the robot lacks, a hold on a chain
the config lacks); ``check`` and ``simulate`` refuse a posture at a spot the config lacks;
``pool -o p.npz`` is refused (a ``.npz`` is the arrays beside a header).
"""

from __future__ import annotations

import pytest
import yaml

from posegen.io import load_pool, sidecars_of, write_yaml
from tests.cli.test_cli import assert_one_line_error, run
from tests.conftest import EXAMPLE_POOL


def _route_copy(route_file, folder, edit):
    header = yaml.safe_load(route_file.read_text())
    edit(header)
    for sidecar in sidecars_of(route_file):
        (folder / sidecar.name).write_bytes(sidecar.read_bytes())
    path = folder / "route.yaml"
    path.write_text(yaml.safe_dump(header, sort_keys=False))
    return path


def _hold_on(chain):
    def edit(header):
        next(s for s in header["segments"] if s["type"] == "hold")["chain"] = chain

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda h: h["trajectory"]["joint_names"].__setitem__(0, "no_such_joint"), "'no_such_joint' is not a joint"),
        (_hold_on("tail"), "names chain 'tail'"),
    ],
)
def test_export_refuses_names_the_robot_lacks(edit, message, route_file, tmp_path, capsys):
    path = _route_copy(route_file, tmp_path, edit)
    code, _, err = run(["export", str(path), "--bag", str(tmp_path / "bag")], capsys)
    assert code == 2
    assert_one_line_error(err)
    assert message in err and not (tmp_path / "bag").exists()


@pytest.mark.parametrize("command", ["check", "simulate"])
def test_a_posture_at_a_spot_the_config_lacks_is_refused(command, tmp_path, capsys):
    data = load_pool(EXAMPLE_POOL).to_dict()
    data["postures"] = data["postures"][:2]
    data["postures"][1]["spot"] = "nowhere"
    path = tmp_path / "pool.yaml"
    write_yaml(path, data)
    argv = [command, str(path), *(["--seed", "1", "-o", str(tmp_path / "sim.yaml")] if command == "simulate" else [])]
    code, _, err = run(argv, capsys)
    assert code == 2
    assert_one_line_error(err)
    assert "unknown spot 'nowhere'" in err


def test_an_output_named_like_a_sidecar_is_refused(tmp_path, capsys):
    code, _, err = run(["pool", "--n", "2", "-o", str(tmp_path / "p.npz")], capsys)
    assert code == 2
    assert_one_line_error(err)
    assert "a .npz name is kept for the arrays" in err and not (tmp_path / "p.npz").exists()
