"""``posegen simulate ROUTE --physics --bag DIR``: a short free-standing contact run, read back as a recording."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

from posegen.calibrate import measure_bag
from posegen.cli import main
from posegen.extras import Extra
from posegen.io import RecordedBag, read_yaml
from posegen.physics import PHYSICS_FILE, read_physics
from tests.test_extras import assert_asks_for, posegen_without

NOMINAL = ["--seed", "7", "--error-mm", "0", "--error-deg", "0", "-q"]  # the URDF's robot: its route is for it


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def physics_bag(physics_route: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    bag = tmp_path_factory.mktemp("physics") / "bag"
    code, out, err = run(["simulate", str(physics_route), "--physics", "--bag", str(bag), *NOMINAL])
    assert code == 0, err
    assert "completed" in out and "holds within [10, 60] N: 2 of 2" in out
    return bag


def test_the_run_completes_and_its_contacts_are_held(physics_bag: Path) -> None:
    report = read_physics(physics_bag / PHYSICS_FILE)
    summary = report.summary
    assert summary.completed and summary.contacts == 2 and summary.holds_in_range == 2
    assert summary.unwanted_contacts == 0 and summary.pelvis_deviation_max_m < 0.02
    holds = [s for s in report.segments if s.type == "hold"]
    assert all(s.force_min_n >= 10.0 and s.force_max_n <= 60.0 for s in holds)
    provenance = report.provenance
    assert provenance["seed"] == 7 and provenance["robot_model_sha256"] and provenance["config"]
    assert provenance["simulation"]["physics"]["engine"].startswith("mujoco")


def test_measure_reads_the_physics_bag_as_a_recording(physics_bag: Path, physics_route: Path, tmp_path: Path) -> None:
    from tests.conftest import CONFIG

    truth = read_yaml(physics_bag / "truth.yaml", "posegen-truth")
    assert "provenance" in truth and truth["parameters"]
    recorded = RecordedBag(str(physics_bag))
    joints, wrenches, _ = recorded.read_and_hash("/joint_states", ["/left_wrist_ft", "/right_wrist_ft"])
    assert len(joints.names) == 32 and len(wrenches) == 2
    measured = measure_bag(
        str(physics_bag),
        str(tmp_path / "measured.yaml"),
        config_path=str(CONFIG),
        route_path=str(physics_route),
        session="sim",
        joint_topic="/joint_states",
        use_wrench=True,
    )
    assert len(measured.windows) == 2


def test_the_same_seed_writes_the_same_bytes(physics_bag: Path, physics_route: Path, tmp_path: Path) -> None:
    again = tmp_path / physics_bag.name  # the bag's folder name is written in it
    code, _, err = run(["simulate", str(physics_route), "--physics", "--bag", str(again), *NOMINAL])
    assert code == 0, err
    names = sorted(p.name for p in physics_bag.iterdir())
    assert names == sorted(p.name for p in again.iterdir())
    for name in names:
        assert (physics_bag / name).read_bytes() == (again / name).read_bytes(), name


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--glued-feet"], "--glued-feet is an option of --physics"),
        (["--physics"], "give --bag DIR"),
        (["--physics", "--bag", "X", "--contact-noise-mm", "1"], "--contact-noise-mm"),
        (["--physics", "--bag", "X", "--rate", "300"], "rate"),
        (["--physics", "--bag", "X", "--rate", "0.001"], "at least 50 Hz"),  # 500 Hz / 500 000 steps: too slow
    ],
)
def test_bad_physics_options_fail_in_one_line(physics_route: Path, tmp_path: Path, argv: list[str], says: str) -> None:
    argv = [a.replace("X", str(tmp_path / "bag")) for a in argv]
    code, _, err = run(["simulate", str(physics_route), *argv])
    assert code == 2 and says in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "bag").exists()


def test_physics_without_mujoco_names_the_physics_extra(physics_route: Path, tmp_path: Path) -> None:
    result = posegen_without(["mujoco"], ["simulate", str(physics_route), "--physics", "--bag", str(tmp_path / "bag")])
    assert_asks_for(result, Extra.PHYSICS)
    assert not (tmp_path / "bag").exists()
