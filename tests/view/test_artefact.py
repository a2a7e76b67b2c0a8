"""Opening what ``posegen view`` shows: each kind recognised, bad input refused in one line."""

import dataclasses

import numpy as np
import pytest
import yaml

from posegen.errors import InputError
from posegen.io import read_route, write_route
from posegen.view import ArtefactKind, CalibrationArtefact, PosturesArtefact, RouteArtefact, open_artefact
from tests.conftest import EXAMPLE_POOL


def test_each_kind_is_recognised(selection_file, route_file, calibration_folder):
    pool = open_artefact(EXAMPLE_POOL)
    assert isinstance(pool, PosturesArtefact) and pool.kind == ArtefactKind.POOL and pool.pool is None
    selection = open_artefact(selection_file)
    assert isinstance(selection, PosturesArtefact) and selection.kind == ArtefactKind.SELECTION
    assert selection.pool is not None and len(selection.pool.postures) == len(pool.postures.postures)  # linked
    route = open_artefact(route_file)
    assert isinstance(route, RouteArtefact) and route.selection is not None and len(route.selection.postures) == 2
    calibration = open_artefact(calibration_folder.path)
    assert isinstance(calibration, CalibrationArtefact)
    assert open_artefact(calibration_folder.path / "calibration.yaml").path == calibration.path


def test_route_joints_are_put_in_the_scene_order(route_file, tmp_path):
    route = read_route(route_file)
    order = np.arange(len(route.joint_names))[::-1]
    shuffled = tmp_path / "route.yaml"
    reordered = {key: getattr(route, key)[:, order] for key in ("positions", "velocities", "accelerations")}
    names = tuple(route.joint_names[i] for i in order)
    write_route(shuffled, dataclasses.replace(route, joint_names=names, **reordered))
    assert np.array_equal(open_artefact(shuffled).positions, open_artefact(route_file).positions)


def one_line_error(path, match):
    with pytest.raises(InputError, match=match) as info:
        open_artefact(path)
    assert "\n" not in str(info.value)


def test_bad_input_is_refused_with_one_line(tmp_path, calibration_folder):
    one_line_error(tmp_path / "missing.yaml", "no such file or folder")
    config = tmp_path / "config.yaml"
    config.write_text("robot: {}\n")
    one_line_error(config, "not a pool, selection or route file, nor a calibration folder")
    broken = tmp_path / "broken.yaml"
    broken.write_text("format: [unclosed\n")
    one_line_error(broken, "not valid YAML")
    one_line_error(tmp_path, "calibration.yaml")  # a folder that holds no calibration


def test_an_artefact_of_another_robot_model_is_refused(tmp_path):
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["provenance"]["robot_model_sha256"] = "0" * 64
    other = tmp_path / "other.yaml"
    other.write_text(yaml.safe_dump(data))
    one_line_error(other, "another robot model")


def test_a_residual_of_a_chain_the_robot_lacks_is_refused(tmp_path, calibration_folder):
    """``residuals.csv`` edited by hand (a chain ``tail``): the calibration view failed on a KeyError."""
    import shutil

    folder = tmp_path / "calibration"
    shutil.copytree(calibration_folder.path, folder)
    residuals = folder / "residuals.csv"
    header, first, *rest = residuals.read_text().splitlines()
    cells = first.split(",")
    cells[header.split(",").index("chain")] = "tail"
    residuals.write_text("\n".join([header, ",".join(cells), *rest]) + "\n")
    with pytest.raises(InputError, match=r"a residual of chain 'tail'; the robot's chains: left, right"):
        open_artefact(folder)


@pytest.mark.parametrize("weight", ["heavy", float("nan")])
def test_a_selection_weight_that_is_no_finite_number_is_refused_as_every_reader_refuses_it(
    weight, selection_file, tmp_path
):
    """The view reads a selection with the one selection reader (it labelled a weight ``heavy`` as written)."""
    data = yaml.safe_load(selection_file.read_text())
    data["postures"][0]["weight"] = weight
    edited = tmp_path / "selected.yaml"
    edited.write_text(yaml.safe_dump(data))
    with pytest.raises(InputError, match=r"selected.yaml: posture 0: 'weight' must be a finite number, got"):
        open_artefact(edited)
