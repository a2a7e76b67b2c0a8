"""Artefact reads: only a regular file's text, a path checked before it is used."""

import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from posegen.errors import InputError
from posegen.io import read_text_file, read_yaml


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "pool.yaml"
    os.mkfifo(fifo)
    outcome: list[BaseException] = []
    reader = threading.Thread(target=lambda: _capture(outcome, fifo), daemon=True)
    reader.start()
    reader.join(timeout=10)
    if reader.is_alive():  # the old read blocked here: open a writer so the thread ends, then fail
        with open(fifo, "w"):
            pass
        pytest.fail("reading a FIFO waited for a writer")
    assert len(outcome) == 1 and isinstance(outcome[0], InputError)
    assert "not a regular file" in str(outcome[0])


def _capture(outcome: list[BaseException], path: Path) -> None:
    try:
        read_yaml(path, "posegen-pool")
    except BaseException as exc:  # handed to the test's thread
        outcome.append(exc)


# /dev/null stands for every device: it ends at once, so a reader that wrongly reads it fails the test
# instead of filling the memory as /dev/zero would.
@pytest.mark.skipif(not Path("/dev/null").exists(), reason="no /dev/null on this system")
def test_a_device_is_refused():
    with pytest.raises(InputError, match="/dev/null: not a regular file"):
        read_text_file(Path("/dev/null"), InputError)


@pytest.mark.skipif(not Path("/dev/null").exists(), reason="no /dev/null on this system")
def test_check_on_a_device_exits_with_one_line():
    posegen = str(Path(sys.executable).parent / "posegen")
    run = subprocess.run([posegen, "check", "/dev/null"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert "not a regular file" in run.stderr and "Traceback" not in run.stderr


def test_a_folder_keeps_the_system_message(tmp_path):
    with pytest.raises(InputError, match="Is a directory"):
        read_text_file(tmp_path, InputError)


@pytest.mark.parametrize("path", [None, 3, ["pool.yaml"], ""])
def test_read_yaml_refuses_what_is_not_a_path(path):
    with pytest.raises(InputError, match="expected a file's path"):
        read_yaml(path, "posegen-pool")


def test_read_compliance_of_none_is_an_input_error():
    from posegen import read_compliance

    with pytest.raises(InputError, match="expected a file's path"):
        read_compliance(None)  # type: ignore[arg-type]


def test_a_key_given_twice_is_refused_naming_it_and_its_line(tmp_path):
    """YAML keeps the last of two keys without a word: a second ``table:`` block read as "table.size_m: missing"."""
    from posegen.errors import ConfigError
    from posegen.io import load_yaml_file
    from posegen.robot import load_config
    from tests.conftest import CONFIG

    path = tmp_path / "twice.yaml"
    path.write_text("a: 1\nb: {c: 2, c: 3}\n")
    with pytest.raises(InputError, match=r"twice\.yaml: not valid YAML \(the key 'c' is given twice \(line 2\)\)$"):
        load_yaml_file(path, InputError)
    path.write_text("x: &x {a: 1}\ny:\n  <<: *x\n  a: 2\nz: [1, 1]\n")  # a merged key given again overrides it
    assert load_yaml_file(path, InputError) == {"x": {"a": 1}, "y": {"a": 2}, "z": [1, 1]}
    text = Path(CONFIG).read_text()
    config = tmp_path / "config.yaml"
    config.write_text(text.replace("\ntable:\n", "\ntable:\n  yaw_deg: 45.0\n", 1))
    assert "yaw_deg" in text.split("\ntable:\n", 1)[1].split("\n\n", 1)[0]  # the config gives it already
    with pytest.raises(ConfigError, match=r"the key 'yaw_deg' is given twice \(line \d+\)"):
        load_config(config)
