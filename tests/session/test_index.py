"""The session index: written and read back to the same dataclass; malformed or edited indexes refused."""

import dataclasses
import shutil

import pytest
import yaml

from posegen.errors import InputError
from posegen.session import (
    INDEX_FILE,
    Assessment,
    Batch,
    BatchState,
    Deliverable,
    Recording,
    SessionIndex,
    SessionSettings,
    read_index,
    write_index,
)
from posegen.session.index import check_files, sha256_of


def an_index(tmp_path):
    for number in (1, 2):  # each batch's rosbag2 to play
        (tmp_path / f"batch_00{number}" / "route_bag").mkdir(parents=True, exist_ok=True)
        (tmp_path / f"batch_00{number}" / "route_bag" / "metadata.yaml").write_text("bag\n")
    made = tmp_path / "batch_001" / "route.yaml"
    made.write_text("route\n")
    recording = Recording("/bags/one", "ab" * 32, "table_1", 27, 130.5, (4, 9))
    assessment = Assessment(27, "urdf", "offsets", {"left": 5.25, "right": 3.5}, False)
    first = Batch(1, (1, 4, 9), 132.0, {"batch_001/route.yaml": sha256_of(made)}, recording, assessment)
    second = Batch(2, (7, 8), 25.0, {})
    settings = SessionSettings(target_mm=3.0, seed=4, deliverable=Deliverable.COMPENSATED, candidates=("offsets",))
    return SessionIndex({"seed": 4, "posegen_version": "0"}, "/pools/pool.yaml", "cd" * 32, settings, (first, second))


def test_the_index_reads_back_to_the_same_dataclass(tmp_path):
    index = an_index(tmp_path)
    write_index(tmp_path, index)
    again = read_index(tmp_path)
    assert again == index
    assert [b.state for b in again.batches] == [BatchState.ASSESSED, BatchState.PLANNED]
    assert not again.done and again.table == "table_1"
    data = yaml.safe_load((tmp_path / INDEX_FILE).read_text())
    assert data["format"] == "posegen-session" and data["format_version"] == 1 and data["done"] is False


def test_a_file_edited_by_hand_is_refused(tmp_path):
    index = an_index(tmp_path)
    check_files(tmp_path, index)
    (tmp_path / "batch_001" / "route.yaml").write_text("route, edited\n")
    with pytest.raises(InputError, match="changed since the session wrote it"):
        check_files(tmp_path, index)
    (tmp_path / "batch_001" / "route.yaml").unlink()
    with pytest.raises(InputError, match="missing"):
        check_files(tmp_path, index)


def test_a_batch_whose_bag_to_play_was_removed_is_refused(tmp_path):
    index = an_index(tmp_path)
    check_files(tmp_path, index)
    shutil.rmtree(tmp_path / "batch_002" / "route_bag")
    with pytest.raises(InputError, match="batch_002/route_bag is missing"):
        check_files(tmp_path, index)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(format_version=9), "version 9"),
        (lambda d: d["batches"][0].pop("pool_rows"), "not a valid session index"),
        (lambda d: d["settings"].update(deliverable="everything"), "not a valid session index"),
        (lambda d: d["settings"].update(patience="soon"), "not a valid session index"),
        (lambda d: d["settings"].update(patience=-2), "not a valid session index"),
        (lambda d: d["batches"][1].update(number=5), "numbered"),
        (lambda d: d.update(format="posegen-pool"), "posegen-pool"),
        # issue 33: every field typed and in its range, the field named (no raw KeyError, no silent accept)
        (lambda d: d.update(batches=[]), r"batches: expected the list of batches"),
        (lambda d: d["settings"].update(batch_postures="ten"), r"settings\.batch_postures must be an integer"),
        (lambda d: d["settings"].update(target_mm=-1.0), r"settings\.target_mm must be > 0"),
        (lambda d: d["settings"].update(margin=-0.5), r"settings\.margin must be a number from 0 to 10"),
        (lambda d: d["settings"].update(seed="four"), r"settings\.seed must be an integer"),
        (lambda d: d["settings"].pop("joint_topic"), r"settings\.joint_topic: missing"),
        (lambda d: d.pop("settings"), r"settings: missing"),
        (lambda d: d["batches"][0].update(state=None), r"batches\[0\]\.state: expected a non-empty name"),
        (lambda d: d["batches"][0].update(state="planned"), r"batches\[0\]\.state: planned, but the batch is"),
        (lambda d: d["batches"][0].update(planned_s=float("nan")), r"batches\[0\]\.planned_s: expected a finite"),
        (lambda d: d["batches"][0]["recording"].update(duration_s=float("nan")), r"recording\.duration_s"),
        (lambda d: d["batches"][0]["recording"].update(contacts="27"), r"recording\.contacts: expected a whole"),
        (lambda d: d.pop("done"), r"done: missing"),
        (lambda d: d.update(done=True), r"done: true, but the batches say false"),
        (lambda d: d["batches"][0]["files"].update({"../../etc/passwd": "ab" * 32}), r"not a file of the session"),
        (lambda d: d["batches"][0].update(recording=None), r"batches\[0\]\.assessment: a batch assessed but not"),
        (lambda d: d["batches"][0]["assessment"]["predicted_z_mm"].update(left=float("nan")), r"predicted_z_mm\.left"),
    ],
)
def test_a_malformed_index_is_one_clear_error(tmp_path, edit, message):
    write_index(tmp_path, an_index(tmp_path))
    data = yaml.safe_load((tmp_path / INDEX_FILE).read_text())
    edit(data)
    (tmp_path / INDEX_FILE).write_text(yaml.safe_dump(data))
    with pytest.raises(InputError, match=message):
        read_index(tmp_path)


def test_no_index_is_not_a_session(tmp_path):
    with pytest.raises(InputError, match="not a posegen session"):
        read_index(tmp_path)


def test_a_chain_above_the_target_whose_prediction_did_not_fall_is_stalled(tmp_path):
    index = an_index(tmp_path)  # batch 1: left 5.25, right 3.5 (target 3); batch 2 not assessed yet
    assert index.stalled == ()  # one figure: nothing to compare
    recording = Recording("/bags/two", "ef" * 32, "table_1", 2, 25.0, ())
    for left, right, stalled in (
        (5.30, 3.6, (("left", 5.25, 5.30), ("right", 3.5, 3.6))),  # both rose, both above the target
        (5.25, 2.9, (("left", 5.25, 5.25),)),  # left unchanged; right fell below the target
        (5.00, 3.4, ()),  # both fell: no stall, though both are still above
    ):
        assessed = Assessment(29, "urdf", "offsets", {"left": left, "right": right}, False)
        second = Batch(2, (7, 8), 25.0, {}, recording, assessed)
        assert index.with_batch(second).stalled == stalled
    failed = Batch(2, (7, 8), 25.0, {}, recording, Assessment(29, "", "", {}, False, error="too few contacts"))
    assert index.with_batch(failed).stalled == ()  # a batch without a figure is not compared


def with_predictions(index, *predicted, patience=2):
    """The index with one assessed batch per ``{chain: mm}`` of ``predicted`` (batch 1 replaced)."""
    recording = Recording("/bags/b", "ef" * 32, "table_1", 10, 25.0, ())
    batches = tuple(
        Batch(n, (n,), 25.0, {}, recording, Assessment(10 * n, "urdf", "offsets", figures, False))
        for n, figures in enumerate(predicted, start=1)
    )
    settings = dataclasses.replace(index.settings, patience=patience)
    return dataclasses.replace(index, settings=settings, batches=batches)


@pytest.mark.parametrize(
    ("predicted", "patience", "at_floor"),
    [
        (({"left": 5.0}, {"left": 5.1}), 2, False),  # one batch without gain: patience 2 waits
        (({"left": 5.0}, {"left": 5.1}, {"left": 5.05}), 2, True),  # two batches, no new low
        (({"left": 5.0}, {"left": 5.1}, {"left": 4.99}), 2, False),  # a new low, by any amount
        (({"left": 5.0}, {"left": 5.1}), 1, True),
        (({"left": 5.0}, {"left": 5.1}, {"left": 5.2}), 0, False),  # 0: only the target stops it
        (({"left": 5.0, "right": 4.0}, {"left": 4.0, "right": 4.5}, {"left": 3.9, "right": 4.6}), 2, False),
        (({"left": 5.0, "right": 4.0}, {"left": 2.0, "right": 4.5}, {"left": 2.1, "right": 4.6}), 2, True),
        (({"left": 2.0, "right": 2.0}, {"left": 2.5, "right": 2.9}, {"left": 2.6, "right": 2.9}), 2, False),  # done
    ],
)
def test_a_session_is_at_its_floor_when_no_chain_above_the_target_reaches_a_new_low(
    tmp_path, predicted, patience, at_floor
):
    index = with_predictions(an_index(tmp_path), *predicted, patience=patience)  # target 3 mm
    assert index.at_floor is at_floor
    assert index.ended is (at_floor or index.done)


def test_patience_is_written_and_read_back(tmp_path):
    index = with_predictions(an_index(tmp_path), {"left": 5.0}, {"left": 5.1}, patience=1)
    write_index(tmp_path, index)
    again = read_index(tmp_path)
    assert again.settings.patience == 1 and again.at_floor
    assert yaml.safe_load((tmp_path / INDEX_FILE).read_text())["at_floor"] is True


def test_an_index_written_before_patience_existed_reads_with_its_default(tmp_path):
    write_index(tmp_path, an_index(tmp_path))
    data = yaml.safe_load((tmp_path / INDEX_FILE).read_text())
    del data["settings"]["patience"]
    (tmp_path / INDEX_FILE).write_text(yaml.safe_dump(data))
    assert read_index(tmp_path).settings.patience == SessionSettings().patience
