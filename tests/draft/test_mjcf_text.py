"""The MJCF text pinocchio is given: includes inlined (dm_control's layout), one asset section, absolute folders."""

from __future__ import annotations

from pathlib import Path

import pytest

from posegen.draft.mjcf import convert_mjcf
from posegen.draft.mjcf_text import flattened_mjcf
from posegen.errors import ConfigError
from tests.draft.humanoid_mjcf import humanoid_mjcf

SKYBOX = '<mujoco><asset><texture name="sky" type="skybox" builtin="gradient" width="8" height="8"/></asset></mujoco>'
MATERIALS = '<mujoco><asset><material name="self" rgba=".7 .5 .3 1"/></asset><include file="common/more.xml"/></mujoco>'
MORE = '<mujoco><asset><material name="other" rgba="0 0 1 1"/></asset></mujoco>'


def _dm_control_layout(folder: Path) -> Path:
    """The fixture as dm_control's suite writes its models: materials in included files, a skybox first."""
    path = humanoid_mjcf(folder)
    (folder / "common").mkdir()
    (folder / "common" / "skybox.xml").write_text(SKYBOX)
    (folder / "common" / "materials.xml").write_text(MATERIALS)  # itself including one, from the main file's folder
    (folder / "common" / "more.xml").write_text(MORE)
    text = path.read_text().replace(
        '<compiler angle="radian"/>',
        '<compiler angle="radian"/><include file="./common/skybox.xml"/><include file="./common/materials.xml"/>',
    )
    path.write_text(text.replace('<geom type="capsule"', '<geom material="self" type="capsule"'))
    return path


def test_includes_are_inlined_into_one_asset_section(tmp_path):
    path = _dm_control_layout(tmp_path)
    root = flattened_mjcf(path)
    assert not list(root.iter("include"))
    (asset,) = root.findall("asset")  # pinocchio reads the first asset section only
    assert [e.get("name") for e in asset] == ["sky", "self", "other"]
    (compiler,) = root.findall("compiler")
    assert compiler.get("angle") == "radian"
    assert compiler.get("meshdir") == compiler.get("texturedir") == str(tmp_path.resolve())  # readable from anywhere


def test_a_model_with_included_materials_converts_as_without(tmp_path):
    plain = convert_mjcf(humanoid_mjcf(tmp_path / "plain"))
    included = convert_mjcf(_dm_control_layout(tmp_path / "dm"))  # pinocchio alone: 'unordered_map::at'
    assert included.text == plain.text.replace("plain", "dm")


def test_relative_asset_folders_become_absolute(tmp_path):
    path = humanoid_mjcf(tmp_path)
    path.write_text(path.read_text().replace('<compiler angle="radian"/>', '<compiler angle="radian" meshdir="m"/>'))
    assert flattened_mjcf(path).find("compiler").get("meshdir") == str((tmp_path / "m").resolve())


@pytest.mark.parametrize(
    ("include", "message"),
    [
        ('<include file="none.xml"/>', r'robot\.xml: <include file="none\.xml"> not found beside it'),
        ('<include file="robot.xml"/>', r'robot\.xml: <include file="robot\.xml"> nests 16 deep'),
        ('<include file="bad.xml"/>', r"bad\.xml: not valid XML"),
    ],
)
def test_bad_includes_are_one_line(include, message, tmp_path):
    path = humanoid_mjcf(tmp_path)
    (tmp_path / "bad.xml").write_text("<mujoco>")
    path.write_text(path.read_text().replace("<worldbody>", include + "<worldbody>"))
    with pytest.raises(ConfigError, match=message) as error:
        flattened_mjcf(path)
    assert len(str(error.value).splitlines()) == 1
