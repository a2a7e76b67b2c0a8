"""Atomic writes: crash points at every rename, folders swapped in by one rename, pairs replaced as one."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pytest
import yaml

from posegen.errors import OutputError
from posegen.io import atomic as atomic_module
from posegen.io import atomic_folder, check_replaceable, read_arrays, sidecars_of, write_with_arrays
from posegen.io.atomic import leftover_temporaries
from tests.io.crashing import kill_at_every_point


def tree(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): p.read_text() for p in sorted(folder.rglob("*")) if p.is_file()}


def write_folder(path: Path, files: dict[str, str]) -> None:
    with atomic_folder(path) as staging:
        for name, text in files.items():
            (staging / name).write_text(text)


def test_a_folder_is_swapped_in_whole_and_the_old_one_removed(tmp_path):
    target = tmp_path / "cal"
    write_folder(target, {"a.txt": "1", "b.txt": "1"})
    assert tree(target) == {"a.txt": "1", "b.txt": "1"}
    write_folder(target, {"a.txt": "2", "c.txt": "2"})
    assert tree(target) == {"a.txt": "2", "c.txt": "2"}  # b.txt of the old run is gone: one run's files
    assert [p.name for p in tmp_path.iterdir()] == ["cal"]  # no staging or old folder left


def test_a_failing_folder_write_changes_nothing(tmp_path):
    target = tmp_path / "cal"
    write_folder(target, {"a.txt": "1"})
    with pytest.raises(RuntimeError), atomic_folder(target) as staging:
        (staging / "a.txt").write_text("2")
        raise RuntimeError("disk full")
    assert tree(target) == {"a.txt": "1"}
    assert [p.name for p in tmp_path.iterdir()] == ["cal"]


def test_without_rename_exchange_the_old_folder_goes_aside_first(tmp_path, monkeypatch):
    monkeypatch.setattr(atomic_module, "_exchange", lambda first, second: False)
    target = tmp_path / "cal"
    write_folder(target, {"a.txt": "1"})
    write_folder(target, {"a.txt": "2"})
    assert tree(target) == {"a.txt": "2"}
    assert [p.name for p in tmp_path.iterdir()] == ["cal"]


def test_rename_exchange_swaps_two_folders(tmp_path):
    first, second = tmp_path / "first", tmp_path / "second"
    for folder in (first, second):
        folder.mkdir()
        (folder / "name").write_text(folder.name)
    if not atomic_module._exchange(first, second):
        pytest.skip("this system cannot exchange two paths")
    assert (first / "name").read_text() == "second" and (second / "name").read_text() == "first"


def test_only_empty_folders_or_artefacts_of_the_kind_are_replaced(tmp_path):
    check_replaceable(tmp_path / "absent", "calibration.yaml")
    (tmp_path / "empty").mkdir()
    check_replaceable(tmp_path / "empty", "calibration.yaml")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    with pytest.raises(OutputError, match=r"no calibration.yaml: not replacing it"):
        check_replaceable(mine, "calibration.yaml")
    (mine / "calibration.yaml").write_text("format: posegen-calibration")
    check_replaceable(mine, "calibration.yaml")


ARRAYS = {"a": np.arange(6.0).reshape(2, 3)}


def header_and_arrays(path: Path) -> tuple[dict, np.ndarray]:
    header = yaml.safe_load(path.read_text())
    return header, read_arrays(path, header["arrays"], ("a",))["a"]


def test_a_pair_never_overwrites_the_arrays_the_old_header_reads(tmp_path):
    path = tmp_path / "r.yaml"
    write_with_arrays(path, {"format": "test", "run": 1}, ARRAYS)
    old = sidecars_of(path)
    new = write_with_arrays(path, {"format": "test", "run": 2}, {"a": ARRAYS["a"] + 1})
    assert new not in old and sidecars_of(path) == [new]  # the old arrays are removed once the header moved
    header, arrays = header_and_arrays(path)
    assert header["run"] == 2 and arrays[0, 0] == 1.0
    again = write_with_arrays(path, {"format": "test", "run": 3}, {"a": ARRAYS["a"] + 1})
    assert again == new and sidecars_of(path) == [new]  # the same arrays: the same file, kept


def test_two_headers_with_one_stem_do_not_share_arrays(tmp_path):
    write_with_arrays(tmp_path / "r.yaml", {"format": "test"}, ARRAYS)
    write_with_arrays(tmp_path / "r.json", {"format": "test"}, {"a": ARRAYS["a"] * 3})
    write_with_arrays(tmp_path / "r.yaml", {"format": "test"}, {"a": ARRAYS["a"] * 2})
    assert header_and_arrays(tmp_path / "r.yaml")[1][0, 1] == 2.0
    header = yaml.safe_load((tmp_path / "r.json").read_text())
    assert read_arrays(tmp_path / "r.json", header["arrays"], ("a",))["a"][0, 1] == 3.0


def test_a_failed_header_write_removes_the_new_sidecar(tmp_path, monkeypatch):
    path = tmp_path / "r.yaml"
    write_with_arrays(path, {"format": "test", "run": 1}, ARRAYS)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    from posegen.io import arrays as arrays_module
    from posegen.io import companion as companion_module

    real = arrays_module.write_atomic

    def full_disk(target, content):
        if Path(target) == path:
            raise OSError(28, "No space left on device")
        real(target, content)

    monkeypatch.setattr(arrays_module, "write_atomic", full_disk)
    monkeypatch.setattr(companion_module, "write_atomic", full_disk)  # the header lands with its companions
    with pytest.raises(OSError, match="No space"):
        write_with_arrays(path, {"format": "test", "run": 2}, {"a": ARRAYS["a"] + 1})
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


SCRIPT = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    import numpy as np
    from posegen.io import write_with_arrays
    from posegen.io.atomic import atomic_folder
    out = Path(sys.argv[1])
    write_with_arrays(out / "r.yaml", {"format": "test", "run": 2}, {"a": np.full((2, 3), 2.0)})
    with atomic_folder(out / "folder") as staging:
        (staging / "x.txt").write_text("2")
        (staging / "y.txt").write_text("2")
    """
)


def old_state(out: Path) -> None:
    write_with_arrays(out / "r.yaml", {"format": "test", "run": 1}, {"a": np.full((2, 3), 1.0)})
    write_folder(out / "folder", {"x.txt": "1", "z.txt": "1"})


def test_a_kill_at_every_rename_boundary_leaves_the_old_or_the_new_artefact(tmp_path):
    """The process kills itself at each crash point in turn: the pair and the folder are each old or new, whole."""

    def check(out: Path, point: str) -> None:
        run = yaml.safe_load((out / "r.yaml").read_text())["run"]
        assert header_and_arrays(out / "r.yaml")[1][0, 0] == run  # the header reads its own arrays
        assert tree(out / "folder") in ({"x.txt": "1", "z.txt": "1"}, {"x.txt": "2", "y.txt": "2"}), point
        allowed = [*sidecars_of(out / "r.yaml"), *leftover_temporaries(out / "r.yaml")]
        allowed += leftover_temporaries(out / "folder")  # the staging folder, or the old folder once swapped out
        hidden = [p for p in out.iterdir() if p.name not in ("r.yaml", "folder")]
        assert all(p in allowed for p in hidden), (point, hidden)

    labels = kill_at_every_point(tmp_path, SCRIPT, old_state, check)
    assert "before r.yaml" in labels and "before folder/" in labels and "after folder/ (old not yet removed)" in labels
