"""Fixed-layout CDR against rosbags' own serialiser (an independent implementation)."""

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from posegen.io.cdr import decode, encode, joint_state_layout, matches, wrench_stamped_layout

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types


def _header(stamp, frame_id):
    sec, nanosec = divmod(int(stamp), 1_000_000_000)
    return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec), frame_id=frame_id)


@pytest.mark.parametrize("frame_id", ["", "b", "base_link"])
@pytest.mark.parametrize("counts", [(3, 3, 0), (3, 0, 3), (3, 3, 3), (3, 0, 0)])
@pytest.mark.parametrize("names", [["a", "leg_left_1_joint", "xyz12"], ["abcd", "e", "fgh"]])
def test_joint_states_are_byte_identical_to_rosbags(names, frame_id, counts):
    rng = np.random.default_rng(len(frame_id) + sum(counts))
    layout = joint_state_layout(names, frame_id, counts)
    arrays = [rng.normal(size=(3, c)) for c in counts]
    stamps = np.array([0, 1_500_000_001, 12_000_000_999])
    rows = encode(layout, stamps, arrays)
    for k in range(3):
        message = T["sensor_msgs/msg/JointState"](
            header=_header(stamps[k], frame_id),
            name=names,
            position=arrays[0][k],
            velocity=arrays[1][k],
            effort=arrays[2][k],
        )
        assert bytes(STORE.serialize_cdr(message, "sensor_msgs/msg/JointState")) == rows[k].tobytes()
    assert matches(layout, rows).all()
    decoded_stamps, blocks = decode(layout, rows)
    assert np.array_equal(decoded_stamps, stamps)
    for original, back in zip(arrays, blocks, strict=True):
        assert np.array_equal(original, back)


@pytest.mark.parametrize("frame_id", ["", "wrist_left_ft_link", "abc"])
def test_wrenches_are_byte_identical_to_rosbags(frame_id):
    layout = wrench_stamped_layout(frame_id)
    values = np.arange(12.0).reshape(2, 6) - 5.5
    stamps = np.array([5, 1_000_000_007])
    rows = encode(layout, stamps, [values[:, :3], values[:, 3:]])
    vector, wrench = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Wrench"]
    for k in range(2):
        message = T["geometry_msgs/msg/WrenchStamped"](
            header=_header(stamps[k], frame_id),
            wrench=wrench(force=vector(*values[k, :3]), torque=vector(*values[k, 3:])),
        )
        assert bytes(STORE.serialize_cdr(message, "geometry_msgs/msg/WrenchStamped")) == rows[k].tobytes()


def test_a_message_of_another_layout_does_not_match():
    layout = joint_state_layout(["a", "b"])
    other = joint_state_layout(["b", "a"])  # same length, names swapped
    rows = encode(other, np.array([1]), [np.ones((1, 2)), np.ones((1, 2)), np.zeros((1, 0))])
    assert other.size == layout.size and not matches(layout, rows)[0]
