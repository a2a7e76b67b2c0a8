"""``posegen session`` end to end on a simulated robot: start -> rehearse, the stopping rule, and bad input.

One arm of the example pool, the smallest first batch (no margin), 3-posture follow-ups,
two candidate models and one fold seed: every step runs, in about two minutes. The robot
(seed 3, compliant hips) is simulated once, for the first two batches; the other tests
reuse its recordings (a copy of the started session is the robot before its first batch).
"""

import dataclasses
import shutil

import numpy as np
import pytest
import yaml

from posegen.cli import main
from posegen.errors import InfeasibleError, InputError
from posegen.io import (
    JointStates,
    RecordedBag,
    SegmentType,
    Wrenches,
    load_pool,
    read_route,
    write_recording,
    write_yaml,
)
from posegen.parallel import open_backend
from posegen.route import route_postures_file
from posegen.session import (
    INDEX_FILE,
    REHEARSAL_BAG,
    BatchState,
    add_bag,
    read_index,
    session_status,
    start_session,
    write_index,
)
from posegen.session.batch import ROUTE_FILE, BatchSources, route_batch, select_next, standing_posture
from tests.cli.test_cli import assert_one_line_error
from tests.session.conftest import CHAIN, SETTINGS


@pytest.fixture(scope="module")
def backend():
    with open_backend(2) as opened:
        yield opened


def copy_of(folder, tmp_path):
    shutil.copytree(folder, tmp_path / "session")
    return tmp_path / "session"


@pytest.mark.slow  # the started session (1.7 min, shared with the rehearsed one): `make slow`
def test_the_first_batch_identifies_every_base_parameter(started):
    index = read_index(started)
    assert [b.state for b in index.batches] == [BatchState.PLANNED]
    batch = index.batches[0]
    selection = yaml.safe_load((started / batch.folder / "selection.yaml").read_text())
    figures = selection["figures"]
    assert figures["rank"] == figures["base_parameters"]  # identifies every base parameter...
    assert len(batch.pool_rows) >= -(-figures["base_parameters"] // 3)  # ... so at least nb / 3 flush contacts
    route = read_route(started / batch.folder / ROUTE_FILE)
    lost = {s["pool_id"] for s in route.substitutions}
    routed = [p["pool_id"] for p in selection["postures"] if p["pool_id"] not in lost]
    routed += [s["substitute_pool_id"] for s in route.substitutions]
    assert not route.skipped and sorted(batch.pool_rows) == sorted(routed)  # all routed, each lost one replaced
    assert RecordedBag(started / batch.folder / "route_bag").topics  # the bag to play
    provenance = index.provenance
    assert provenance["seed"] == 0 and provenance["robot_model_sha256"] and provenance["posegen_version"]
    assert provenance["config"]["chains"][CHAIN]


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_the_rehearsal_plays_batches_for_the_weakest_chain(rehearsed):
    folder, added = rehearsed
    index = read_index(folder)
    assert len(added) == 2 and [b.state for b in index.batches] == [BatchState.ASSESSED] * 2 + [BatchState.PLANNED]
    first, second, third = index.batches
    assert first.recording.contacts == len(first.pool_rows) and not first.recording.missing
    assert second.assessment.contacts == first.recording.contacts + second.recording.contacts
    assert len(second.pool_rows) == len(third.pool_rows) == SETTINGS.batch_postures
    follow_up = yaml.safe_load((folder / "batch_002" / "followup.yaml").read_text())["figures"]
    assert follow_up["weakest_chain"] == CHAIN and follow_up["given_contacts"] == first.recording.contacts
    assert not index.done  # 1 mm is out of reach of the URDF alone on a robot whose hips give way


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_no_batch_repeats_a_posture_of_the_session(rehearsed, tmp_path):
    folder, _ = rehearsed
    index = read_index(folder)
    rows = [r for b in index.batches for r in b.pool_rows]
    assert len(rows) == len(set(rows))  # every batch new postures
    follow_up = yaml.safe_load((folder / "batch_003" / "followup.yaml").read_text())["figures"]
    assert follow_up["excluded_postures"] == len(index.batches[0].pool_rows) + len(index.batches[1].pool_rows)
    pool = load_pool(index.pool)
    sources = BatchSources(
        given=tuple(str(folder / b.folder / "measurements.yaml") for b in index.batches[:2]),
        calibration=str(folder / "batch_002" / "calibration" / "calibration.yaml"),
        weakest=CHAIN,
        planned=tuple(range(2, len(pool.postures))),
    )
    select_next(index.pool, pool, tmp_path, sources, SETTINGS)  # two postures left: the batch takes both
    selection = yaml.safe_load((tmp_path / "selection.yaml").read_text())
    assert sorted(p["pool_id"] for p in selection["postures"]) == [0, 1]
    with pytest.raises(InfeasibleError, match="every posture of the pool is in the session already"):
        select_next(
            index.pool, pool, tmp_path, dataclasses.replace(sources, planned=tuple(range(len(pool.postures)))), SETTINGS
        )


@pytest.mark.slow  # the started session (1.7 min, shared with the rehearsed one): `make slow`
def test_the_next_batch_is_routed_from_where_the_robot_stands(started, backend, tmp_path):
    assert standing_posture(started / "batch_001" / ROUTE_FILE) is None  # back at the start posture
    route = read_route(started / "batch_001" / ROUTE_FILE)
    approach = next(s for s in route.segments if s.type == SegmentType.APPROACH)
    standoff = route.positions[approach.first_point]  # above a contact
    index = read_index(started)
    pool = load_pool(index.pool).to_dict()
    routed = sorted(index.batches[0].pool_rows)[:2]  # two postures the first batch reached
    two = tmp_path / "two.yaml"
    write_yaml(two, {**pool, "postures": [pool["postures"][r] for r in routed]})
    for number in (1, 2):
        (tmp_path / "session" / f"batch_00{number}").mkdir(parents=True)
    shutil.copy(two, tmp_path / "session" / "batch_002" / "selection.yaml")
    before = tmp_path / "session" / "batch_001" / ROUTE_FILE  # a batch that left the robot above a contact
    route_postures_file(str(two), str(before), 0, None, workers=backend, from_posture=standoff)
    assert np.array_equal(standing_posture(before), standoff)
    batch = route_batch(tmp_path / "session", 2, str(two), SETTINGS, backend)
    after = read_route(tmp_path / "session" / "batch_002" / ROUTE_FILE).positions
    assert np.array_equal(after[0], standoff) and sorted(batch.pool_rows) == routed


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_the_stopping_figure_is_the_one_calibrate_reports(rehearsed):
    folder, _ = rehearsed
    for batch in read_index(folder).batches[:2]:
        report = yaml.safe_load((folder / batch.folder / "calibration" / "calibration.yaml").read_text())
        entry = report["deliverables"]["urdf"]
        assert batch.assessment.deliverable == "urdf" and batch.assessment.candidate == entry["candidate"]
        expected = {c: e["mean_abs"]["z_mm"] for c, e in entry["predicted_error"].items()}
        assert batch.assessment.predicted_z_mm == expected
        assert batch.assessment.done == all(v <= SETTINGS.target_mm for v in expected.values())


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_status_counts_contacts_and_robot_time(rehearsed, capsys):
    folder, _ = rehearsed
    status = session_status(str(folder))
    index = status.index
    assert status.contacts == sum(b.recording.contacts for b in index.batches[:2])
    assert status.spent_s == pytest.approx(sum(b.recording.duration_s for b in index.batches[:2]))
    assert status.planned_s == index.batches[2].planned_s > 0
    assert status.plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["session", "status", str(folder), "--plot", str(folder / "again.png")]) == 0
    out = capsys.readouterr().out
    assert f"{status.contacts} contacts" in out and "not done" in out and (folder / "again.png").is_file()


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_a_bag_added_twice_or_not_a_recording_is_refused_and_nothing_changes(rehearsed, backend):
    folder, _ = rehearsed
    before = (folder / INDEX_FILE).read_bytes()
    with pytest.raises(InputError, match="already added"):
        add_bag(str(folder), str(folder / "batch_001" / REHEARSAL_BAG), backend)
    with pytest.raises(InputError, match="joint_states"):  # the bag to play, not the one recorded
        add_bag(str(folder), str(folder / "batch_003" / "route_bag"), backend)
    assert (folder / INDEX_FILE).read_bytes() == before


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_a_bag_of_another_route_or_robot_is_refused(started, rehearsed, backend, tmp_path):
    copy = copy_of(started, tmp_path)
    other = rehearsed[0] / "batch_002" / REHEARSAL_BAG
    with pytest.raises(InputError, match="another route"):
        add_bag(str(copy), str(other), backend)
    robot = tmp_path / "robot_bag"
    shutil.copytree(rehearsed[0] / "batch_001" / REHEARSAL_BAG, robot)
    meta = yaml.safe_load((robot / "metadata.yaml").read_text())
    custom = meta["rosbag2_bagfile_information"]["custom_data"]
    custom["posegen"] = custom["posegen"].replace(read_index(copy).provenance["robot_model_sha256"], "0" * 64)
    (robot / "metadata.yaml").write_text(yaml.safe_dump(meta))
    with pytest.raises(InputError, match="another robot model"):
        add_bag(str(copy), str(robot), backend)
    assert read_index(copy) == read_index(started)


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_a_file_edited_by_hand_stops_every_command(rehearsed, tmp_path, capsys):
    copy = copy_of(rehearsed[0], tmp_path)
    selection = copy / "batch_002" / "selection.yaml"
    selection.write_text(selection.read_text() + "# edited\n")
    for argv in (
        ["session", "status", str(copy)],
        ["session", "add", str(copy), str(copy / "batch_001" / "route_bag")],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert_one_line_error(err) and "changed since the session wrote it" in err


@pytest.mark.slow  # the started session (1.7 min, shared with the rehearsed one): `make slow`
def test_start_refuses_a_folder_that_holds_a_session(started, backend):
    with pytest.raises(InputError, match="already holds a session"):
        start_session(read_index(started).pool, str(started), SETTINGS, backend)


@pytest.mark.slow  # the started session (1.7 min, shared with the rehearsed one): `make slow`
def test_a_start_that_fails_leaves_no_folder_and_keeps_one_it_was_given(started, backend, tmp_path, monkeypatch):
    import posegen.session.workflow as workflow

    def unroutable(*args, **kwargs):
        raise InfeasibleError("no route")

    monkeypatch.setattr(workflow, "route_batch", unroutable)
    pool = read_index(started).pool
    with pytest.raises(InfeasibleError, match="no route"):
        start_session(pool, str(tmp_path / "new"), SETTINGS, backend)
    assert not (tmp_path / "new").exists()
    (tmp_path / "given").mkdir()
    with pytest.raises(InfeasibleError, match="no route"):
        start_session(pool, str(tmp_path / "given"), SETTINGS, backend)
    assert (tmp_path / "given").is_dir() and not any((tmp_path / "given").iterdir())


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_killed_while_planning_the_next_batch_the_same_add_finishes_it(
    started, rehearsed, backend, tmp_path, monkeypatch
):
    copy = copy_of(started, tmp_path)
    bag = str(rehearsed[0] / "batch_001" / REHEARSAL_BAG)
    import posegen.session.workflow as workflow

    planned = workflow.route_batch

    def killed(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(workflow, "route_batch", killed)
    with pytest.raises(KeyboardInterrupt):
        add_bag(str(copy), bag, backend)
    index = read_index(copy)  # the index names what is complete, nothing more
    assert [b.state for b in index.batches] == [BatchState.ASSESSED]
    monkeypatch.setattr(workflow, "route_batch", planned)
    added = add_bag(str(copy), bag, backend)
    done = read_index(rehearsed[0])  # the same steps, uninterrupted
    first, second = added.index.batches
    assert (first.recording, first.assessment) == (done.batches[0].recording, done.batches[0].assessment)
    assert (second.pool_rows, second.planned_s) == (done.batches[1].pool_rows, done.batches[1].planned_s)


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_a_batch_played_in_part_plans_its_missing_postures_again(started, rehearsed, backend, tmp_path):
    copy = copy_of(started, tmp_path)
    full = RecordedBag(rehearsed[0] / "batch_001" / REHEARSAL_BAG)
    topics = {"left": "/left_wrist_ft", "right": "/right_wrist_ft"}
    joints, wrenches = full.read("/joint_states", list(topics.values()))
    stop = 0.85 * joints.times_s[-1]  # the robot stopped before the end
    keep = joints.times_s <= stop
    cut = JointStates(joints.names, joints.times_s[keep], joints.positions[keep])
    cut_wrenches = {
        t: Wrenches(w.times_s[w.times_s <= stop], w.forces[w.times_s <= stop], w.torques[w.times_s <= stop])
        for t, w in zip(topics.values(), wrenches, strict=True)
    }
    write_recording(tmp_path / "part", cut, "/joint_states", cut_wrenches, full.provenance)
    added = add_bag(str(copy), str(tmp_path / "part"), backend)
    recording = added.batch.recording
    planned = read_index(started).batches[0].pool_rows
    assert 0 < len(recording.missing) < len(planned) and recording.contacts + len(recording.missing) == len(planned)
    assert recording.missing == planned[-len(recording.missing) :]  # the route's last postures
    selection = yaml.safe_load((copy / "batch_002" / "selection.yaml").read_text())
    rows = [p["pool_id"] for p in selection["postures"]]
    assert rows[: len(recording.missing)] == list(recording.missing)  # planned again, first
    follow_up = [p["pool_id"] for p in yaml.safe_load((copy / "batch_002" / "followup.yaml").read_text())["postures"]]
    assert rows[len(recording.missing) :] == follow_up and len(follow_up) == SETTINGS.batch_postures  # all new
    assert not set(follow_up) & set(read_index(started).batches[0].pool_rows)
    assert sorted(added.next_batch.pool_rows) == sorted(rows)  # routed (in the route's own order)
    assert np.isfinite(list(added.batch.assessment.predicted_z_mm.values())).all()


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_the_session_stops_when_every_chain_meets_the_target(started, rehearsed, tmp_path, capsys):
    copy = copy_of(started, tmp_path)
    index = read_index(copy)
    write_index(copy, dataclasses.replace(index, settings=dataclasses.replace(index.settings, target_mm=50.0)))
    bag = str(rehearsed[0] / "batch_001" / REHEARSAL_BAG)
    assert main(["session", "add", str(copy), bag, "--workers", "2", "-q"]) == 0
    out = capsys.readouterr().out
    assert (
        "ok the target 50 mm" in out
        and f"session: done -> the deliverables are in {copy}/batch_001/calibration/" in out
    )
    done = read_index(copy)
    assert done.done and len(done.batches) == 1 and not (copy / "batch_002").exists()
    assert (copy / "batch_001" / "calibration" / "calibrated.urdf").is_file()
    assert main(["session", "add", str(copy), bag, "-q"]) == 2
    assert "already added" in capsys.readouterr().err
    assert main(["session", "rehearse", str(copy), "--seed", "3", "-q"]) == 0
    assert "is done already" in capsys.readouterr().out


@pytest.mark.slow  # the rehearsed session (3 min, shared by these tests): `make slow`
def test_the_session_stops_at_the_floor_when_batches_bring_no_new_low(started, rehearsed, backend, tmp_path, capsys):
    copy = copy_of(started, tmp_path)
    first = add_bag(str(copy), str(rehearsed[0] / "batch_001" / REHEARSAL_BAG), backend)
    assert first.next_batch is not None and not first.index.ended  # one figure: nothing to compare yet
    index = read_index(copy)  # as rehearsed so far; now an unreachable target, and a low no batch can beat
    unreachable = dataclasses.replace(index.settings, target_mm=0.01, patience=1)
    low = dataclasses.replace(index.batches[0].assessment, predicted_z_mm={CHAIN: 0.02})
    index = index.with_batch(dataclasses.replace(index.batches[0], assessment=low))
    write_index(copy, dataclasses.replace(index, settings=unreachable))
    rehearse = ["session", "rehearse", str(copy), "--seed", "3", "--compliance", "0.3", "--workers", "2", "-q"]
    assert main([*rehearse, "--max-batches", "5"]) == 0  # batch 2 played on the same robot, then the rule stops it
    out = capsys.readouterr().out
    assert "session: stopped at the floor: no chain above the target 0.01 mm reached a new low in the last 1" in out
    assert "not done after" not in out
    ended = read_index(copy)
    assert ended.at_floor and not ended.done and len(ended.batches) == 2 and not (copy / "batch_003").exists()
    assert main(["session", "add", str(copy), str(copy / "batch_002" / REHEARSAL_BAG), "-q"]) == 2
    assert "already added" in capsys.readouterr().err
    assert main(rehearse) == 0
    assert "stopped at the floor already" in capsys.readouterr().out
    assert main(["session", "status", str(copy), "--plot", str(tmp_path / "s.png")]) == 0
    assert "stopped at the floor" in capsys.readouterr().out
