"""``robot init`` on descriptions a new user gets wrong (issue 33): one line naming the file and the real cause.

Every case exits 2 with one line and nothing else on the terminal (the native parsers'
own output is kept off it, at the file-descriptor level), writes no draft, and never
overwrites what the draft reads: the URDF, the MJCF or a mesh.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from posegen.cli.main import main
from posegen.draft.mjcf import convert_mjcf
from posegen.errors import ConfigError
from tests.draft.humanoid_mjcf import humanoid_mjcf
from tests.draft.humanoid_urdf import humanoid_urdf


def _init(argv: list[str], capfd: pytest.CaptureFixture[str]) -> str:
    """Run ``robot init``; check it fails with one line (and nothing printed by native code); that line."""
    assert main(["robot", "init", *argv, "--samples", "2"]) == 2
    out, err = capfd.readouterr()
    lines = [line for line in (out + err).splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("posegen: error: "), out + err
    return lines[0]


def _first(pattern: str, replacement: str, text: str) -> str:
    edited = re.sub(pattern, replacement, text, count=1)
    assert edited != text
    return edited


URDF_CASES = [
    (lambda t: re.sub(r'<mass value="[^"]*"', '<mass value="0"', t), r"every link has zero mass"),
    (lambda t: _first(r'<axis xyz="[^"]*"', '<axis xyz="0 0 0"', t), r"joint 'l_hip_yaw': its axis is 0 0 0"),
    (  # scipy's least squares failed on the stance's reach ("residuals are not finite": a traceback)
        lambda t: _first(r'<axis xyz="[^"]*"', '<axis xyz="1e-300 0 0"', t),
        r"joint 'l_hip_yaw': its axis is 1e-300 0 0, of no length",
    ),
    (lambda t: _first(r'\.stl"/>', '.stl" scale="1 0 1"/>', t), r'<mesh scale="1 0 1">: a mesh scaled to nothing'),
    (
        lambda t: _first(r'ixx="[^"]*"', 'ixx="-1"', t),
        r'<inertia ixx="-1">: a moment of inertia cannot be negative',
    ),
    (lambda t: _first(r'<origin xyz="[^"]*"', '<origin xyz="0 nan 0"', t), r"xyz=\"0 nan 0\">: expected 3 finite"),
    (lambda t: t.replace('<parent link="pelvis"/>', '<parent link="nothing"/>', 1), r"parent link 'nothing' is not"),
    (lambda t: t.replace('<child link="l_thigh"/>', '<child link="pelvis"/>', 1), r"loop through link"),
    (lambda t: _first(r"<limit [^>]*/>", "", t), r"pinocchio cannot load it: .*does not specify limits"),
    (  # an unbounded wrist: the draft named it in reference_joints, a scene cannot hold a 2-value joint
        lambda t: _first(r'(<joint name="l_wrist") type="revolute"', r'\1 type="continuous"', t),
        r"joint 'l_wrist' is continuous: posegen plans joints of one angle or length between limits",
    ),
    (lambda t: _first(r'<joint name="neck" type="revolute"', '<joint name="neck" type="planar"', t), r"is planar"),
    (  # numpy's uniform draw failed on it (a traceback)
        lambda t: _first(
            r'(<joint name="l_elbow".*?)<limit lower="-2.0" upper="0.0"', r'\1<limit lower="0" upper="-2"', t
        ),
        r"joint 'l_elbow': <limit lower=\"0\" upper=\"-2\">: its lower limit is above its upper",
    ),
]


@pytest.mark.parametrize(("edit", "message"), URDF_CASES)
def test_a_malformed_urdf_is_one_line_naming_the_real_cause(edit, message, tmp_path, capfd):
    path = humanoid_urdf(tmp_path)
    path.write_text(edit(path.read_text()))
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert str(path.name) in line and re.search(message, line), line
    assert not (tmp_path / "config.yaml").exists()


def test_a_urdf_of_one_link_is_one_line(tmp_path, capfd):
    """Was a traceback: ``min() arg is an empty sequence`` looking for the up axis among no branches."""
    path = tmp_path / "one.urdf"
    inertial = '<inertial><mass value="5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'
    path.write_text(f'<robot name="one"><link name="pelvis">{inertial}</link></robot>')
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert "no joint below its root link: posegen needs a humanoid" in line, line
    assert not (tmp_path / "config.yaml").exists()


def test_a_mesh_file_that_is_not_a_mesh_is_named(tmp_path, capfd):
    path = humanoid_urdf(tmp_path)
    (tmp_path / "meshes" / "foot.stl").write_text("not a mesh\n")
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert "a mesh of the robot cannot be loaded" in line and "foot.stl" in line, line


def test_a_folder_is_not_taken_for_a_robot_name(tmp_path, capfd):
    humanoid_urdf(tmp_path)
    line = _init([str(tmp_path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert "a folder; give a URDF or MJCF file" in line, line


def test_a_folder_named_like_the_robot_does_not_hide_its_name(tmp_path, monkeypatch, capfd):
    """``robot init human -o human/config.yaml``: the output's folder, made first, is not taken for the robot."""
    monkeypatch.chdir(tmp_path)
    assert main(["robot", "init", "human", "-o", "human/human_table.yaml", "--samples", "2"]) == 0, capfd.readouterr()
    assert "example_robot_data: human" in (tmp_path / "human" / "human_table.yaml").read_text()
    capfd.readouterr()
    line = _init(["./human", "-o", "other.yaml"], capfd)  # a path to the folder is still a folder
    assert "a folder; give a URDF or MJCF file" in line, line


@pytest.mark.parametrize("output", ["robot.urdf", "meshes/foot.stl"])
def test_the_draft_never_overwrites_the_urdf_or_a_mesh_it_reads(output, tmp_path, capfd):
    path = humanoid_urdf(tmp_path)
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    line = _init([str(path), "-o", str(tmp_path / output)], capfd)
    assert "is an input of this command" in line, line
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_the_draft_never_overwrites_the_mjcf_it_reads(tmp_path, capfd):
    path = humanoid_mjcf(tmp_path)
    before = path.read_bytes()
    line = _init([str(path), "-o", str(path)], capfd)
    assert "is an input of this command" in line, line
    assert path.read_bytes() == before


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: _first(r'pos="[^"]*"', 'pos="0 nan 0.1"', t), r"pos=\"0 nan 0\.1\": expected finite numbers"),
        (lambda t: _first(r'mass="[^"]*"', 'mass="-1"', t), r"mass=\"-1\": a negative mass"),
    ],
)
def test_an_mjcf_with_numbers_no_body_has_is_refused(edit, message, tmp_path):
    path = humanoid_mjcf(tmp_path)
    path.write_text(edit(path.read_text()))
    with pytest.raises(ConfigError, match=message):
        convert_mjcf(path)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: _first(r'pos="[^"]*"', 'pos="0 nan 0.1"', t), r"pos=\"0 nan 0\.1\": expected finite numbers"),
        (lambda t: re.sub(r'mass="[^"]*"', 'mass="0"', t), r"every link has zero mass"),
        (lambda t: _first(r'axis="[^"]*"', 'axis="0 0 0"', t), r"its axis is 0\.0 0\.0 0\.0, of no length"),
        (  # was: "names the mesh 'cube', not in <asset>" (it is there)
            lambda t: _first(
                r'<geom type="sphere" pos="0 0 0.1" size="0.08"/>',
                '<geom type="mesh" mesh="cube"/>',
                _first(
                    r"<worldbody>", '<asset><mesh name="cube" vertex="0 0 0 1 0 0 0 1 0 0 0 1"/></asset><worldbody>', t
                ),
            ),
            r"mesh 'cube' is given inline \(vertex=...\), not as a file",
        ),
    ],
)
def test_an_mjcf_refused_at_init_names_the_mjcf(edit, message, tmp_path, capfd):
    path = humanoid_mjcf(tmp_path)
    path.write_text(edit(path.read_text()))
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert path.name in line and re.search(message, line), line
    assert not (tmp_path / "config.yaml").exists() and not (tmp_path / "config.urdf").exists()


def _humanoid_with_meshes_in_mm(folder: Path) -> Path:
    """The synthetic humanoid's URDF, its STL meshes scaled to millimetres."""
    import trimesh

    path = humanoid_urdf(folder)
    for mesh in (folder / "meshes").glob("*.stl"):
        loaded = trimesh.load(mesh)
        loaded.apply_scale(1000.0)
        loaded.export(mesh)
    return path


def test_a_foot_mesh_in_millimetres_is_named(tmp_path, capfd):
    """Was: "stance.foot_x_m: expected values within 0.5 of 0", a key of a config the user never wrote."""
    path = _humanoid_with_meshes_in_mm(tmp_path)
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert re.search(r"link '._foot': its foot geometry spans .* m, not a foot: meshes in millimetres\?", line), line
    assert not (tmp_path / "config.yaml").exists()


def test_a_foot_mesh_scaled_down_twice_is_named(tmp_path, capfd):
    """Was: "stance.foot_x_m: expected [low, high] with low < high" (a helper's scale="0.001" on meshes in metres)."""
    path = humanoid_urdf(tmp_path)
    path.write_text(path.read_text().replace('.stl"/>', '.stl" scale="0.001 0.001 0.001"/>'))
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert re.search(r"link '._foot': its foot geometry spans .* m, not a foot: meshes scaled down twice", line), line
    assert not (tmp_path / "config.yaml").exists()


def test_a_urdf_in_millimetres_throughout_is_named(tmp_path, capfd):
    """Origins in mm too: the foot-mesh message's scale was half the fix; the robot's size is named first."""
    path = _humanoid_with_meshes_in_mm(tmp_path)

    def in_mm(match: re.Match[str]) -> str:
        return f'{match.group(1)}="{" ".join(f"{1000.0 * float(v):g}" for v in match.group(2).split())}"'

    path.write_text(re.sub(r'(xyz|length|radius|size)="([^"]*)"', in_mm, path.read_text()))
    line = _init([str(path), "-o", str(tmp_path / "config.yaml")], capfd)
    assert re.search(r"joints lie \d+ m apart, no humanoid's size: lengths in millimetres\? .*scale its origins", line)
    assert not (tmp_path / "config.yaml").exists()
