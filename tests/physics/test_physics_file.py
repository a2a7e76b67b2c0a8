"""physics.yaml: written and read back as the same object; another file is refused in one line."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from posegen.errors import InputError
from posegen.io import write_yaml
from posegen.physics import PhysicsReport, PhysicsSummary, SegmentFigures, UnwantedContact, read_physics, write_physics


def _report() -> PhysicsReport:
    segment = SegmentFigures(
        index=0,
        type="hold",
        chain="left",
        label="posture 3 (pool 17)",
        start_s=1.0,
        end_s=2.0,
        zmp_margin_min_m=0.031,
        slip_max_mm=(0.5, 0.25),
        pelvis_deviation_max_m=0.004,
        torque_ratio_max=0.8,
        torque_joint="arm_left_2_joint",
        force_min_n=25.0,
        force_max_n=35.0,
        unwanted=(UnwantedContact(1.5, "arm_left_4_link", "table", 0.5),),
    )
    summary = PhysicsSummary(True, None, 3.0, 1, 1, (10.0, 60.0), 0.031, 0.5, 0.004, 0.8, "arm_left_2_joint", 1)
    return PhysicsReport({"seed": 3}, summary, (segment,))


def test_a_report_reads_back_as_written(tmp_path: Path) -> None:
    write_physics(tmp_path / "physics.yaml", _report())
    assert read_physics(tmp_path / "physics.yaml") == _report()


def test_a_figure_that_could_not_be_measured_is_null_and_nan(tmp_path: Path) -> None:
    report = _report()
    broken = PhysicsReport(
        report.provenance,
        report.summary,
        (report.segments[0].__class__(**{**report.segments[0].__dict__, "zmp_margin_min_m": math.nan}),),
    )
    write_physics(tmp_path / "physics.yaml", broken)
    assert "zmp_margin_min_m: null" in (tmp_path / "physics.yaml").read_text()
    assert math.isnan(read_physics(tmp_path / "physics.yaml").segments[0].zmp_margin_min_m)


def test_another_file_is_refused(tmp_path: Path) -> None:
    write_yaml(tmp_path / "other.yaml", {"format": "posegen-route", "format_version": 2})
    with pytest.raises(InputError, match="not a posegen-physics file"):
        read_physics(tmp_path / "other.yaml")
    write_yaml(tmp_path / "broken.yaml", {"format": "posegen-physics", "format_version": 1, "summary": {}})
    with pytest.raises(InputError, match="malformed"):
        read_physics(tmp_path / "broken.yaml")
