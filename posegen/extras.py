"""The optional parts of posegen and the packages each needs.

``pip install posegen`` plans, selects, routes and calibrates. The rest is optional:
``posegen[view]`` (the 3D viewer and the calibration report: viser, trimesh),
``posegen[dask]`` (work sent to a Dask cluster: distributed), ``posegen[ros]`` (rosbag2
bags: rosbags), ``posegen[physics]`` (a route rehearsed in MuJoCo: mujoco),
``posegen[all]`` (all four). The code that needs one calls
:func:`require` first, so a missing package is one clear error naming what to install.
"""

from __future__ import annotations

import enum
import importlib

from posegen.errors import ExtraError


class Extra(enum.Enum):
    """An optional part: its value is the name of the ``posegen[...]`` extra."""

    VIEW = "view"
    DASK = "dask"
    ROS = "ros"
    PHYSICS = "physics"


PACKAGES: dict[Extra, tuple[str, ...]] = {  # the modules each extra installs (pyproject.toml)
    Extra.VIEW: ("viser", "trimesh"),
    Extra.DASK: ("dask", "distributed"),
    Extra.ROS: ("rosbags",),
    Extra.PHYSICS: ("mujoco",),
}


def install_hint(extra: Extra) -> str:
    """The command that installs ``extra``."""
    return f"pip install 'posegen[{extra.value}]'"


def require(extra: Extra, purpose: str) -> None:
    """Import the modules of ``extra``; fail with what to install when one is missing.

    Args:
        extra: The optional part needed.
        purpose: What needs it, for the message ("the 3D view", "reading rosbag2 bags").

    Raises:
        ExtraError: A module of ``extra`` cannot be imported.

    Example:
        >>> require(Extra.ROS, "reading rosbag2 bags")  # silent when rosbags is installed

    """
    for module in PACKAGES[extra]:
        try:
            importlib.import_module(module)
        except ImportError as exc:
            raise ExtraError(
                f"{purpose} needs the optional package {module}, which is not installed: {install_hint(extra)}",
                name=module,
            ) from exc
