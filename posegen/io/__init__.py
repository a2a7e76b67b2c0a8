"""Files: atomic writes, output locks, YAML artefacts with provenance, kind-checked reads, sidecars, rosbag2.

Below every other layer but :mod:`posegen.errors`: nothing here knows the robot. The
rosbag2 modules hold the format concerns of talking to ROS 2: fixed-layout CDR
(:mod:`~posegen.io.cdr`), indexed MCAP reading (:mod:`~posegen.io.mcap_index`), atomic bag
writing (:mod:`~posegen.io.bag_writer`), recorded sessions (:mod:`~posegen.io.recorded_bag`)
and routes as bags (:mod:`~posegen.io.trajectory_bag`).
"""

from posegen.io.arrays import (
    encode_arrays,
    read_arrays,
    sidecar_path,
    sidecar_reference,
    sidecars_of,
    write_with_arrays,
)
from posegen.io.artefact import dump_yaml, load_yaml_file, provenance, read_text_file, read_yaml, write_yaml
from posegen.io.atomic import atomic_folder, atomic_path, crash_point, staging_folder, swap_folder, write_atomic
from posegen.io.bag_writer import check_bag_destination
from posegen.io.companion import companion_of, companion_path, companions_of, write_with_companions
from posegen.io.output import (
    OutputKind,
    OutputLock,
    check_apart,
    check_replaceable,
    check_writable,
    claim_output,
    input_files,
    lock_path,
)
from posegen.io.recorded_bag import JOINT_STATE, WRENCH_STAMPED, JointStates, RecordedBag, Wrenches, write_recording
from posegen.io.trajectory_bag import SEGMENT_FIELDS, SEGMENT_TABLE, TRAJECTORY, SegmentRow, write_trajectory_bag

__all__ = [
    "JOINT_STATE",
    "SEGMENT_FIELDS",
    "SEGMENT_TABLE",
    "TRAJECTORY",
    "WRENCH_STAMPED",
    "JointStates",
    "OutputKind",
    "OutputLock",
    "RecordedBag",
    "SegmentRow",
    "Wrenches",
    "atomic_folder",
    "atomic_path",
    "check_apart",
    "check_bag_destination",
    "check_replaceable",
    "check_writable",
    "claim_output",
    "companion_of",
    "companion_path",
    "companions_of",
    "crash_point",
    "dump_yaml",
    "encode_arrays",
    "input_files",
    "load_yaml_file",
    "lock_path",
    "provenance",
    "read_arrays",
    "read_text_file",
    "read_yaml",
    "sidecar_path",
    "sidecar_reference",
    "sidecars_of",
    "staging_folder",
    "swap_folder",
    "write_atomic",
    "write_recording",
    "write_trajectory_bag",
    "write_with_arrays",
    "write_with_companions",
    "write_yaml",
]
