"""Where a robot's files are found, and how a draft names them: ``package://`` only for installed packages."""

import sys
from pathlib import Path

import jvrc_description

from posegen.robot.description import package_uri, resolve_path


def test_a_description_installed_from_pypi_is_named_by_its_package():
    urdf = Path(jvrc_description.__file__).parent / "urdf" / "jvrc1.urdf"
    uri = package_uri(urdf)
    assert uri == "package://jvrc_description/urdf/jvrc1.urdf"
    assert resolve_path(uri, ()) == urdf.resolve()  # and found again from that name


def test_a_folder_python_finds_only_from_the_current_folder_is_not_a_package(tmp_path, monkeypatch):
    urdf = tmp_path / "myrobot" / "urdf" / "robot.urdf"
    urdf.parent.mkdir(parents=True)
    urdf.write_text("<robot name='r'/>")
    monkeypatch.setattr(sys, "path", [str(tmp_path), *sys.path])  # python -m from tmp_path, or a script there
    assert package_uri(urdf) is None  # a namespace folder: another process would not find it
    (tmp_path / "myrobot" / "__init__.py").write_text("")
    assert package_uri(urdf) is None  # a regular package, but not installed
