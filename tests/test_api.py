"""The public API at ``posegen.``: every name documented with an example and fully typed, loaded lazily,
with the command line's defaults; the subpackages say they are internal."""

from __future__ import annotations

import argparse
import inspect
import subprocess
import sys
import typing
from pathlib import Path

import pytest

import posegen
import posegen.api
from posegen.errors import ArgumentError

ROOT = Path(__file__).resolve().parents[1]
PUBLIC = [name for name in posegen.__all__ if name != "__version__"]


def test_the_api_is_small_and_every_name_resolves():
    assert 15 <= len(PUBLIC) <= 30
    assert len(set(PUBLIC)) == len(PUBLIC)
    for name in PUBLIC:
        assert getattr(posegen, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        _ = posegen.not_a_name  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", PUBLIC)
def test_a_public_name_has_an_example_and_type_hints(name):
    obj = getattr(posegen, name)
    doc = inspect.getdoc(obj) or ""
    assert "Example:" in doc and ">>> " in doc.split("Example:")[1], f"{name}: no example in its docstring"
    if inspect.isfunction(obj):
        hints = typing.get_type_hints(obj)
        parameters = inspect.signature(obj).parameters
        missing = [p for p in parameters if p not in hints]
        assert not missing and "return" in hints, f"{name}: untyped {missing or 'return'}"


def test_the_api_names_its_own_functions_and_objects_in_help():
    text = inspect.getdoc(posegen) or ""
    assert all(name in text for name in PUBLIC), [name for name in PUBLIC if name not in text]


def test_import_posegen_loads_no_stage():
    """``import posegen`` stays light: the API (and the stages, placo, viser) load at first use."""
    code = "import sys, posegen; print(sorted(m for m in sys.modules if m.startswith('posegen')))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert loaded.stdout.strip() == "['posegen']"


@pytest.mark.parametrize(
    "package", ["pool", "select", "route", "calibrate", "session", "robot", "model", "io", "parallel", "view"]
)
def test_every_subpackage_says_it_is_internal(package):
    module = __import__(f"posegen.{package}", fromlist=["__doc__"])
    assert "Internal:" in (module.__doc__ or ""), f"posegen.{package}'s docstring does not mark it internal"


def _defaults(command: str) -> dict[str, object]:
    from posegen.cli.main import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    return {a.dest: a.default for a in sub._actions if a.default is not argparse.SUPPRESS}


@pytest.mark.parametrize(
    ("function", "command", "pairs"),
    [
        ("generate_pool", "pool", {"n": "n", "seed": "seed"}),
        ("plan_route", "route", {"seed": "seed", "csv": "csv"}),
        ("simulate_recording", "simulate", {"session": "session"}),
        ("measure", "measure", {"joint_topic": "joint_topic", "session": "session"}),
        ("export_route", "export", {"topic": "topic", "segments_topic": "segments_topic"}),
    ],
)
def test_the_api_defaults_are_the_command_lines(function, command, pairs):
    parameters = inspect.signature(getattr(posegen.api, function)).parameters
    defaults = _defaults(command)
    for api_name, flag in pairs.items():
        assert parameters[api_name].default == defaults[flag], (function, api_name)


def test_the_recording_rate_is_the_command_line_s_kinematic_one():
    """``simulate --rate`` defaults by mode (500 Hz recorded, 250 Hz with --physics); the API records kinematically.

    ``--joint-topic``, an option of ``--bag`` like ``--rate``, is None unless given; it then means the API's topic.
    """
    from posegen.cli.options import JOINT_STATES_TOPIC
    from posegen.cli.simulate import KINEMATIC_RATE_HZ

    parameters = inspect.signature(posegen.api.simulate_recording).parameters
    assert _defaults("simulate")["rate"] is None
    assert parameters["rate_hz"].default == KINEMATIC_RATE_HZ
    assert _defaults("simulate")["joint_topic"] is None  # an option of --bag: None tells it was not given
    assert parameters["joint_topic"].default == JOINT_STATES_TOPIC


def test_a_simulated_robot_has_the_command_lines_defaults():
    defaults = _defaults("simulate")
    robot = posegen.SimulatedRobot().options()
    for name in ("seed", "error_mm", "error_deg", "noise_deg", "contact_noise_mm", "contact_noise_deg"):
        assert robot[name] == defaults[name], name
    assert robot["compliance_rad_per_knm"] == defaults["compliance"]


def test_load_reads_each_artefact_as_its_object(example_pool, tmp_path):
    pool = posegen.load(ROOT / "plans" / "talos" / "pool.yaml")
    assert isinstance(pool, posegen.Pool) and len(pool.postures) == len(example_pool.postures)
    (tmp_path / "x.yaml").write_text("format: posegen-something\nformat_version: 2\n")
    with pytest.raises(posegen.PosegenError, match=r"x\.yaml"):
        posegen.load(tmp_path / "x.yaml")


def test_the_examples_call_only_public_names():
    """An example in a public docstring uses ``posegen.NAME`` only for names of the API (a typo fails here)."""
    import re

    docs = [inspect.getdoc(getattr(posegen, name)) or "" for name in PUBLIC] + [inspect.getdoc(posegen) or ""]
    called = {m for doc in docs for m in re.findall(r">>> .*?\bposegen\.(\w+)", doc)}
    called |= {m for doc in docs for m in re.findall(r"\.\.\. .*?\bposegen\.(\w+)", doc)}
    assert called and called <= set(PUBLIC), sorted(called - set(PUBLIC))


def test_one_path_is_a_list_of_one_and_never_its_letters(tmp_path):
    """``calibrate_robot("meas.yaml", ...)`` read the string letter by letter ("." was the folder: refused)."""
    missing = tmp_path / "recorded.yaml"
    with pytest.raises(posegen.PosegenError, match=r"measurement file not found: .*recorded\.yaml$"):
        posegen.calibrate_robot(str(missing), tmp_path / "out")
    with pytest.raises(posegen.PosegenError, match=r"measurement file not found: .*recorded\.yaml$"):
        posegen.calibrate_robot(missing, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    from posegen.calibrate.calibration import check_candidates

    settings = posegen.CalibrationSettings(candidates="offsets")  # type: ignore[arg-type]
    with pytest.raises(ArgumentError, match=r"^candidates must be a list of model names, got the string"):
        check_candidates(posegen.load_scene(), settings)  # was: unknown candidate models ['o', 'f', 'f', ...]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: posegen.load(None), r"^path must be a path \(str or pathlib\.Path\), got None"),
        (lambda: posegen.load_scene(3), r"^config must be a path"),
        (lambda: posegen.Scene("configs/talos_table.yaml"), r"^config must be a Config: Scene\(load_config\(path\)\)"),
        (
            lambda: posegen.check_pool(ROOT / "plans/talos/pool.yaml", workers=0),
            r"^workers must be a backend or an integer >= 1, got 0",
        ),
        (
            lambda: posegen.check_pool(ROOT / "plans/talos/pool.yaml", workers="2"),
            r"^workers must be a backend or an integer",
        ),
        (lambda: posegen.select_postures("p.yaml", "s.yaml", settings={"k": 40}), r"^settings must be a SelectionSet"),
        (lambda: posegen.simulate("p.yaml", "m.yaml", robot={"seed": 1}), r"^robot must be a SimulatedRobot"),
        (lambda: posegen.calibrate_robot(["m.yaml"], "o", settings={}), r"^settings must be a posegen\.CalibrationS"),
        (lambda: posegen.calibrate_robot([None], "o"), r"^measurements\[0\] must be a path"),
        (lambda: posegen.follow_up("p.yaml", "n.yaml", 5), r"^given must be a list of paths, got 5"),
        (lambda: posegen.describe_calibration(None), r"^summary must be a CalibrationSummary"),
        (lambda: posegen.write_view("s.yaml", None), r"^html must be a path"),
    ],
)
def test_an_argument_of_the_wrong_type_is_named(call, message):
    """Each was a bare AttributeError or TypeError from deep inside (a dict has no ``k``, a str no ``stance``)."""
    with pytest.raises(ArgumentError, match=message):
        call()
