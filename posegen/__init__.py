"""posegen: plan and run the whole-body geometric calibration of a humanoid at a table."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("posegen")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
