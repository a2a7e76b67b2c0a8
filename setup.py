"""Build hook: the wheel carries a copy of the shipped folders (read through posegen.resources.shipped_path).

The top-level ``configs/`` and ``plans/talos/`` stay the source; ``build_py`` copies them
into ``posegen/_data/`` of the build (an editable install reads them in place).
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

SHIPPED = ("configs", "plans/talos")  # each inside a posegen.resources.ROOTS folder (tests/test_resources.py)


class BuildWithData(build_py):
    """``build_py``, then the shipped folders copied into the built package."""

    def run(self) -> None:
        """Build the package, then copy the shipped folders (not in editable mode: read in place)."""
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for folder in SHIPPED:
            target = Path(self.build_lib) / "posegen" / "_data" / folder
            shutil.rmtree(target, ignore_errors=True)
            shutil.copytree(Path(folder), target, ignore=shutil.ignore_patterns(".*", "*.lock", "*.partial*"))


setup(cmdclass={"build_py": BuildWithData})
