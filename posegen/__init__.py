"""posegen: plan and run the whole-body geometric calibration of a humanoid at a table.

The public API (each name documented with an example; the subpackages are internal):

- the robot: ``load_scene``, ``Scene``;
- any artefact read back as its object: ``load``; the objects ``Pool``, ``Selection``,
  ``Route``, ``Measurements``, ``CalibrationSummary``;
- the commands, files in and out: ``generate_pool``, ``check_pool``, ``select_postures``
  (with ``SelectionSettings``), ``follow_up``, ``plan_route``, ``check_route``,
  ``export_route``, ``simulate`` and ``simulate_recording`` (with ``SimulatedRobot``),
  ``measure``, ``calibrate_robot`` (with ``CalibrationSettings``; ``describe_calibration``), ``write_view``;
- what a controller applies: ``compensate``, ``uncompensate``, ``read_compliance``;
- errors: ``PosegenError`` (every failure posegen means to report).

Example:
    >>> import posegen
    >>> posegen.generate_pool("configs/talos_table.yaml", "plans/pool.yaml", n=200, seed=1)
    >>> posegen.select_postures("plans/pool.yaml", "plans/selected.yaml")

The names load at first use (``import posegen`` imports no stage, no placo, no viser).

"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("posegen")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

_HOMES = {  # public name -> the module that defines it (imported at first use)
    "load_scene": "posegen.api",
    "load": "posegen.api",
    "generate_pool": "posegen.api",
    "check_pool": "posegen.api",
    "select_postures": "posegen.api",
    "follow_up": "posegen.api",
    "plan_route": "posegen.api",
    "check_route": "posegen.api",
    "export_route": "posegen.api",
    "simulate": "posegen.api",
    "simulate_recording": "posegen.api",
    "measure": "posegen.api",
    "calibrate_robot": "posegen.api",
    "describe_calibration": "posegen.api",
    "write_view": "posegen.api",
    "SimulatedRobot": "posegen.api",
    "CalibrationSettings": "posegen.api",
    "Scene": "posegen.robot",
    "Pool": "posegen.io",
    "Selection": "posegen.select",
    "SelectionSettings": "posegen.select",
    "Route": "posegen.io",
    "Measurements": "posegen.model",
    "CalibrationSummary": "posegen.calibrate",
    "compensate": "posegen.calibrate",
    "uncompensate": "posegen.calibrate",
    "read_compliance": "posegen.calibrate",
    "PosegenError": "posegen.errors",
}

__all__ = [  # the public API (the names of _HOMES)
    "CalibrationSettings",
    "CalibrationSummary",
    "Measurements",
    "Pool",
    "PosegenError",
    "Route",
    "Scene",
    "Selection",
    "SelectionSettings",
    "SimulatedRobot",
    "__version__",
    "calibrate_robot",
    "check_pool",
    "check_route",
    "compensate",
    "describe_calibration",
    "export_route",
    "follow_up",
    "generate_pool",
    "load",
    "load_scene",
    "measure",
    "plan_route",
    "read_compliance",
    "select_postures",
    "simulate",
    "simulate_recording",
    "uncompensate",
    "write_view",
]


def __getattr__(name: str) -> Any:
    """A public name, imported from its module at first use (PEP 562)."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'posegen' has no attribute {name!r}")
    value = getattr(import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_HOMES])
