"""Files: atomic writes, output locks, YAML artefacts with provenance, kind-checked reads, sidecars, rosbag2.

Below every other layer but :mod:`posegen.errors`: nothing here knows the robot. The
rosbag2 modules hold the format concerns of talking to ROS 2: fixed-layout CDR
(:mod:`~posegen.io.cdr`), indexed MCAP reading (:mod:`~posegen.io.mcap_index`), atomic bag
writing (:mod:`~posegen.io.bag_writer`), recorded sessions (:mod:`~posegen.io.recorded_bag`)
and routes as bags (:mod:`~posegen.io.trajectory_bag`). Route files (the typed
:class:`~posegen.io.route_file.Route`, its reader and writer), pool files
(:class:`~posegen.io.pool_file.Pool`) and selection files
(:class:`~posegen.io.selection_file.Selection`) live here too, below every stage that reads one.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
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
from posegen.io.native_output import NativeOutput, native_output
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
from posegen.io.pool_file import (
    POOL_FORMAT,
    POOL_VERSION,
    SELECTION_FORMAT,
    Pool,
    Posture,
    load_pool,
    pool_from_dict,
    posture_from_dict,
    write_pool,
)
from posegen.io.recorded_bag import JOINT_STATE, WRENCH_STAMPED, JointStates, RecordedBag, Wrenches, write_recording
from posegen.io.route_file import (
    MAX_DURATION_S,
    MAX_POINT_VALUE,
    MIN_STEP_S,
    POSITION_DTYPE,
    ROUTE_ARRAYS,
    ROUTE_FORMAT,
    ROUTE_VERSION,
    TIME_DTYPE,
    Route,
    Segment,
    SegmentType,
    is_route_file,
    points_problem,
    read_route,
    stamp,
)
from posegen.io.route_writer import (
    ACCELERATION_STEP,
    VELOCITY_STEP,
    route_header,
    route_outputs,
    stored_arrays,
    write_route,
)
from posegen.io.selection_file import (
    Certificate,
    ChosenPosture,
    DesignFigures,
    DetmaxFigures,
    Figures,
    FollowUpFigures,
    IrocFigures,
    Selection,
    SelectionMethod,
    SessionFigures,
    chosen_from_pool,
    load_postures,
    posture_entries,
    postures_from_dict,
    postures_of,
    read_selection,
    selection_from_dict,
    write_selection,
)
from posegen.io.topic_names import check_topics, topic_name_problem
from posegen.io.trajectory_bag import SEGMENT_FIELDS, SEGMENT_TABLE, TRAJECTORY, write_trajectory_bag

__all__ = [
    "ACCELERATION_STEP",
    "JOINT_STATE",
    "MAX_DURATION_S",
    "MAX_POINT_VALUE",
    "MIN_STEP_S",
    "POOL_FORMAT",
    "POOL_VERSION",
    "POSITION_DTYPE",
    "ROUTE_ARRAYS",
    "ROUTE_FORMAT",
    "ROUTE_VERSION",
    "SEGMENT_FIELDS",
    "SEGMENT_TABLE",
    "SELECTION_FORMAT",
    "TIME_DTYPE",
    "TRAJECTORY",
    "VELOCITY_STEP",
    "WRENCH_STAMPED",
    "Certificate",
    "ChosenPosture",
    "DesignFigures",
    "DetmaxFigures",
    "Figures",
    "FollowUpFigures",
    "IrocFigures",
    "JointStates",
    "NativeOutput",
    "OutputKind",
    "OutputLock",
    "Pool",
    "Posture",
    "RecordedBag",
    "Route",
    "Segment",
    "SegmentType",
    "Selection",
    "SelectionMethod",
    "SessionFigures",
    "Wrenches",
    "atomic_folder",
    "atomic_path",
    "check_apart",
    "check_bag_destination",
    "check_replaceable",
    "check_topics",
    "check_writable",
    "chosen_from_pool",
    "claim_output",
    "companion_of",
    "companion_path",
    "companions_of",
    "crash_point",
    "dump_yaml",
    "encode_arrays",
    "input_files",
    "is_route_file",
    "load_pool",
    "load_postures",
    "load_yaml_file",
    "lock_path",
    "native_output",
    "points_problem",
    "pool_from_dict",
    "posture_entries",
    "posture_from_dict",
    "postures_from_dict",
    "postures_of",
    "provenance",
    "read_arrays",
    "read_route",
    "read_selection",
    "read_text_file",
    "read_yaml",
    "route_header",
    "route_outputs",
    "selection_from_dict",
    "sidecar_path",
    "sidecar_reference",
    "sidecars_of",
    "staging_folder",
    "stamp",
    "stored_arrays",
    "swap_folder",
    "topic_name_problem",
    "write_atomic",
    "write_pool",
    "write_recording",
    "write_route",
    "write_selection",
    "write_trajectory_bag",
    "write_with_arrays",
    "write_with_companions",
    "write_yaml",
]
