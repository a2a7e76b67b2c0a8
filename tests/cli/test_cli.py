"""The command line: clean one-line errors, exit codes, no partial output files."""

import numpy as np
import yaml

from posegen.calibrate import truth_of
from posegen.cli import main
from posegen.io import companion_of, write_yaml
from tests.conftest import CONFIG


def run(argv, capsys):
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def assert_one_line_error(err):
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("posegen: error: "), err
    assert "Traceback" not in err


def assert_fails_cleanly(argv, out, capsys):
    """The command exits 2 with a one-line error and writes no output file; returns the error."""
    code, _, err = run(argv, capsys)
    assert code == 2
    assert_one_line_error(err)
    assert not out.exists()
    return err


def bad_config(tmp_path, edit):
    data = yaml.safe_load(CONFIG.read_text())
    edit(data)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


def empty_pool_file(pool, tmp_path):
    data = pool.to_dict()
    data["postures"] = []
    path = tmp_path / "empty.yaml"
    write_yaml(path, data)
    return path


def test_pool_writes_file_and_summary(tmp_path, capsys):
    out = tmp_path / "pool.yaml"
    code, stdout, _ = run(["pool", "--n", "6", "--workers", "1", "-q", "-o", str(out)], capsys)
    assert code == 0
    assert "6 postures accepted" in stdout and "rejected:" in stdout
    assert out.exists() and not (tmp_path / "pool.yaml.partial.jsonl").exists()
    code, stdout, _ = run(["check", str(out), "-q"], capsys)
    assert code == 0 and "FAIL" not in stdout


def test_unknown_frame_in_config(tmp_path, capsys):
    path = bad_config(tmp_path, lambda d: d["chains"]["left"].update(gripper_frame="left_hand"))
    out = tmp_path / "pool.yaml"
    err = assert_fails_cleanly(["pool", "--n", "3", "--config", path, "-o", str(out), "-q"], out, capsys)
    assert "unknown frame 'left_hand'" in err and "gripper_left_base_link" in err


def test_table_out_of_reach(tmp_path, capsys):
    path = bad_config(tmp_path, lambda d: d["table"].update(top_center_m=[2.5, 0.0, 0.7]))
    out = tmp_path / "pool.yaml"
    argv = ["pool", "--n", "3", "--workers", "1", "--config", path, "-o", str(out), "-q"]
    err = assert_fails_cleanly(argv, out, capsys)
    assert "table.top_center_m: out of reach of chain" in err


def test_nonpositive_n(tmp_path, capsys):
    out = tmp_path / "pool.yaml"
    assert_fails_cleanly(["pool", "--n", "0", "-o", str(out), "-q"], out, capsys)


def test_malformed_config_yaml(tmp_path, capsys):
    path = tmp_path / "broken.yaml"
    path.write_text("robot: {source: [\n")
    code, _, err = run(["pool", "--n", "3", "--config", str(path), "-q"], capsys)
    assert code == 2
    assert_one_line_error(err)


def test_check_flags_a_tampered_pool(small_pool, tmp_path, capsys):
    data = small_pool.to_dict()
    hip = data["joint_names"].index("leg_left_3_joint")
    data["postures"][3]["joints"][hip] += 0.05  # a left hip pitch: the right sole and the hand leave their places
    path = tmp_path / "tampered.yaml"
    write_yaml(path, data)
    code, stdout, _ = run(["check", str(path), "-q"], capsys)
    assert code == 1
    assert "FAIL sole" in stdout and "FAIL contact" in stdout and "posture 3" in stdout


def test_check_verifies_a_selection_and_flags_its_tampered_posture(selection_file, tmp_path, capsys):
    data = yaml.safe_load(selection_file.read_text())
    data["postures"] = data["postures"][:4]  # the check of four postures: quick
    path = tmp_path / "selected.yaml"
    write_yaml(path, data)
    code, stdout, _ = run(["check", str(path), "-q"], capsys)
    assert code == 0 and f"checked 4 postures of {path}" in stdout and "FAIL" not in stdout
    hip = data["joint_names"].index("leg_left_3_joint")
    data["postures"][2]["joints"][hip] += 0.05  # the right sole and the hand leave their places
    write_yaml(path, data)
    code, stdout, _ = run(["check", str(path), "-q"], capsys)
    assert code == 1 and "FAIL sole" in stdout and "posture 2" in stdout


def test_check_rejects_files_that_are_not_pools(tmp_path, capsys):
    path = tmp_path / "notapool.yaml"
    path.write_text("format: something-else\n")
    code, _, err = run(["check", str(path)], capsys)
    assert code == 2
    assert_one_line_error(err)
    code, _, err = run(["check", str(tmp_path / "missing.yaml")], capsys)
    assert code == 2
    assert_one_line_error(err)


def test_simulate_then_calibrate(tmp_path, capsys):
    from tests.conftest import EXAMPLE_POOL

    meas = tmp_path / "meas.yaml"
    code, stdout, _ = run(["simulate", str(EXAMPLE_POOL), "--seed", "2", "-o", str(meas)], capsys)
    assert code == 0 and meas.exists()
    truth = truth_of(meas)  # named by the measurements' bytes: edited, the file has no truth any more
    assert truth.parent == tmp_path and yaml.safe_load(truth.read_text())["format"] == "posegen-truth"
    assert truth.name in stdout
    out = tmp_path / "cal"
    argv = ["calibrate", f"{meas}@day1", "--prior-scale", "5", "--candidates", "offsets", "offsets_legs"]
    code, stdout, _ = run([*argv, "--fold-seeds", "1", "-q", "-o", str(out)], capsys)
    assert code == 0, stdout
    assert "training" in stdout and (out / "calibrated.urdf").exists()
    assert (out / "report.html").exists() and "report.html" in stdout
    assert "predicted held-out (grouped CV)  left " in stdout
    assert "interpretable model (one-standard-error rule; not a file): offsets" in stdout


def test_simulate_contact_noise_is_recorded_and_checked(tmp_path, capsys):
    from tests.conftest import EXAMPLE_POOL

    plain, noisy = tmp_path / "plain.yaml", tmp_path / "noisy.yaml"
    assert run(["simulate", str(EXAMPLE_POOL), "--seed", "2", "-o", str(plain)], capsys)[0] == 0
    argv = ["simulate", str(EXAMPLE_POOL), "--seed", "2", "--contact-noise-mm", "3", "--contact-noise-deg", "0.3"]
    assert run([*argv, "-o", str(noisy)], capsys)[0] == 0
    simulation = yaml.safe_load(noisy.read_text())["provenance"]["simulation"]
    assert simulation["contact_noise_mm"] == 3.0 and simulation["contact_noise_deg"] == 0.3
    assert "contact_noise_mm" not in yaml.safe_load(plain.read_text())["provenance"]["simulation"]
    truth = {p.name: yaml.safe_load(truth_of(p).read_text()) for p in (plain, noisy)}
    assert truth["plain.yaml"]["parameters"] == truth["noisy.yaml"]["parameters"]  # the same robot and table
    joints = [np.array([c["joints"] for c in yaml.safe_load(p.read_text())["contacts"]]) for p in (plain, noisy)]
    assert 1e-4 < np.abs(joints[0] - joints[1]).max() < 0.1  # the joints carry the local planes
    out = tmp_path / "bad.yaml"
    err = assert_fails_cleanly(["simulate", str(EXAMPLE_POOL), "--contact-noise-mm", "-1", "-o", str(out)], out, capsys)
    assert "--contact-noise-mm" in err


def test_calibrate_real_csv(tmp_path, capsys, real_data):
    out = tmp_path / "real"
    code, stdout, _ = run(
        [
            "calibrate",
            str(real_data / "left_train.csv"),
            str(real_data / "right_train.csv"),
            "--validate",
            str(real_data / "left_validation.csv"),
            "--candidates",
            "offsets_hip_pitch",
            "--prior-scale",
            "10",
            "--fold-seeds",
            "1",
            "-q",
            "-o",
            str(out),
        ],
        capsys,
    )
    assert code == 0
    head = stdout.splitlines()[:3]  # the files written lead, each with its predicted and its held-out error
    assert head[1].startswith("  calibrated.urdf (any stack;") and "predicted held-out (grouped CV)  left " in head[2]
    assert "interpretable model (one-standard-error rule; not a file): offsets_hip_pitch x10" in stdout
    assert any(line.startswith("held-out  left    calibrated.urdf          9") for line in stdout.splitlines())
    assert "right_train.csv:4 (table/contact_19): residual" in stdout  # a bad row, with its file and line


def test_calibrate_unknown_candidate(tmp_path, capsys):
    from tests.conftest import REAL_DATA

    out = tmp_path / "out"
    argv = ["calibrate", str(REAL_DATA / "left_train.csv"), "--candidates", "nonsense", "-q", "-o", str(out)]
    err = assert_fails_cleanly(argv, out, capsys)
    assert "nonsense" in err and "offsets_hip_pitch" in err


def test_calibrate_bad_file(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("joint_names,arm_left_1_joint\ngripper,talos/left_gripper,handle,x,joint_states,abc\n")
    out = tmp_path / "out"
    assert_fails_cleanly(["calibrate", str(bad), "-q", "-o", str(out)], out, capsys)


def test_select_then_simulate_the_selection(tmp_path, capsys):
    from tests.conftest import EXAMPLE_POOL

    out = tmp_path / "selected.yaml"
    argv = ["select", str(EXAMPLE_POOL), "--k", "70", "--runs", "1", "--fraction", "0.8", "-q", "-o", str(out)]
    code, stdout, _ = run(argv, capsys)
    assert code == 0, stdout
    assert "70 of 200 postures" in stdout and "DETMAX best of 1" in stdout and "80% of O1* at k = " in stdout
    data = yaml.safe_load(out.read_text())
    assert data["format"] == "posegen-selection" and len(data["postures"]) == 70
    assert data["provenance"]["robot_model_sha256"] and data["figures"]["certificate"]["kiefer_wolfowitz_gap"] <= 1e-4
    assert (tmp_path / "selected_o1.png").exists() and (tmp_path / "selected_detmax.png").exists()
    code, _, _ = run(["simulate", str(out), "-o", str(tmp_path / "m.yaml")], capsys)
    assert code == 0


def test_select_on_an_empty_pool(small_pool, tmp_path, capsys):
    path = empty_pool_file(small_pool, tmp_path)
    out = tmp_path / "sel.yaml"
    err = assert_fails_cleanly(["select", str(path), "-q", "-o", str(out)], out, capsys)
    assert "empty" in err


def test_route_errors(small_pool, tmp_path, capsys):
    garbage = tmp_path / "garbage.yaml"
    garbage.write_text("format: posegen-selection\nformat_version: 1\njoint_names: 3\n")
    out = tmp_path / "route.yaml"
    assert_fails_cleanly(["route", str(garbage), "-q", "-o", str(out)], out, capsys)
    empty = empty_pool_file(small_pool, tmp_path)
    assert "no postures" in assert_fails_cleanly(["route", str(empty), "-q", "-o", str(out)], out, capsys)


def test_route_then_check(tmp_path, capsys):
    from tests.conftest import EXAMPLE_POOL

    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][4:6]
    two = tmp_path / "two.yaml"
    write_yaml(two, data)
    out = tmp_path / "route.json"
    code, stdout, _ = run(["route", str(two), "--workers", "1", "--csv", "-q", "-o", str(out)], capsys)
    assert code == 0 and "2 of 2 postures" in stdout and out.exists()
    assert len(list(tmp_path.glob("route.json.*.npz"))) == 1
    csv = companion_of(out, ".csv")  # named by the header's bytes: replaced with it as one
    assert csv is not None and csv.name in stdout and csv.read_text().startswith("time_s,segment,chain,posture,")
    code, stdout, _ = run(["check", str(out), "--workers", "1", "-q"], capsys)
    assert code == 0 and "FAIL" not in stdout and "points" in stdout
    code, stdout, _ = run(["check", str(out), "--workers", "1", "--min-dt", "5", "-q"], capsys)
    assert code == 1 and "FAIL times" in stdout and "minimum 5.000e+00 s" in stdout


def test_unreachable_scheduler_fails_before_any_work(tmp_path, capsys, monkeypatch):
    from posegen.parallel import cluster

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1.0)
    out = tmp_path / "pool.yaml"
    err = assert_fails_cleanly(
        ["pool", "--n", "2", "--scheduler", "tcp://127.0.0.1:9", "-q", "-o", str(out)], out, capsys
    )
    assert "cannot reach the Dask scheduler" in err
    assert not list(tmp_path.glob("*.npz"))


def test_route_repairs_a_selection_from_its_pool(scene, selection_file, tmp_path, capsys):
    """A selected posture that cannot be reached is replaced by a pool posture, and the swap is reported."""
    import hashlib

    from posegen.io import load_pool
    from tests.conftest import EXAMPLE_POOL, routable_rows

    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    rows = [0, *routable_rows(scene, load_pool(EXAMPLE_POOL), 9, 2)]  # row 0 among them: a falsy row counts in O1
    postures = [{"pool_id": r, "rank": i + 1, "weight": 0.1, **data["postures"][r]} for i, r in enumerate(rows)]
    other = "right" if postures[1]["chain"] == "left" else "left"
    k = scene.joint_index(f"arm_{other}_1_joint")
    postures[1]["joints"][k] = float(scene.upper[k])  # no valid state above this contact
    figures = yaml.safe_load(selection_file.read_text())["figures"]  # a whole section (of another selection)
    data.update(format="posegen-selection", postures=postures, method="k", figures=figures)
    data["provenance"] = {
        **data["provenance"],
        "pool": str(EXAMPLE_POOL),
        "pool_sha256": hashlib.sha256(EXAMPLE_POOL.read_bytes()).hexdigest(),
    }
    selection = tmp_path / "selected.yaml"
    write_yaml(selection, data)
    out = tmp_path / "route.yaml"
    code, stdout, _ = run(["route", str(selection), "--workers", "1", "-q", "-o", str(out)], capsys)
    assert code == 0 and "3 of 3 postures (1 substituted)" in stdout
    assert "posture 1 replaced by pool posture" in stdout and "vertical approach" in stdout
    header = yaml.safe_load(out.read_text())
    (swap,) = header["substitutions"]
    assert swap["pool_id"] == rows[1] and swap["substitute_pool_id"] not in rows and not header["skipped"]
    assert [p["pool_id"] for p in header["postures"]].count(swap["substitute_pool_id"]) == 1
    information = header["summary"]["information"]
    assert information["rank_routed"] == information["rank_selected"] == 9  # 3 postures x 3 rows, all counted


def test_robot_init_unknown_name(tmp_path, capsys):
    out = tmp_path / "new.yaml"
    err = assert_fails_cleanly(["robot", "init", "talosfull", "-o", str(out)], out, capsys)
    assert "did you mean talos_full" in err


def test_robot_pairs_prints_the_block_to_paste(capsys):
    from tests.conftest import ROOT

    config = str(ROOT / "configs" / "talos_full_table.yaml")
    code, stdout, _ = run(["robot", "pairs", config, "--samples", "20"], capsys)
    assert code == 0
    pasted = yaml.safe_load(stdout)
    assert {frozenset(p[:2]) for p in pasted["disabled_pairs"]} == {
        frozenset(("gripper_left_inner_double_link", "gripper_left_inner_single_link")),
        frozenset(("gripper_right_inner_double_link", "gripper_right_inner_single_link")),
    }


def test_reference_posture_in_collision(tmp_path, capsys):
    bent = {"torso_2_joint": 0.7, "arm_left_1_joint": -1.5}
    path = bad_config(tmp_path, lambda d: d["stance"].update(reference_joints=bent))
    out = tmp_path / "pool.yaml"
    argv = ["pool", "--n", "3", "--workers", "1", "--config", path, "-o", str(out), "-q"]
    err = assert_fails_cleanly(argv, out, capsys)
    assert "stance.reference_posture: 'half_sitting' with stance.reference_joints is in collision" in err


def test_route_routes_a_repeated_posture_once_and_says_so(tmp_path, capsys):
    from tests.conftest import EXAMPLE_POOL

    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = [data["postures"][4], data["postures"][5], data["postures"][4]]
    plan = tmp_path / "twice.yaml"
    write_yaml(plan, data)
    out = tmp_path / "route.yaml"
    code, stdout, err = run(["route", str(plan), "--workers", "1", "-o", str(out)], capsys)
    assert code == 0, err
    assert "posture 2 repeats posture 0 (same chain and joints): routed once" in err
    header = yaml.safe_load(out.read_text())
    assert header["summary"]["repeated"] == [{"posture": 2, "same_as": 0}]
    assert len(header["postures"]) == 2 and "2 of 2 postures" in stdout


def test_simulate_bag_and_measure_take_a_route_whose_joints_are_in_another_order(route_file, tmp_path, capsys):
    import numpy as np

    from posegen.io import ROUTE_ARRAYS, RecordedBag, read_arrays, write_with_arrays

    header = yaml.safe_load(route_file.read_text())
    arrays = read_arrays(route_file, header.pop("arrays"), ROUTE_ARRAYS)
    order = np.random.default_rng(0).permutation(len(header["trajectory"]["joint_names"]))
    header["trajectory"]["joint_names"] = [header["trajectory"]["joint_names"][j] for j in order]
    arrays = {k: v if v.ndim == 1 else np.asfortranarray(v[:, order]) for k, v in arrays.items()}
    shuffled = tmp_path / "shuffled.yaml"
    write_with_arrays(shuffled, header, arrays, compress=True)
    joints = {}
    for name, route in (("plain", route_file), ("shuffled", shuffled)):
        bag = tmp_path / f"{name}_bag"
        argv = ["simulate", str(route), "--bag", str(bag), "--rate", "100", "--seed", "3", "-q"]
        code, _, err = run(argv, capsys)
        assert code == 0, err
        joints[name] = RecordedBag(bag).read_and_hash("/joint_states", [])[0]
        out = tmp_path / f"measured_{name}.yaml"
        code, _, err = run(["measure", str(bag), "--route", str(route), "--session", "s", "-q", "-o", str(out)], capsys)
        assert code == 0, err
        joints[name + " contacts"] = [c["joints"] for c in yaml.safe_load(out.read_text())["contacts"]]
    assert joints["plain"].names == joints["shuffled"].names  # recorded in the robot's order
    assert np.array_equal(joints["plain"].positions, joints["shuffled"].positions)
    assert joints["plain contacts"] == joints["shuffled contacts"] and joints["plain contacts"]


def test_q_holds_warnings_only_while_main_runs(tmp_path, capsys):
    import logging
    import logging.handlers

    code, _, err = run(["check", str(tmp_path / "nothing.yaml"), "-q"], capsys)
    assert code == 2 and err.count("\n") == 1
    assert not any(isinstance(h, logging.handlers.MemoryHandler) for h in logging.getLogger().handlers)
