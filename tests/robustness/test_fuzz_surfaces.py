"""Fuzzing the surfaces issue 33 hardened: robot init, the session index, the deliverables, bags over folders.

``robot init`` runs on the synthetic humanoid (URDF and MJCF) with one element's
attribute set to a bad value or the element removed; the session index is a valid one
mutated node by node, read by :func:`posegen.session.read_index` and by ``session
status``; the deliverable readers (``read_compliance``, ``read_offsets``) read mutated
files and the functions (``compensate``, ``uncompensate``, ``apply_offsets``) take any
value; ``export --bag`` and ``simulate --bag`` write over a folder that is posegen's
bag, a recording, or either with a user's file in it or its metadata damaged.

Every run must end in a result or one ``posegen: error:`` line (exit 2) with nothing
else on the terminal (the native parsers' output is captured at the file descriptors),
leave every input's bytes (the URDF's meshes included) as they were, and replace a bag
folder only if posegen wrote all of it. The kills of ``session add`` are in
``tests/session/test_journal.py``; ``make fuzz`` runs both with the ``fuzz`` profile.
"""

from __future__ import annotations

import hashlib
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from posegen.calibrate import JointOffset, apply_offsets, compensate, read_compliance, read_offsets, uncompensate
from posegen.calibrate.compliance import COMPLIANCE_FORMAT, Compliance, ComplianceGroup
from posegen.cli import main
from posegen.errors import PosegenError
from posegen.io import check_bag_destination
from posegen.session import SessionIndex, read_index
from posegen.session.index import index_to_dict
from tests.draft.humanoid_mjcf import humanoid_mjcf
from tests.draft.humanoid_urdf import humanoid_urdf
from tests.robustness.strategies import NUMBERS, SCALARS, damaged, mutated
from tests.session.test_index import an_index

SLOW = max(settings().max_examples // 80, 3)  # 1-8 s an example (a draft that loads): 3 in make test, 10 in make fuzz
FAST = max(settings().max_examples // 8, 10)  # < 0.1 s an example: 10 in make test, 100 in make fuzz
FIXTURES = [*settings().suppress_health_check, HealthCheck.function_scoped_fixture]  # capfd: read per run
ATTRIBUTE_VALUES = st.one_of(
    NUMBERS.map(repr),
    st.sampled_from(["", "nan", "0 0 0", "0 nan 0", "1e39 0 0", "-1", "abc", "1 2", "nothing", "pelvis", "ball"]),
    st.text(max_size=10).map(lambda t: re.sub(r"[\x00-\x1f\"<>&]", "", t)),
)


def tree(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.rglob("*") if
            p.is_file()}  # fmt: skip


def one_line_or_nothing(code: int, out: str, err: str) -> None:
    assert code in (0, 2), (code, out, err)
    if code == 2:
        lines = [line for line in (out + err).splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("posegen: error: "), out + err
    assert "Traceback" not in err


def edit_xml(text: str, data: st.DataObject) -> str:
    """One element of ``text``: an attribute set to a bad value, or the element removed."""
    elements = list(re.finditer(r"<(\w+)((?:\s+[\w:]+=\"[^\"]*\")*)\s*/?>", text))
    element = data.draw(st.sampled_from(elements))
    attributes = re.findall(r"([\w:]+)=\"[^\"]*\"", element.group(2))
    if not attributes or data.draw(st.integers(0, 5)) == 0:
        if element.group(0).endswith("/>"):
            return text[: element.start()] + text[element.end() :]
        return text
    name = data.draw(st.sampled_from(attributes))
    value = data.draw(ATTRIBUTE_VALUES)
    start, end = element.span(2)
    edited = re.sub(rf'(\s{name}=)"[^"]*"', lambda m: f'{m.group(1)}"{value}"', element.group(2), count=1)
    return text[:start] + edited + text[end:]


@pytest.fixture(scope="module")
def descriptions(tmp_path_factory) -> dict[str, Path]:
    return {
        "urdf": humanoid_urdf(tmp_path_factory.mktemp("urdf")),
        "mjcf": humanoid_mjcf(tmp_path_factory.mktemp("mjcf")),
    }


@settings(max_examples=SLOW, suppress_health_check=FIXTURES)
@given(kind=st.sampled_from(["urdf", "mjcf"]), data=st.data())
def test_robot_init_on_edited_descriptions(descriptions, kind, data, capfd):
    source = descriptions[kind]
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "robot"
        shutil.copytree(source.parent, folder)
        path = folder / source.name
        path.write_text(edit_xml(path.read_text(), data))
        output = data.draw(st.sampled_from(["config.yaml", source.name, "meshes/foot.stl", "meshes", "."]))
        before = tree(folder)
        capfd.readouterr()
        code = main(["robot", "init", str(path), "-o", str(folder / output), "--samples", "2", "-q"])
        out, err = capfd.readouterr()
        one_line_or_nothing(code, out, err)
        after = tree(folder)
        assert {k: v for k, v in after.items() if k in before} == before  # no input (a mesh included) changed
        if code == 2:
            assert after == before  # nothing written


@pytest.fixture(scope="module")
def session_index(tmp_path_factory) -> tuple[Path, dict[str, Any]]:
    folder = tmp_path_factory.mktemp("session")
    index = an_index(folder)
    assert isinstance(index, SessionIndex)
    return folder, index_to_dict(index)


@settings(max_examples=FAST, suppress_health_check=FIXTURES)
@given(data=st.data())
def test_the_session_index_reader_and_status_on_mutated_indexes(session_index, data, capfd):
    folder, document = session_index
    with tempfile.TemporaryDirectory() as scratch:
        copy = Path(scratch) / "session"
        shutil.copytree(folder, copy)
        content = yaml.safe_dump(data.draw(mutated(document)), sort_keys=False)
        if data.draw(st.booleans()):
            content = data.draw(damaged(content)).decode(errors="replace")
        (copy / "session.yaml").write_text(content)
        try:
            read_index(copy)
        except PosegenError as exc:
            assert len(str(exc).splitlines()) == 1 and "KeyError" not in str(exc)
        capfd.readouterr()
        code = main(["session", "status", str(copy), "--plot", str(Path(scratch) / "status.png")])
        out, err = capfd.readouterr()
        assert code in (0, 2), err
        one_line_or_nothing(code, "" if code == 0 else out, err)


def compliance_document(joint: str) -> dict[str, Any]:
    group = {"joints": [joint], "compliance_rad_per_nm": 1e-4, "std_rad_per_knm": 0.01}
    return {"format": COMPLIANCE_FORMAT, "format_version": 1, "groups": {"hips": group}, "sole_frames": []}


def offsets_document(joint: str) -> dict[str, Any]:
    placement = dict.fromkeys(("x_m", "y_m", "z_m", "roll_rad", "pitch_rad", "yaw_rad"), 0.001)
    return {
        "format": "posegen-offsets",
        "format_version": 1,
        "joints": {joint: {"angle_offset_rad": 0.01, "placement": placement}},
    }


@settings(max_examples=FAST)
@given(kind=st.sampled_from(["compliance", "offsets"]), data=st.data())
def test_deliverable_readers_on_mutated_files(scene, kind, data):
    joint = scene.joint_names[2]
    document = compliance_document(joint) if kind == "compliance" else offsets_document(joint)
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / f"{kind}.yaml"
        path.write_text(yaml.safe_dump(data.draw(mutated(document)), sort_keys=False))
        try:
            read = read_compliance(path) if kind == "compliance" else read_offsets(path, scene.joint_names)
        except PosegenError as exc:
            assert len(str(exc).splitlines()) == 1
            return
    if kind == "compliance":
        assert all(0.0 <= g.compliance_rad_per_nm <= 1.0 for g in read.groups)
        compensate(scene, np.tile(scene.reference, (2, 1)), read)
    else:
        apply_offsets(scene.files.urdf.read_text(), read)


ARRAYS = st.one_of(
    st.builds(lambda v, n: np.full((1, n), v), NUMBERS, st.integers(0, 40)),
    st.builds(lambda kind: np.zeros((2, 32)).astype(kind), st.sampled_from(["complex128", "bool", "int8", "U3", "O"])),
    SCALARS,
    st.lists(st.lists(NUMBERS, max_size=3), max_size=3),
)


@settings(max_examples=FAST)
@given(
    function=st.sampled_from([compensate, uncompensate]),
    joints=ARRAYS,
    compliance=st.one_of(NUMBERS.map(lambda c: Compliance((ComplianceGroup("g", ("leg_left_3_joint",), c),), ())),
                         SCALARS),
    urdf=st.one_of(SCALARS, st.sampled_from(["<robot/>", "<mujoco/>", "<robot><joint name='j'><origin xyz='a'/>"
                                                                     "</joint></robot>"])),
    placement=st.one_of(st.tuples(*[NUMBERS] * 6), st.lists(SCALARS, max_size=7)),
)  # fmt: skip
def test_deliverable_functions_on_any_value(scene, function, joints, compliance, urdf, placement):
    for call in (
        lambda: function(scene, joints, compliance),
        lambda: apply_offsets(urdf, [JointOffset("leg_left_1_joint", 0.0, placement)]),
        lambda: apply_offsets(scene.files.urdf.read_text(), [JointOffset("leg_left_1_joint", 0.0, placement)]),
    ):
        try:
            result = call()
        except PosegenError as exc:
            assert len(str(exc).splitlines()) == 1
            continue
        if isinstance(result, np.ndarray):
            assert np.all(np.isfinite(result))
        else:
            assert "nan" not in result and "e+" not in result


@pytest.fixture(scope="module")
def posegen_bag(route_file, tmp_path_factory) -> Path:
    bag = tmp_path_factory.mktemp("exported") / "bag"
    assert main(["export", str(route_file), "--bag", str(bag), "-q"]) == 0
    return bag


FOLDER_EDITS = st.sampled_from(["none", "notes", "recording", "metadata", "storage_dir", "empty", "file", "hidden"])


def edit_folder(bag: Path, edit: str, data: st.DataObject) -> None:
    """A bag folder as a user may have it: posegen's, with a note, a recording, damaged, or not a bag."""
    meta = bag / "metadata.yaml"
    if edit == "notes":
        (bag / data.draw(st.sampled_from(["notes.txt", "other.mcap", "truth.yaml.bak"]))).write_text("mine")
    elif edit == "recording":
        info = yaml.safe_load(meta.read_text())
        info["rosbag2_bagfile_information"].pop("custom_data", None)
        meta.write_text(yaml.safe_dump(info))
    elif edit == "metadata":
        meta.write_bytes(data.draw(damaged(meta.read_text())))
    elif edit == "storage_dir":
        storage = next(bag.glob("*.mcap"))
        storage.unlink()
        storage.mkdir()
    elif edit == "empty":
        shutil.rmtree(bag)
        bag.mkdir()
    elif edit == "file":
        shutil.rmtree(bag)
        bag.write_text("mine")
    elif edit == "hidden":
        (bag / ".notes").write_text("mine")


@settings(max_examples=SLOW, suppress_health_check=FIXTURES)
@given(edit=FOLDER_EDITS, command=st.sampled_from(["export", "simulate"]), data=st.data())
@example(edit="storage_dir", command="export", data=None)  # corpus: a folder named as its storage was replaced
def test_bags_over_existing_folders(posegen_bag, route_file, edit, command, data, capfd):
    with tempfile.TemporaryDirectory() as scratch:
        bag = Path(scratch) / "bag"
        shutil.copytree(posegen_bag, bag)
        edit_folder(bag, edit, data)
        before = tree(bag) if bag.is_dir() else {"": hashlib.sha256(bag.read_bytes()).hexdigest()}
        try:
            check_bag_destination(bag)
            replaceable = True
        except PosegenError:
            replaceable = False
        assert replaceable == (edit in ("none", "empty")), edit
        argv = [command, str(route_file), "--bag", str(bag), "-q", *(["--seed", "1"] if command == "simulate" else [])]
        capfd.readouterr()
        code = main(argv)
        out, err = capfd.readouterr()
        one_line_or_nothing(code, out, err)
        assert code == (0 if replaceable else 2), err
        if not replaceable:
            after = tree(bag) if bag.is_dir() else {"": hashlib.sha256(bag.read_bytes()).hexdigest()}
            assert after == before
