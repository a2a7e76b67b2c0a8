"""``calibration.yaml`` as an object: its typed fields are the calibration's, and it is written back to the byte."""

import numpy as np
import pytest
import yaml

from posegen.calibrate import (
    DeliverableKind,
    file_lines,
    format_table,
    load_line,
    read_summary,
    summary_from_dict,
    write_summary,
)
from posegen.errors import InputError
from posegen.io import write_yaml


@pytest.fixture(scope="module")
def summary(calibration_folder):
    return read_summary(calibration_folder.path / "calibration.yaml")


def test_the_typed_fields_are_the_calibration_s(calibration_folder, summary):
    calibration, held_out = calibration_folder.calibration, calibration_folder.held_out
    chosen = calibration.selection.chosen
    assert (summary.model.candidate, summary.model.prior_scale) == (chosen.candidate, chosen.prior_scale)
    assert summary.chosen.free_parameters == chosen.free and summary.chosen.score == round(chosen.score, 2)
    assert summary.stability == round(calibration.selection.stability, 3)
    assert set(summary.predicted_error) == set(chosen.chains)
    for chain, error in summary.predicted_error.items():
        assert error.mean_abs.z_mm == pytest.approx(chosen.chains[chain].mean_abs[0] * 1e3, abs=5e-4)
    assert summary.deliverables[DeliverableKind.URDF].files[0] == "calibrated.urdf"
    assert (DeliverableKind.COMPENSATED in summary.deliverables) == (calibration.deliverables.compensated is not None)
    for figures in (summary.nominal, *(d.figures for d in summary.deliverables.values()), summary.model_figures):
        assert figures.training["all"].contacts == len(calibration.kept)
        assert figures.held_out["all"].contacts == len(held_out)
        assert set(figures.held_out) == {"all", *held_out.chains}
    assert len(summary.left_out) == len(calibration.flags)
    assert summary.contact_noise.z_mm == pytest.approx(calibration.after.noise.contact[0] * 1e3, abs=5e-5)
    assert summary.provenance["seed"] == 3


def test_the_summary_is_written_back_to_the_byte(calibration_folder, summary, tmp_path):
    write_summary(tmp_path / "calibration.yaml", summary)
    original = (calibration_folder.path / "calibration.yaml").read_bytes()
    assert (tmp_path / "calibration.yaml").read_bytes() == original
    assert summary_from_dict(yaml.safe_load(original)) == summary


def test_the_table_and_the_load_line_render_the_summary(summary):
    table = format_table(summary).splitlines()
    files = 1 + len(summary.deliverables)  # the nominal URDF and each file written
    chains = len(summary.nominal.training) - 1 + len(summary.nominal.held_out) - 1
    assert len(table) == 2 + files * chains
    row = next(line for line in table if line.startswith("held-out") and " calibrated.urdf " in line)
    chain = row.split()[1]
    shown = summary.deliverables[DeliverableKind.URDF].figures.held_out[chain]
    assert float(row.split()[4]) == round(shown.mean_abs.z_mm, 2) and float(row.split()[5]) == round(shown.rms.z_mm, 2)
    lines = file_lines(summary)
    assert lines[0].startswith("  calibrated.urdf (any stack; offsets_legs x5)")
    assert f"{chain} {shown.mean_abs.z_mm:.2f} / " in lines[2] and lines[2].lstrip().startswith("held-out")
    line = load_line(summary)
    urdf = summary.deliverables[DeliverableKind.URDF]
    assert line.startswith(f"load: {urdf.files[0]} for any stack")
    for chain, error in urdf.predicted_error.items():
        assert f"{chain} {error.mean_abs.z_mm:.2f} mm" in line


def test_a_point_contact_s_roll_and_pitch_are_none(calibration_folder, tmp_path):
    data = yaml.safe_load((calibration_folder.path / "calibration.yaml").read_text())
    chain = next(iter(data["model"]["predicted_error"]))
    data["model"]["predicted_error"][chain]["mean_abs"] |= {"roll_deg": None, "pitch_deg": None}
    write_yaml(tmp_path / "calibration.yaml", data)
    error = read_summary(tmp_path / "calibration.yaml").predicted_error[chain]
    assert error.mean_abs.roll_deg is None and error.mean_abs.pitch_deg is None
    assert np.isfinite(error.mean_abs.z_mm)


def test_a_nominal_urdf_no_cross_validation_scored_is_read_and_said_so(calibration_folder, tmp_path):
    data = yaml.safe_load((calibration_folder.path / "calibration.yaml").read_text())
    nominal = data["deliverables"]["nominal_urdf"]  # an implausible fit: score inf, its errors written as null
    nominal |= {"score": float("inf"), "se": float("inf")}
    for error in nominal["predicted_error"].values():
        for key in ("mean_abs", "rms"):
            error[key] = dict.fromkeys(error[key])
    write_yaml(tmp_path / "calibration.yaml", data)
    summary = read_summary(tmp_path / "calibration.yaml")
    assert all(np.isnan(e.mean_abs.z_mm) for e in summary.nominal.predicted_error.values())
    lines = file_lines(summary)
    at = lines.index("  the nominal URDF (for comparison; not written):")
    assert lines[at + 1] == "    predicted held-out (grouped CV)  not scored: its fit on every row is implausible"


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.pop("model"), "not a posegen calibration"),
        (lambda d: d["model_selection"]["stability"].pop("share_of_seeds"), "not a posegen calibration"),
        (lambda d: d["deliverables"]["urdf"].update(files=None), "not a posegen calibration"),
        (lambda d: d["model"]["predicted_error"].update(left={"mean_abs": {}}), "not a posegen calibration"),
        (lambda d: d["deliverables"]["urdf"]["held_out"].update(left={"contacts": 3}), "not a posegen calibration"),
        (lambda d: d["deliverables"].pop("nominal_urdf"), "not a posegen calibration"),
        (lambda d: d.update(format_version=2), "unsupported format_version"),
    ],
)
def test_a_malformed_calibration_yaml_is_refused_in_one_line(calibration_folder, tmp_path, edit, message):
    data = yaml.safe_load((calibration_folder.path / "calibration.yaml").read_text())
    edit(data)
    write_yaml(tmp_path / "calibration.yaml", data)
    with pytest.raises(InputError, match=message) as refused:
        read_summary(tmp_path / "calibration.yaml")
    assert "\n" not in str(refused.value)
