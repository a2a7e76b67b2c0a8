"""The calibration report: one self-contained page with every section, rebuilt from the folder alone."""

import html
import re

import numpy as np
import pytest

from posegen.calibrate import DeliverableKind, read_calibration, read_summary
from posegen.errors import InputError
from posegen.view import REPORT_FILE, write_report
from posegen.view.report_figures import strongest_correlations


@pytest.fixture(scope="module")
def report(calibration_folder):
    path = write_report(calibration_folder.path)
    return path, path.read_text()


def test_the_report_is_written_beside_calibration_yaml_with_every_section(calibration_folder, report):
    path, text = report
    assert path == calibration_folder.path / REPORT_FILE
    titles = (
        "What to load: the files written",
        "Summary",
        "Every file's errors, as a stack loading it sees them",
        "Every contact",
        "Model selection: repeated grouped cross-validation",
        "The interpretable model's parameters",
        "Conditioning and correlation of the regressor",
        "Rows left out",
        "3D: nominal (grey) and calibrated (blue) robot at each contact",
    )
    assert re.findall(r"<h2>(.*?)</h2>", html.unescape(text)) == list(titles)  # the files first
    images = re.findall(r"<img src=\"data:image/png;base64,", text)
    assert len(images) == 4  # residuals, their spread, singular values, correlation


def test_what_to_load_names_each_file_with_its_predicted_and_held_out_error(calibration_folder, report):
    _, text = report
    section = text.split("<h2>What to load: the files written</h2>")[1].split("<h2>")[0]
    deliverables = calibration_folder.calibration.deliverables
    summary = read_summary(calibration_folder.path / "calibration.yaml")
    assert "calibrated.urdf, calibrated.yaml, offsets.yaml" in section
    assert deliverables.urdf.candidate.name in section and "left: predicted held-out (grouped CV)" in section
    rows = [r for r in re.findall(r"<tr>(.*?)</tr>", section) if "calibrated.urdf, calibrated.yaml" in r]
    held = summary.deliverables[DeliverableKind.URDF].figures.held_out["left"]
    [row] = [r for r in rows if f"left: held-out, {held.contacts} contacts" in r]
    assert f"{held.mean_abs.z_mm:.2f} / {held.mean_abs.roll_deg:.2f} / {held.mean_abs.pitch_deg:.2f}" in row
    z = deliverables.urdf.result.chains["left"].mean_abs[0] * 1e3
    assert f"{z:.2f} / " in section


def test_every_identified_parameter_is_listed_with_its_std(calibration_folder, report):
    _, text = report
    section = html.unescape(text).split("<h2>The interpretable model's parameters</h2>")[1].split("<h2>")[0]
    rows = re.findall(r"<tr>(.*?)</tr>", section)
    parameters = read_calibration(calibration_folder.path).report["parameters"]
    assert len(rows) == len(parameters) + 1
    first = re.findall(r"<td[^>]*>(.*?)</td>", rows[1])
    expected = parameters[0]  # shown in its own unit (mm, deg or rad/kNm)
    assert first[0] == expected["name"] and float(first[4]) == pytest.approx(expected["std"], abs=1e-4)


def test_conditioning_figures_are_the_posterior_ones(calibration_folder, report):
    _, text = report
    posterior = read_calibration(calibration_folder.path).posterior
    assert f"<b>{posterior.condition:.4g}</b>" in text
    section = text.split("<h2>Model selection: repeated grouped cross-validation</h2>")[1].split("<h2>")[0]
    assert "offsets_legs" in section and "score +- SE" in section
    pairs = strongest_correlations(posterior)
    rho = posterior.correlation
    off = np.abs(rho[np.triu_indices(len(rho), k=1)])
    assert abs(pairs[0][2]) == pytest.approx(off.max())
    assert [abs(p[2]) for p in pairs] == sorted((abs(p[2]) for p in pairs), reverse=True)


def test_the_3d_overlay_is_inlined_and_the_page_fetches_nothing(report):
    _, text = report
    frame = re.search(r'<iframe title="3D view" srcdoc="([^"]*)"', text)
    assert frame and "window.__VISER_EMBED_DATA__=" in html.unescape(frame.group(1))
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)


def test_a_report_needs_a_calibration_folder(tmp_path):
    with pytest.raises(InputError, match="not a calibration folder"):
        write_report(tmp_path / "nothing")


def test_figures_drawn_on_workers_make_the_same_page(calibration_folder, report, tmp_path):
    import shutil

    from posegen.parallel import ProcessBackend
    from posegen.view import write_report_into

    copy = tmp_path / "calibration"
    shutil.copytree(calibration_folder.path, copy)
    with ProcessBackend(2) as backend:
        path = write_report_into(copy, shown_as=calibration_folder.path, backend=backend)
    assert path.read_bytes() == report[0].read_bytes()  # the figures, the 3D page and the order of each
