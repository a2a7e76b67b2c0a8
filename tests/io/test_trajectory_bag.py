"""A route as a rosbag2: JointTrajectory messages and the segment table, read by rosbags and by mcap_ros2."""

import numpy as np
import pytest
import yaml
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from posegen.errors import InputError
from posegen.io import SEGMENT_FIELDS, Segment, SegmentType, write_trajectory_bag

STORE = get_typestore(Stores.ROS2_HUMBLE)
NAMES = ["a_joint", "b_joint"]
TRAJECTORY_TOPIC = "/arm_controller/joint_trajectory"


def route():
    times = np.array([0.0, 0.5, 1.25, 2.0, 3.0, 3.5])
    positions = np.column_stack([np.linspace(0, 1, 6), np.linspace(0, -1, 6) ** 2])
    velocities = np.gradient(positions, times, axis=0)
    velocities[[0, 2, 3, 4, 5]] = 0.0
    accelerations = np.full_like(positions, 0.25)
    segments = [
        Segment(SegmentType.FREE, None, 0, 17, 0, 2, 0.0, 1.25),
        Segment(SegmentType.GO_TO_CONTACT, "left", 0, 17, 2, 3, 1.25, 2.0),
        Segment(SegmentType.HOLD, "left", 0, 17, 3, 4, 2.0, 3.0),
        Segment(SegmentType.RELEASE, "left", 0, 17, 4, 5, 3.0, 3.5),
    ]
    return times, (positions, velocities, accelerations), segments


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    path = tmp_path_factory.mktemp("route") / "route_bag"
    times, arrays, segments = route()
    count = write_trajectory_bag(path, NAMES, times, arrays, segments, TRAJECTORY_TOPIC, "/posegen/segments", {})
    return path, count


def read(path):
    with Reader(path) as reader:
        return [(c.topic, t, STORE.deserialize_cdr(raw, c.msgtype)) for c, t, raw in reader.messages()]


def test_whole_route_then_one_message_per_segment(exported):
    path, count = exported
    times, (positions, velocities, accelerations), segments = route()
    messages = read(path)
    assert count == len(messages) == 1 + 2 * len(segments)
    trajectories = [(t, m) for topic, t, m in messages if topic == TRAJECTORY_TOPIC]
    whole = trajectories[0][1]
    assert list(whole.joint_names) == NAMES and len(whole.points) == len(times)
    stamps = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in whole.points]
    assert np.allclose(stamps, times, atol=1e-9)
    assert np.array_equal(np.array([p.positions for p in whole.points]), positions)
    assert np.array_equal(np.array([p.accelerations for p in whole.points]), accelerations)
    for (bag_time, message), segment in zip(trajectories[1:], segments, strict=True):
        assert bag_time == round(segment.start_s * 1e9)
        first, last = segment.first_point, segment.last_point
        assert len(message.points) == last - first + 1
        offsets = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in message.points]
        assert np.allclose(offsets, times[first : last + 1] - times[first], atol=1e-9)  # timed from the segment
        assert np.array_equal(np.array([p.velocities for p in message.points]), velocities[first : last + 1])


def test_segment_table(exported):
    path, _ = exported
    _, _, segments = route()
    table = [(t, m) for topic, t, m in read(path) if topic == "/posegen/segments"]
    assert len(table) == len(segments)
    for index, ((bag_time, message), segment) in enumerate(zip(table, segments, strict=True)):
        (status,) = message.status
        assert status.name == f"posegen/segment/{index}" and status.message == segment.type
        assert status.hardware_id == (segment.chain or "")
        values = {kv.key: kv.value for kv in status.values}
        assert list(values) == list(SEGMENT_FIELDS)
        assert float(values["start_s"]) == segment.start_s and int(values["pool_id"]) == 17
        assert message.header.stamp.sec * 10**9 + message.header.stamp.nanosec == bag_time


def test_the_independent_mcap_reader_decodes_the_same_messages(exported):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path, count = exported
    ours = read(path)
    with next(path.glob("*.mcap")).open("rb") as handle:
        theirs = list(make_reader(handle, decoder_factories=[DecoderFactory()]).iter_decoded_messages())
    assert len(theirs) == count
    for (topic, bag_time, message), (schema, channel, raw, decoded) in zip(ours, theirs, strict=True):
        assert (channel.topic, raw.log_time) == (topic, bag_time)
        assert schema.name == message.__msgtype__
        if topic == TRAJECTORY_TOPIC:
            assert [list(p.positions) for p in decoded.points] == [list(p.positions) for p in message.points]
        else:
            assert [(kv.key, kv.value) for kv in decoded.status[0].values] == [
                (kv.key, kv.value) for kv in message.status[0].values
            ]


def test_a_bag_is_replaced_whole_and_anything_else_is_kept(exported, tmp_path):
    times, arrays, segments = route()
    target = tmp_path / "out"
    write_trajectory_bag(target, NAMES, times, arrays, segments, TRAJECTORY_TOPIC, "/s", {})
    write_trajectory_bag(target, NAMES, times, arrays, segments[:1], TRAJECTORY_TOPIC, "/s", {})
    assert len(read(target)) == 3  # the second bag replaced the first
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no scratch folder left behind
    keep = tmp_path / "notes"
    keep.mkdir()
    (keep / "a.txt").write_text("mine")
    with pytest.raises(InputError, match="not a rosbag2 directory"):
        write_trajectory_bag(keep, NAMES, times, arrays, segments, TRAJECTORY_TOPIC, "/s", {})
    assert (keep / "a.txt").read_text() == "mine"


def _without_provenance(bag):
    meta = bag / "metadata.yaml"
    info = yaml.safe_load(meta.read_text())
    info["rosbag2_bagfile_information"].pop("custom_data", None)
    meta.write_text(yaml.safe_dump(info))


@pytest.mark.parametrize("kind", ["recording", "notes", "bad_metadata", "storage_folder"])
def test_a_recording_or_a_bag_holding_other_files_is_never_replaced(kind, tmp_path):
    times, arrays, segments = route()
    target = tmp_path / "bag"
    write_trajectory_bag(target, NAMES, times, arrays, segments, TRAJECTORY_TOPIC, "/s", {"posegen_version": "x"})
    if kind == "recording":  # a real recording: no posegen provenance in its metadata
        _without_provenance(target)
    elif kind == "notes":
        (target / "notes.txt").write_text("mine")
    elif kind == "storage_folder":  # a folder where the storage file was: not posegen's
        storage = next(target.glob("*.mcap"))
        storage.unlink()
        storage.mkdir()
        (storage / "mine.txt").write_text("mine")
    else:
        (target / "metadata.yaml").write_text("rosbag2_bagfile_information: 3\n")
    before = {str(p): p.read_bytes() for p in target.rglob("*") if p.is_file()}
    message = {
        "recording": "posegen did not write",
        "notes": r"files posegen did not write \(notes\.txt\)",
        "storage_folder": r"files posegen did not write \(bag\.mcap\)",
    }
    with pytest.raises(InputError, match=message.get(kind, "not a rosbag2 bag")):
        write_trajectory_bag(target, NAMES, times, arrays, segments[:1], TRAJECTORY_TOPIC, "/s", {})
    assert {str(p): p.read_bytes() for p in target.rglob("*") if p.is_file()} == before
