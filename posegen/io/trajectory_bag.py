"""A route as a rosbag2: ``trajectory_msgs/JointTrajectory`` messages and the segment table.

Topics:

* the trajectory topic (a ``joint_trajectory_controller``'s command topic by default):
  the whole route at time 0, then one message per segment at the time the segment starts,
  its points timed from the segment's start. Segments are timed rest to rest, so each
  segment message is the rest of the route's motion up to its end: played into a
  controller, the bag streams the route segment by segment.
* ``/posegen/segments`` (``diagnostic_msgs/DiagnosticArray``, a standard message with named
  fields that every ROS 2 tool prints): one message per segment at its start, holding one
  ``DiagnosticStatus``: ``name`` ``posegen/segment/<index>``, ``message`` the segment type
  (free, approach, go_to_contact, hold, release), ``hardware_id`` the arm at the table (empty
  for free motions), and ``values`` (key/value strings): posture, pool_id, start_s, end_s,
  first_point, last_point.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from posegen.io.bag_writer import BagWriter, writing_bag
from posegen.io.cdr import FloatArray
from posegen.io.route_file import Segment

TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
SEGMENT_TABLE = "diagnostic_msgs/msg/DiagnosticArray"
SEGMENT_FIELDS = ("posture", "pool_id", "start_s", "end_s", "first_point", "last_point")


def _ns(seconds: float) -> int:
    return round(seconds * 1e9)


def _trajectory(
    writer: BagWriter, names: Sequence[str], times: FloatArray, arrays: Sequence[FloatArray], first: int, last: int
) -> Any:
    types = writer.typestore.types
    duration, point = types["builtin_interfaces/msg/Duration"], types["trajectory_msgs/msg/JointTrajectoryPoint"]
    positions, velocities, accelerations = arrays
    points = []
    for k in range(first, last + 1):
        sec, nanosec = divmod(_ns(float(times[k] - times[first])), 1_000_000_000)
        points.append(
            point(
                positions=np.array(positions[k], dtype=float),
                velocities=np.array(velocities[k], dtype=float),
                accelerations=np.array(accelerations[k], dtype=float),
                effort=np.zeros(0),
                time_from_start=duration(sec=sec, nanosec=nanosec),
            )
        )
    return types[TRAJECTORY](header=_header(writer, 0), joint_names=list(names), points=points)


def _header(writer: BagWriter, time_ns: int) -> Any:
    types = writer.typestore.types
    sec, nanosec = divmod(time_ns, 1_000_000_000)
    return types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec), frame_id=""
    )


def _segment(writer: BagWriter, index: int, row: Segment, time_ns: int) -> Any:
    types = writer.typestore.types
    status, key_value = types["diagnostic_msgs/msg/DiagnosticStatus"], types["diagnostic_msgs/msg/KeyValue"]
    values = [
        key_value(key=key, value="" if getattr(row, key) is None else str(getattr(row, key))) for key in SEGMENT_FIELDS
    ]
    entry = status(
        level=0,  # DiagnosticStatus.OK
        name=f"posegen/segment/{index}",
        message=row.type.value,
        hardware_id=row.chain or "",
        values=values,
    )
    return types[SEGMENT_TABLE](header=_header(writer, time_ns), status=[entry])


def write_trajectory_bag(
    path: str | Path,
    names: Sequence[str],
    times: FloatArray,
    arrays: Sequence[FloatArray],
    segments: Sequence[Segment],
    topic: str,
    segments_topic: str,
    provenance: dict[str, Any],
) -> int:
    """Write a route as a rosbag2 directory; return the number of messages.

    Args:
        path: Bag directory to write (replaced if it is a bag).
        names: Joint names.
        times: (m,) s from the route's start.
        arrays: Positions (rad), velocities (rad/s), accelerations (rad/s^2), each (m, nj).
        segments: The segment table.
        topic: Trajectory topic.
        segments_topic: Segment-table topic.
        provenance: Recorded in the bag's metadata.

    """
    count = 0
    with writing_bag(path, provenance) as writer:
        writer.topic(topic, TRAJECTORY)
        writer.topic(segments_topic, SEGMENT_TABLE)
        writer.message(topic, 0, _trajectory(writer, names, times, arrays, 0, len(times) - 1))
        for index, row in enumerate(segments):
            start = _ns(row.start_s)
            writer.message(topic, start, _trajectory(writer, names, times, arrays, row.first_point, row.last_point))
            writer.message(segments_topic, start, _segment(writer, index, row, start))
            count += 2
    return count + 1
