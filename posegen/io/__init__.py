"""Files: atomic writes, YAML artefacts with their provenance, kind-checked reads, array sidecars.

Below every other layer but :mod:`posegen.errors`: nothing here knows the robot.
"""

from posegen.io.arrays import encode_arrays, read_arrays, sidecar_path, sidecar_reference, write_with_arrays
from posegen.io.artefact import dump_yaml, load_yaml_file, provenance, read_yaml, write_yaml
from posegen.io.atomic import write_atomic

__all__ = [
    "dump_yaml",
    "encode_arrays",
    "load_yaml_file",
    "provenance",
    "read_arrays",
    "read_yaml",
    "sidecar_path",
    "sidecar_reference",
    "write_atomic",
    "write_with_arrays",
    "write_yaml",
]
