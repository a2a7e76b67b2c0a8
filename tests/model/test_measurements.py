import re

import numpy as np
import pytest

from posegen.errors import InputError
from posegen.model import measurement_item, read_measurements, write_measurements


@pytest.mark.parametrize(
    ("name", "rows", "chain"),
    [("left_train", 21, "left"), ("left_validation", 9, "left"), ("right_train", 29, "right")],
)
def test_real_csv_layouts(scene, real_data, name, rows, chain):
    recording = read_measurements(real_data / f"{name}.csv", scene)
    contacts = recording.contacts
    assert len(contacts) == rows and recording.rejected == ()
    assert set(contacts.chains) == {chain}
    assert set(contacts.sessions) == {name}
    assert contacts.labels[0].startswith(f"{name}.csv:2:table/contact_")
    assert np.all(np.abs(contacts.joints) < 3.2)


def test_session_override(scene, real_data):
    contacts = read_measurements(real_data / "left_validation.csv", scene, "day2").contacts
    assert set(contacts.sessions) == {"day2"}


def _copy_with(tmp_path, edit, real_data):
    lines = (real_data / "left_train.csv").read_text().splitlines()
    lines = edit(lines)
    path = tmp_path / "edited.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_shifted_column_is_reported(scene, real_data, tmp_path):
    def shift(lines):
        cells = lines[3].split(",")
        cells.insert(5, "0.0")  # every angle moves one column right
        lines[3] = ",".join(cells[:-1])
        return lines

    recording = read_measurements(_copy_with(tmp_path, shift, real_data), scene)
    assert len(recording.contacts) == 20  # the other rows are kept
    assert len(recording.rejected) == 1 and re.search(r"edited.csv:4: .* outside its limits", recording.rejected[0])


def _angle_field(text):
    """An edit of the CSV's second data row: its tenth field becomes ``text``."""

    def put(lines):
        cells = lines[2].split(",")
        cells[10] = text
        lines[2] = ",".join(cells)
        return lines

    return put


def test_a_huge_angle_is_reported_in_a_few_digits(scene, real_data, tmp_path):
    recording = read_measurements(_copy_with(tmp_path, _angle_field("1e300"), real_data), scene)
    [message] = recording.rejected
    assert re.search(r"edited.csv:3: \w+ = 1e\+300 rad is outside its limits", message) and len(message) < 250


def test_a_folder_is_no_measurement_file(scene, tmp_path):
    with pytest.raises(InputError, match=rf"^{re.escape(str(tmp_path))}: a folder, not a measurement file"):
        read_measurements(tmp_path, scene)
    with pytest.raises(InputError, match="measurement file not found"):
        read_measurements(tmp_path / "nothing.yaml", scene)


def test_text_in_an_angle_field_is_reported(scene, real_data, tmp_path):
    recording = read_measurements(_copy_with(tmp_path, _angle_field("handle"), real_data), scene)
    assert recording.rejected == (
        f"{tmp_path / 'edited.csv'}:3: angle field 'handle' is not a number (shifted column?)",
    )


def test_unknown_gripper_no_usable_row_and_missing_header(scene, real_data, tmp_path):
    with pytest.raises(InputError, match=r"no usable data row .* no known gripper"):
        read_measurements(
            _copy_with(tmp_path, lambda ls: [ls[0], ls[1].replace("talos/left_gripper", "hand")], real_data), scene
        )
    with pytest.raises(InputError, match="no header"):
        read_measurements(_copy_with(tmp_path, lambda ls: ls[1:], real_data), scene)


def test_posegen_format_round_trip(scene, real_data, tmp_path):
    contacts = read_measurements(real_data / "right_train.csv", scene).contacts
    path = tmp_path / "m.yaml"
    write_measurements(path, scene, contacts, {"seed": 0})
    again = read_measurements(path, scene).contacts
    assert again.joints == pytest.approx(contacts.joints, abs=0)
    assert again.chains == contacts.chains and again.sessions == contacts.sessions


def test_a_measurement_file_is_read_with_its_provenance(scene, tmp_path):
    from posegen.io import write_yaml
    from posegen.model import Contacts, measurement_provenance, measurements_to_dict

    chain = scene.chains[0].name
    contacts = Contacts(scene.reference[None, :].copy(), (chain,), ("day",), ("c0",))
    provenance = scene.provenance(5)
    write_measurements(tmp_path / "m.yaml", scene, contacts, provenance)
    read = read_measurements(tmp_path / "m.yaml", scene)
    assert read.provenance == provenance == measurement_provenance(tmp_path / "m.yaml")
    assert read.rejected == () and read.contacts.chains == (chain,)
    csv = _one_row_csv(tmp_path / "m.csv", scene.joint_names, scene.reference)
    assert read_measurements(csv, scene).provenance == {}  # a recorded table says nothing of what made it
    write_yaml(tmp_path / "bad.yaml", measurements_to_dict(scene, contacts, provenance) | {"provenance": [1]})
    for reader in (
        lambda: read_measurements(tmp_path / "bad.yaml", scene),
        lambda: measurement_provenance(tmp_path / "bad.yaml"),
    ):
        with pytest.raises(InputError, match="'provenance' must be a mapping"):
            reader()


@pytest.mark.parametrize(
    ("edit", "message"),
    [  # a helper's edits that calibrate and select --given took
        (lambda c: c[1].pop("end_s"), r"contact 1: no end_s, which the other contacts have: a truncated or edited"),
        (lambda c: c[0].update(start_s="yesterday"), r"contact 0: start_s 'yesterday', end_s 2\.5: expected finite"),
        (lambda c: c[1].update(start_s=9.0), r"contact 1: start_s 9\.0, end_s 4\.5: expected finite times"),
        (lambda c: c[0].update(samples=-5), r"contact 0: samples -5: expected a count of 1 or more"),
        (lambda c: c[1].update(force_n=float("nan")), r"contact 1: joint_std_rad 0\.001, force_n nan: expected"),
        (lambda c: c[0].update(session=["a"]), r"contact 0: 'session' must be a name, got \['a'\]"),
    ],
)
def test_a_contact_measure_found_is_checked_whole(scene, tmp_path, edit, message):
    from posegen.io import write_yaml
    from posegen.model import Contacts, measurements_to_dict

    chain = scene.chains[0].name
    contacts = Contacts(np.repeat(scene.reference[None, :], 2, axis=0), (chain,) * 2, ("day",) * 2, ("c0", "c1"))
    data = measurements_to_dict(scene, contacts, scene.provenance(5))
    for k, contact in enumerate(data["contacts"]):  # the window fields `measure` writes
        contact.update(start_s=2.0 * k + 0.5, end_s=2.0 * k + 2.5, samples=400, joint_std_rad=0.001, force_n=31.0)
    write_yaml(tmp_path / "good.yaml", data)
    assert len(read_measurements(tmp_path / "good.yaml", scene).contacts.chains) == 2
    edit(data["contacts"])
    write_yaml(tmp_path / "bad.yaml", data)
    with pytest.raises(InputError, match=message):
        read_measurements(tmp_path / "bad.yaml", scene)


def test_missing_file(scene, tmp_path):
    with pytest.raises(InputError, match="not found"):
        read_measurements(tmp_path / "nothing.csv", scene)


def _one_row_csv(path, names, values):
    path.write_text(
        f"joint_names,{','.join(names)}\n"
        f"gripper,talos/left_gripper,handle,x,joint_states,{','.join(repr(float(v)) for v in values)}\n"
    )
    return path


def test_a_free_joint_without_a_column_is_an_error_naming_it(scene, tmp_path):
    names = list(scene.joint_names)
    free = [n for n, locked in zip(names, scene.locked, strict=True) if not locked]
    gone = free[len(free) // 2]
    kept = [n for n in names if n != gone]
    values = [scene.reference[scene.joint_index(n)] for n in kept]
    with pytest.raises(InputError, match=rf"no column for joint {gone} \(only the joints the config locks"):
        read_measurements(_one_row_csv(tmp_path / "m.csv", kept, values), scene)


def test_a_locked_joint_may_be_absent(scene, tmp_path):
    names = list(scene.joint_names)
    locked = [n for n, lock in zip(names, scene.locked, strict=True) if lock]
    if not locked:
        pytest.skip("the config locks no joint")
    kept = [n for n in names if n != locked[0]]
    values = [scene.reference[scene.joint_index(n)] for n in kept]
    contacts = read_measurements(_one_row_csv(tmp_path / "m.csv", kept, values), scene).contacts
    assert contacts.joints[0, scene.joint_index(locked[0])] == scene.reference[scene.joint_index(locked[0])]


def test_a_joint_column_given_twice_is_an_error(scene, tmp_path):
    names = [*scene.joint_names, scene.joint_names[3]]
    values = [scene.reference[scene.joint_index(n)] for n in names]
    with pytest.raises(InputError, match=rf"joint column {scene.joint_names[3]} given twice"):
        read_measurements(_one_row_csv(tmp_path / "m.csv", names, values), scene)


def test_a_yaml_file_without_a_free_joint_is_an_error(scene, tmp_path):
    from posegen.io import write_yaml
    from posegen.model import Contacts, measurements_to_dict

    contacts = Contacts(scene.reference[None, :].copy(), ("left",), ("s",), ("c",))
    data = measurements_to_dict(scene, contacts, {"seed": 0})
    free = next(n for n, locked in zip(scene.joint_names, scene.locked, strict=True) if not locked)
    k = data["joint_names"].index(free)
    data["joint_names"].pop(k)
    data["contacts"][0]["joints"].pop(k)
    write_yaml(tmp_path / "m.yaml", data)
    with pytest.raises(InputError, match=rf"no column for joint {free}"):
        read_measurements(tmp_path / "m.yaml", scene)


@pytest.mark.parametrize(
    ("item", "parsed"),
    [
        ("m.yaml", ("m.yaml", None)),
        ("m.yaml@day1", ("m.yaml", "day1")),
        ("day@@2.csv", ("day@2.csv", None)),
        ("day@@2.csv@morning", ("day@2.csv", "morning")),
        ("a@@@@b.csv@s@@1", ("a@@b.csv", "s@1")),
    ],
)
def test_measurement_items_and_their_escaped_at_signs(item, parsed):
    assert measurement_item(item) == parsed


def test_an_at_sign_without_a_session_is_an_error():
    with pytest.raises(InputError, match="no session name after '@'"):
        measurement_item("m.yaml@")
