"""Recorded sessions: written, read back by posegen's fast path, by rosbags, and by mcap + mcap_ros2."""

import json
import shutil

import numpy as np
import pytest
import yaml
from rosbags.rosbag2 import CompressionFormat, CompressionMode, Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from posegen.errors import InputError
from posegen.io import JointStates, RecordedBag, Wrenches, write_recording
from posegen.io.cdr import encode, joint_state_layout

NAMES = ("j_b", "j_a", "j_long_name_3")
STORE = get_typestore(Stores.ROS2_HUMBLE)


def session(n=1200, rate=500.0):
    rng = np.random.default_rng(3)
    times = np.arange(n) / rate
    positions = np.cumsum(rng.normal(0, 1e-3, (n, len(NAMES))), axis=0)
    forces = rng.normal(0, 1, (n, 3))
    torques = rng.normal(0, 0.1, (n, 3))
    return JointStates(NAMES, times, positions), Wrenches(times, forces, torques)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("bags") / "session"
    joints, wrench = session()
    write_recording(
        path, joints, "/joint_states", {"/left_ft": wrench}, {"seed": 3}, start_ns=1_700_000_000_000_000_000
    )
    return path, joints, wrench


def test_round_trip_through_the_fast_path(recorded):
    path, joints, wrench = recorded
    bag = RecordedBag(path)
    assert bag.summaries and all(s is not None for s in bag.summaries)  # indexed MCAP: the column path
    back, (forces,), digest = bag.read_and_hash("/joint_states", ["/left_ft"])
    assert back.names == NAMES
    assert np.array_equal(back.positions, joints.positions)
    assert np.allclose(back.times_s, joints.times_s, atol=1e-9)
    assert np.array_equal(forces.forces, wrench.forces) and np.array_equal(forces.torques, wrench.torques)
    assert digest == bag.sha256() and len(digest) == 64
    meta = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert json.loads(meta["custom_data"]["posegen"]) == {"seed": 3}
    assert meta["storage_identifier"] == "mcap" and meta["version"] == 9


def test_the_independent_mcap_reader_decodes_the_same_messages(recorded):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path, joints, wrench = recorded
    positions, stamps, forces = [], [], []
    with next(path.glob("*.mcap")).open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        for _, channel, _, message in reader.iter_decoded_messages():
            stamp = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
            if channel.topic == "/joint_states":
                assert tuple(message.name) == NAMES
                positions.append(list(message.position))
                stamps.append(stamp)
            else:
                forces.append([message.wrench.force.x, message.wrench.force.y, message.wrench.force.z])
    assert np.array_equal(np.array(positions), joints.positions)
    assert np.array_equal(np.array(forces), wrench.forces)
    assert np.allclose((np.array(stamps) - stamps[0]) * 1e-9, joints.times_s, atol=1e-9)


def _rosbags_bag(path, messages, storage=StoragePlugin.MCAP, compression=None):
    """A bag written message by message with rosbags: [(topic, msgtype, time_ns, raw bytes)]."""
    writer = Writer(path, version=9, storage_plugin=storage)
    if compression:
        writer.set_compression(compression, CompressionFormat.ZSTD)
    with writer:
        connections = {}
        for topic, msgtype, time_ns, raw in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=STORE)
            writer.write(connections[topic], time_ns, raw)


def _joint_messages(joints, names=NAMES):
    """Messages naming ``names``, positions taken from ``joints`` by name."""
    layout = joint_state_layout(names)
    stamps = np.round(joints.times_s * 1e9).astype(np.int64)
    order = [joints.names.index(n) for n in names]
    rows = encode(layout, stamps, [joints.positions[:, order], joints.positions[:, order], np.zeros((len(stamps), 0))])
    return [
        ("/joint_states", "sensor_msgs/msg/JointState", int(s), r.tobytes()) for s, r in zip(stamps, rows, strict=True)
    ]


@pytest.mark.parametrize(
    ("storage", "compression"),
    [
        (StoragePlugin.SQLITE3, None),
        (StoragePlugin.MCAP, CompressionMode.STORAGE),
        (StoragePlugin.MCAP, CompressionMode.FILE),
    ],
)
def test_other_storage_and_compression_read_the_same(tmp_path, storage, compression):
    joints, _ = session(300)
    _rosbags_bag(tmp_path / "bag", _joint_messages(joints), storage, compression)
    back, _ = RecordedBag(tmp_path / "bag").read("/joint_states")
    assert np.array_equal(back.positions, joints.positions)


def test_messages_of_another_layout_are_read_one_by_one(tmp_path):
    """A publisher that reorders the names mid-session: its messages are deserialised and reordered."""
    joints, _ = session(200)
    first = _joint_messages(joints)[:100]
    swapped = _joint_messages(joints, names=("j_a", "j_long_name_3", "j_b"))[100:]
    _rosbags_bag(tmp_path / "bag", first + swapped)
    back, _ = RecordedBag(tmp_path / "bag").read("/joint_states")
    assert back.names == NAMES and np.array_equal(back.positions, joints.positions)


def test_joint_names_that_change_are_an_error(tmp_path):
    joints, _ = session(20)
    other = JointStates(("x", "y", "z"), joints.times_s, joints.positions)
    messages = _joint_messages(joints)[:10] + _joint_messages(other, names=("x", "y", "z"))[10:]
    _rosbags_bag(tmp_path / "bag", messages)
    with pytest.raises(InputError, match="names other joints"):
        RecordedBag(tmp_path / "bag").read("/joint_states")


def test_bad_bags(recorded, tmp_path):
    path, _, _ = recorded
    with pytest.raises(InputError, match="not a rosbag2 directory"):
        RecordedBag(tmp_path)
    with pytest.raises(InputError, match="not a rosbag2 directory"):
        RecordedBag(next(path.glob("*.mcap")))
    bag = RecordedBag(path)
    with pytest.raises(InputError, match=r"no topic '/nope'; its topics: /joint_states \(sensor_msgs"):
        bag.read("/nope")
    with pytest.raises(InputError, match="holds geometry_msgs/msg/WrenchStamped, expected sensor_msgs/msg/JointState"):
        bag.read("/left_ft")

    unknown = tmp_path / "unknown"
    shutil.copytree(path, unknown)
    meta = (unknown / "metadata.yaml").read_text().replace("storage_identifier: mcap", "storage_identifier: foo")
    (unknown / "metadata.yaml").write_text(meta)
    with pytest.raises(InputError, match="unknown storage plugin 'foo'; valid: mcap, sqlite3"):
        RecordedBag(unknown)

    truncated = tmp_path / "truncated"
    shutil.copytree(path, truncated)
    storage = next(truncated.glob("*.mcap"))
    storage.write_bytes(storage.read_bytes()[: storage.stat().st_size // 2])
    with pytest.raises(InputError, match="truncated MCAP file"):
        RecordedBag(truncated)

    garbage = tmp_path / "garbage"
    garbage.mkdir()
    (garbage / "metadata.yaml").write_text("just: text\n")
    with pytest.raises(InputError, match="not a rosbag2 bag"):
        RecordedBag(garbage)


def test_rosbags_reads_what_posegen_writes(recorded):
    path, joints, _ = recorded
    with Reader(path) as reader:
        connection = next(c for c in reader.connections if c.topic == "/joint_states")
        raw = [r for _, _, r in reader.messages(connections=[connection])]
    first = STORE.deserialize_cdr(raw[0], "sensor_msgs/msg/JointState")
    assert tuple(first.name) == NAMES and np.array_equal(first.position, joints.positions[0])
    assert len(raw) == len(joints.times_s)


def _rewritten_by_mcap(path, copy, compression, chunked):
    """The bag at ``path`` copied to ``copy``, its storage re-written by the mcap library (CRCs on)."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter

    shutil.copytree(path, copy)
    storage = next(copy.glob("*.mcap"))
    with next(path.glob("*.mcap")).open("rb") as source, storage.open("wb") as target:
        reader = make_reader(source)
        writer = McapWriter(target, compression=getattr(CompressionType, compression), use_chunking=chunked)
        writer.start(profile="ros2", library="test")
        schemas, channels = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata
                )
            writer.add_message(channels[channel.id], message.log_time, message.data, message.publish_time)
        writer.finish()
    return storage


@pytest.mark.parametrize(("compression", "chunked"), [("LZ4", True), ("ZSTD", True), ("NONE", True), ("NONE", False)])
def test_bags_written_by_the_mcap_library_read_the_same(recorded, tmp_path, compression, chunked):
    """The same messages re-written by another MCAP writer: lz4, zstd or no chunks."""
    path, joints, wrench = recorded
    _rewritten_by_mcap(path, tmp_path / "copy", compression, chunked)
    bag = RecordedBag(tmp_path / "copy")
    assert (bag.summaries[0] is not None) == chunked  # unchunked: no chunk index, rosbags' path
    back, (forces,) = bag.read("/joint_states", ["/left_ft"])
    assert np.array_equal(back.positions, joints.positions) and np.array_equal(forces.forces, wrench.forces)


def test_a_corrupt_chunk_is_an_error(recorded, tmp_path):
    path, _, _ = recorded
    storage = _rewritten_by_mcap(path, tmp_path / "copy", "NONE", True)
    data = bytearray(storage.read_bytes())
    data[len(data) // 3] ^= 0xFF  # a bit flipped inside a chunk's messages
    storage.write_bytes(bytes(data))
    with pytest.raises(InputError, match="corrupt MCAP chunk"):
        RecordedBag(tmp_path / "copy").read("/joint_states")


def _stamped_messages(joints, stamps_s, logged_s):
    """Joint state messages whose header stamps are ``stamps_s``, recorded at ``logged_s``."""
    layout = joint_state_layout(NAMES)
    stamps = np.round(np.asarray(stamps_s) * 1e9).astype(np.int64)
    rows = encode(layout, stamps, [joints.positions, joints.positions, np.zeros((len(stamps), 0))])
    logged = np.round(np.asarray(logged_s) * 1e9).astype(np.int64)
    return [("/joint_states", JOINT, int(t), r.tobytes()) for t, r in zip(logged, rows, strict=True)]


JOINT = "sensor_msgs/msg/JointState"


def test_a_clock_that_goes_back_is_an_error_naming_the_jump(tmp_path):
    joints, _ = session(200)
    logged = 10.0 + joints.times_s
    stamps = logged.copy()
    stamps[100:] -= 3.0  # the joint clock jumps back 3 s
    _rosbags_bag(tmp_path / "bag", _stamped_messages(joints, stamps, logged))
    with pytest.raises(InputError, match=r"topic '/joint_states': the clock goes back 2\.998 s at message 100"):
        RecordedBag(tmp_path / "bag").read("/joint_states")


def test_stamps_a_little_out_of_order_are_sorted(tmp_path):
    joints, _ = session(200)
    logged = 10.0 + joints.times_s
    stamps = logged.copy()
    stamps[[50, 51]] = stamps[[51, 50]]  # two messages logged in the other order (2 ms)
    _rosbags_bag(tmp_path / "bag", _stamped_messages(joints, stamps, logged))
    back, _ = RecordedBag(tmp_path / "bag").read("/joint_states")
    assert np.all(np.diff(back.times_s) > 0) and np.array_equal(back.positions[50], joints.positions[51])


def test_joint_states_that_are_not_finite_are_an_error(tmp_path):
    joints, _ = session(200)
    positions = joints.positions.copy()
    positions[30, 1] = np.nan
    write_recording(tmp_path / "bag", JointStates(NAMES, joints.times_s, positions), "/joint_states", {}, {})
    with pytest.raises(InputError, match=r"1 of 200 messages hold values that are not finite \(first at 0\.060 s\)"):
        RecordedBag(tmp_path / "bag").read("/joint_states")


def test_wrench_samples_that_are_not_finite_are_left_out_and_said(tmp_path, caplog):
    joints, wrench = session(200)
    forces = wrench.forces.copy()
    forces[[5, 6, 7], 2] = np.nan
    bad = Wrenches(wrench.times_s, forces, wrench.torques)
    write_recording(tmp_path / "bag", joints, "/joint_states", {"/ft": bad}, {})
    _, (read,) = RecordedBag(tmp_path / "bag").read("/joint_states", ["/ft"])
    assert len(read.times_s) == 197 and np.isfinite(read.forces).all()
    assert "topic '/ft': 3 of 200 messages hold values that are not finite (first at 0.010 s): left out" in caplog.text
    forces[:] = np.nan
    write_recording(
        tmp_path / "all", joints, "/joint_states", {"/ft": Wrenches(wrench.times_s, forces, wrench.torques)}, {}
    )
    with pytest.raises(InputError, match="200 of 200 messages hold values that are not finite"):
        RecordedBag(tmp_path / "all").read("/joint_states", ["/ft"])
