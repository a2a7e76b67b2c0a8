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


def _with_frames(folder: Path) -> Path:
    """The fixture with MuJoCo ``<frame>`` elements: one in ``<worldbody>`` around the robot (with a
    ``childclass``), a turned one in the torso holding the head, and one nested in the head holding the camera."""
    path = humanoid_mjcf(folder)
    text = path.read_text()
    text = text.replace('<compiler angle="radian"/>', '<compiler angle="radian"/><default><default class="soft">'
                        '<geom friction="0.5"/></default></default>')  # fmt: skip
    text = text.replace(
        '<body name="pelvis"', '<frame pos="0.2 0.1 0" euler="0 0 0.4" childclass="soft"><body name="pelvis"'
    )
    text = text.replace("  </worldbody>", "  </frame></worldbody>")
    head, arms = text.index('<body name="head"'), text.index('<body name="l_upper_arm"')
    block = text[head:arms].rstrip()
    framed = block.replace('<body name="camera"', '<frame pos="0.01 0 0" quat="0.9 0 0.436 0"><body name="camera"')
    framed = framed[: framed.rindex("</body>")] + "</frame>" + framed[framed.rindex("</body>") :]
    text = (
        text[:head]
        + f'<frame name="mount" pos="0 0 0.05" euler="0.2 0 0.3">{framed}</frame>'
        + text[head + len(block) :]
    )
    text = text.replace('<body name="head" pos="0 0 0.45">', '<body name="head" pos="0 0 0.4">')
    path.write_text(text)
    return path


def _placed_as_mujoco(path: Path, folder: Path) -> tuple[list[str], object, object]:
    """The bodies MuJoCo names in ``path``, and MuJoCo's and the converted URDF's models (its root placed as MuJoCo's).

    Asserts that every body is where MuJoCo puts it at ``qpos0`` (1e-9 m, 1e-9 in rotation).
    """
    mujoco = pytest.importorskip("mujoco")
    import numpy as np
    import pinocchio as pin

    native = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(native)
    mujoco.mj_forward(native, data)
    urdf = folder / "robot.urdf"
    urdf.write_text(convert_mjcf(path).text)
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    root = mujoco.mj_name2id(native, mujoco.mjtObj.mjOBJ_BODY, "pelvis")
    q = pin.neutral(model)
    q[:3], q[3:7] = data.xpos[root], np.roll(data.xquat[root], -1)  # MuJoCo's (w, x, y, z) as (x, y, z, w)
    placed = model.createData()
    pin.framesForwardKinematics(model, placed, q)
    names = [mujoco.mj_id2name(native, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, native.nbody)]
    for b, name in enumerate(names, start=1):
        assert model.existFrame(name), name
        frame = placed.oMf[model.getFrameId(name)]
        assert np.allclose(frame.translation, data.xpos[b], atol=1e-9), name
        assert np.allclose(frame.rotation, data.xmat[b].reshape(3, 3), atol=1e-9), name
    return names, native, model


def test_bodies_in_frames_are_where_mujoco_puts_them(tmp_path):
    """pinocchio's MJCF parser skips a ``<frame>`` and every body in it: the head (4 kg) and its camera were lost."""
    path = _with_frames(tmp_path)
    names, native, model = _placed_as_mujoco(path, tmp_path)
    assert {"head", "camera"} <= set(names)
    camera = names.index("camera") + 1  # no <inertial>: MuJoCo's mass from its box
    expected = float(native.body_subtreemass[0] - native.body_mass[camera])  # the head's 4 kg among them
    assert sum(i.mass for i in model.inertias) == pytest.approx(expected, rel=1e-12)
    assert flattened_mjcf(path).find(".//frame") is None


def test_a_turn_about_an_axis_of_any_length_is_mujocos(tmp_path):
    """MuJoCo normalizes an ``axisangle``'s axis; pinocchio took "1 1 0 0.3" as it was (0.11 off at the forearm)."""
    path = humanoid_mjcf(tmp_path)
    text = path.read_text().replace(
        '<body name="r_forearm" pos="0 0 -0.25">', '<body name="r_forearm" pos="0 0 -0.25" axisangle="1 1 0 0.3">'
    )
    path.write_text(
        text.replace(
            '<body name="l_hand" pos="0 0 -0.25">', '<body name="l_hand" pos="0 0 -0.25" axisangle="0 0 -3 0.5">'
        )
    )
    names, _, _ = _placed_as_mujoco(path, tmp_path)
    assert {"r_forearm", "r_hand", "l_hand"} <= set(names)
