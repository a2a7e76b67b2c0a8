"""Files: atomic writes, YAML artefacts with their provenance, kind-checked reads.

Below every other layer but :mod:`posegen.errors`: nothing here knows the robot.
"""

from posegen.io.artefact import dump_yaml, load_yaml_file, provenance, read_yaml, write_yaml
from posegen.io.atomic import write_atomic

__all__ = ["dump_yaml", "load_yaml_file", "provenance", "read_yaml", "write_atomic", "write_yaml"]
