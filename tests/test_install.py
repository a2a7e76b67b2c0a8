"""The install cannot drift: every package `make test` runs with is pinned in constraints.txt.

The Makefile installs with ``-c constraints.txt``; these tests check that the lock covers
everything posegen (with every extra: the optional parts and ``dev``) pulls in, at the versions installed here,
and that the caps keeping pinocchio's native libraries loadable are declared.
"""

from __future__ import annotations

import importlib.metadata as metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "constraints.txt"
REFRESH = "refresh the lock: make lock, then make test (docs/getting-started.md, Pinned install)"


def pins() -> dict[str, str]:
    out = {}
    for line in LOCK.read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, _, version = line.partition("==")
            assert version, f"constraints.txt: {line!r} is not name==version"
            out[canonicalize_name(name)] = version
    return out


def project() -> dict:
    tomllib = pytest.importorskip("tomllib", reason="Python 3.11+ reads pyproject.toml")
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def declared() -> list[Requirement]:
    """What pyproject.toml asks for, the core and every extra (``posegen[...]``, extras of extras, left out)."""
    extras = [r for group in project()["optional-dependencies"].values() for r in group]
    requirements = [Requirement(r) for r in [*project()["dependencies"], *extras]]
    return [r for r in requirements if canonicalize_name(r.name) != "posegen"]


def test_the_optional_parts_are_extras_and_all_holds_them():
    """The core leaves the viewer, Dask, rosbags and MuJoCo out; ``all`` is every optional part."""
    core = {canonicalize_name(Requirement(r).name) for r in project()["dependencies"]}
    extras = project()["optional-dependencies"]
    assert not core & {"viser", "trimesh", "distributed", "dask", "rosbags", "mujoco"}, core
    assert {"viser", "trimesh"} <= {canonicalize_name(Requirement(r).name) for r in extras["view"]}
    assert {"distributed"} <= {canonicalize_name(Requirement(r).name) for r in extras["dask"]}
    assert {"rosbags"} <= {canonicalize_name(Requirement(r).name) for r in extras["ros"]}
    assert {"mujoco"} <= {canonicalize_name(Requirement(r).name) for r in extras["physics"]}
    (everything,) = [Requirement(r) for r in extras["all"]]
    assert everything.name == "posegen" and everything.extras == {"view", "dask", "ros", "physics"}


def closure() -> dict[str, str]:
    """Every distribution posegen[all,dev] (and its other extras) needs, as installed here: name -> version."""
    found: dict[str, str] = {}
    todo = [(r, "") for r in declared()]
    while todo:
        requirement, extra = todo.pop()
        if requirement.marker and not requirement.marker.evaluate({"extra": extra}):
            continue
        name = canonicalize_name(requirement.name)
        try:
            dist = metadata.distribution(requirement.name)
        except metadata.PackageNotFoundError:
            pytest.fail(f"{requirement.name} is required but not installed: run make install")
        for wanted in requirement.extras or {""}:
            key = f"{name}[{wanted}]"
            if key in found:
                continue
            found[key] = dist.version
            todo.extend((Requirement(r), wanted) for r in dist.requires or [])
    return {key.split("[")[0]: version for key, version in found.items()}


def test_every_installed_requirement_is_pinned_at_its_installed_version():
    locked = pins()
    for name, version in sorted(closure().items()):
        assert name in locked, f"{name} {version} is installed but not in constraints.txt: {REFRESH}"
        assert locked[name] == version, f"{name}: {version} installed, {locked[name]} locked: {REFRESH}"


def test_the_lock_satisfies_what_pyproject_asks():
    locked = pins()
    for requirement in declared():
        name = canonicalize_name(requirement.name)
        assert name in locked, f"{requirement.name} is declared but not locked: {REFRESH}"
        assert requirement.specifier.contains(locked[name], prereleases=True), (str(requirement), locked[name])


def test_the_native_library_caps_are_declared():
    caps = {canonicalize_name(r.name): r.specifier for r in declared()}
    assert "cmeel-urdfdom" in caps and not caps["cmeel-urdfdom"].contains("5.0.0")  # liburdfdom_sensor.so.4.0
    assert "cmeel-tinyxml2" in caps and not caps["cmeel-tinyxml2"].contains("11.0.0")  # libtinyxml2.so.10
