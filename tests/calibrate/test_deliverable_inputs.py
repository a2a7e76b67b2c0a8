"""The deliverable functions and ``calibrate``'s inputs on what a user may hand them (issue 33).

Each refuses with a :class:`~posegen.errors.PosegenError` naming the parameter and the
cause: text for a URDF or an array, a negative compliance, a placement past any robot, a
measurement file given twice, a CSV cell that is not a number.
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from posegen.calibrate import JointOffset, apply_offsets, compensate, read_compliance, uncompensate
from posegen.calibrate.compliance import COMPLIANCE_FORMAT, Compliance, ComplianceGroup
from posegen.cli import main
from posegen.errors import InputError
from posegen.model.measurements import read_csv
from tests.cli.test_cli import assert_one_line_error
from tests.robustness.test_readers import csv_text


def _compliance(scene, value=1e-4):
    return Compliance((ComplianceGroup("hips", (scene.joint_names[2],), value),), ())


@pytest.mark.parametrize("function", [compensate, uncompensate])
def test_compensation_of_text_or_complex_arrays_is_refused(function, scene):
    for joints in (np.full((1, len(scene.joint_names)), "a"), np.zeros((1, len(scene.joint_names)), complex)):
        with pytest.raises(InputError, match="joints: expected real numbers"):
            function(scene, joints, _compliance(scene))


def test_a_negative_compliance_is_refused_by_the_reader_and_the_functions(scene, tmp_path):
    joints = np.tile(scene.reference, (2, 1))
    with pytest.raises(InputError, match="compliance_rad_per_nm must be a finite number from 0"):
        compensate(scene, joints, _compliance(scene, -1e-4))
    path = tmp_path / "compliance.yaml"
    group = {"joints": [scene.joint_names[2]], "compliance_rad_per_nm": -1e-4, "std_rad_per_knm": 0.0}
    path.write_text(yaml.safe_dump({"format": COMPLIANCE_FORMAT, "format_version": 1, "groups": {"hips": group},
                                    "sole_frames": []}))  # fmt: skip
    with pytest.raises(InputError, match=r"groups\.hips: compliance_rad_per_nm must be a finite number from 0"):
        read_compliance(path)


def test_apply_offsets_on_text_that_is_not_xml_is_an_input_error(scene):
    with pytest.raises(InputError, match=r"nominal_urdf: not a URDF \(not valid XML"):
        apply_offsets("robot: not xml", [])
    with pytest.raises(InputError, match=r"nominal_urdf: not a URDF \(its root element is <mujoco>"):
        apply_offsets("<mujoco/>", [])


@pytest.mark.parametrize(
    "placement",
    [(1e300, 0.0, 0.0, 0.0, 0.0, 0.0), (0.0, float("nan"), 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0, 1e9)],
)
def test_apply_offsets_never_writes_a_placement_no_robot_has(placement, scene):
    text = scene.files.urdf.read_text()
    offset = JointOffset(scene.joint_names[0], 0.0, placement)
    with pytest.raises(InputError, match=f"offsets: joint {scene.joint_names[0]}: "):
        apply_offsets(text, [offset])


def test_the_same_measurement_file_given_twice_is_refused(scene, tmp_path, capsys):
    csv = tmp_path / "recorded.csv"
    csv.write_text(csv_text(scene))
    (tmp_path / "link.csv").symlink_to(csv)
    for second in (csv, tmp_path / "link.csv"):
        assert main(["calibrate", f"{csv}@a", f"{second}@b", "-o", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err
        assert_one_line_error(err)
        assert "is given twice" in err and "would count twice" in err, err
    assert not (tmp_path / "out").exists()


def test_a_nan_cell_is_said_to_be_no_number_not_a_shifted_column(scene, tmp_path, caplog):
    rows = [line.split(",") for line in csv_text(scene).splitlines()]
    rows[1][7] = "nan"
    path = tmp_path / "recorded.csv"
    path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    read = read_csv(path, scene, "s")  # the row left out, and said
    assert len(read.contacts.chains) == len(rows) - 2
    assert f"{path}:2: {scene.joint_names[2]} = nan is not a finite number" in caplog.text
    assert "shifted column" not in caplog.text
