"""Outputs: checked before the work, one writer at a time, nothing left behind by a failure."""

import logging
import os
import subprocess
import sys

import pytest

from posegen.errors import OutputError
from posegen.io import (
    OutputKind,
    OutputLock,
    atomic_path,
    check_apart,
    check_writable,
    claim_output,
    lock_path,
    write_atomic,
)


def test_a_second_writer_fails_at_once_naming_the_first(tmp_path):
    output = tmp_path / "pool.yaml"
    with OutputLock(output):
        assert lock_path(output).read_text().strip() == str(os.getpid())
        with pytest.raises(OutputError, match=rf"pool.yaml is being written by another posegen \(pid {os.getpid()}\)"):
            OutputLock(output).acquire()
    assert not lock_path(output).exists()  # released: the lock file is gone
    with OutputLock(output):  # and the output can be claimed again
        pass


def test_a_lock_held_by_another_process(tmp_path):
    output = tmp_path / "out.yaml"
    holder = subprocess.Popen(
        [sys.executable, "-c", f"from posegen.io import OutputLock; OutputLock({str(output)!r}).acquire(); input()"],
        stdin=subprocess.PIPE,
    )
    try:
        while not lock_path(output).exists() or not lock_path(output).read_text():
            assert holder.poll() is None
        with pytest.raises(OutputError, match=f"pid {holder.pid}"):
            OutputLock(output).acquire()
    finally:
        holder.kill()
        holder.wait()
    with OutputLock(output):  # the kernel released the dead holder's lock
        pass


def test_a_stale_lock_is_taken_over_with_a_line(tmp_path, caplog):
    output = tmp_path / "pool.yaml"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    lock_path(output).write_text(dead.stdout)
    with caplog.at_level(logging.WARNING), OutputLock(output):
        pass
    assert f"left by posegen pid {dead.stdout.strip()}, which is no longer running" in caplog.text


def test_claim_removes_the_folders_it_made_when_the_work_fails(tmp_path):
    output = tmp_path / "a" / "b" / "pool.yaml"
    with pytest.raises(RuntimeError), claim_output(output):
        assert output.parent.is_dir() and lock_path(output).exists()
        raise RuntimeError("the work failed")
    assert list(tmp_path.iterdir()) == []
    with claim_output(output):
        write_atomic(output, "done\n")
    assert sorted(p.name for p in output.parent.iterdir()) == ["pool.yaml"]


def test_claim_keeps_a_folder_that_holds_a_checkpoint(tmp_path):
    output = tmp_path / "new" / "pool.yaml"
    with pytest.raises(KeyboardInterrupt), claim_output(output):
        output.with_name("pool.yaml.partial.jsonl").write_text("{}\n")
        raise KeyboardInterrupt
    assert [p.name for p in (tmp_path / "new").iterdir()] == ["pool.yaml.partial.jsonl"]


@pytest.mark.parametrize(
    ("make", "kind", "message"),
    [
        (lambda t: (t / "x").mkdir(), OutputKind.FILE, "is a folder"),
        (lambda t: (t / "x").write_text(""), OutputKind.FOLDER, "not a folder"),
        (lambda t: None, OutputKind.FILE, None),
        (lambda t: (t / "x").write_text("old"), OutputKind.FILE, None),
    ],
)
def test_check_writable(tmp_path, make, kind, message):
    make(tmp_path)
    if message is None:
        check_writable(tmp_path / "x", kind)
    else:
        with pytest.raises(OutputError, match=message):
            check_writable(tmp_path / "x", kind)
    assert [p.name for p in tmp_path.iterdir()] in ([], ["x"])  # the check changed nothing


def test_check_writable_inside_a_file_or_a_special_file(tmp_path):
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputError, match="not a folder"):
        check_writable(tmp_path / "file" / "sub" / "out.yaml")
    with pytest.raises(OutputError, match="not a regular file"):
        check_writable("/dev/null")


def test_atomic_path_leaves_the_old_file_when_the_writer_fails(tmp_path):
    path = tmp_path / "plot.png"
    path.write_bytes(b"old")
    with pytest.raises(ValueError), atomic_path(path) as tmp:
        tmp.write_bytes(b"half")
        raise ValueError
    assert path.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["plot.png"]
    with atomic_path(path) as tmp:
        assert tmp.suffix == ".png"  # writers that pick a format by extension still do
        tmp.write_bytes(b"new")
    assert path.read_bytes() == b"new" and oct(path.stat().st_mode & 0o777) == "0o644"


def test_the_next_writer_removes_what_a_killed_write_left(tmp_path):
    output = tmp_path / "selected.yaml"
    plot = tmp_path / "selected_o1.png"
    left = [tmp_path / ".selected.yaml.x1.tmp.yaml", tmp_path / ".selected_o1.png.x2.tmp.png"]
    for path in left:
        path.write_text("half")
    (tmp_path / ".other.yaml.x3.tmp.yaml").write_text("another output's")
    with claim_output(output, beside=(plot,)):
        assert not any(p.exists() for p in left)
    assert [p.name for p in tmp_path.iterdir()] == [".other.yaml.x3.tmp.yaml"]


def test_an_output_may_not_be_share_or_hold_an_input(tmp_path):
    source = tmp_path / "r.yaml"
    source.write_text("header")
    sidecar = tmp_path / "r.yaml.0123456789ab.npz"
    sidecar.write_bytes(b"arrays")
    (tmp_path / "link.yaml").hardlink_to(source)
    (tmp_path / "alias.yaml").symlink_to(source)
    bag = tmp_path / "bag"
    bag.mkdir()
    for output, message in (
        (source, "not overwriting"),
        (sidecar, "not overwriting"),  # read with its header
        (tmp_path / "link.yaml", "not overwriting"),  # the same file by another name
        (tmp_path / "alias.yaml", "not overwriting"),
        (bag / "m.yaml", "inside the input"),
        (tmp_path, "holds the input"),
    ):
        with pytest.raises(OutputError, match=message):
            check_apart([output], [source, bag, None])
    check_apart([tmp_path / "other.yaml", None], [source, bag, None])  # apart: nothing said
