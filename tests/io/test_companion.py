"""Companions: files named by their header's bytes, replaced with it as one (a truth, a route's CSV)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pytest
import yaml

from posegen.io import companion as companion_module
from posegen.io import (
    companion_of,
    companion_path,
    companions_of,
    read_arrays,
    sidecars_of,
    write_with_arrays,
    write_with_companions,
)
from posegen.io.atomic import leftover_temporaries
from tests.io.crashing import kill_at_every_point


def test_a_companion_is_named_by_its_headers_bytes_and_the_old_one_removed_after(tmp_path):
    path = tmp_path / "m.yaml"
    (first,) = write_with_companions(path, b"run: 1\n", {".truth.yaml": b"truth: 1\n"})
    assert first == companion_path(path, b"run: 1\n", ".truth.yaml") == companion_of(path, ".truth.yaml")
    assert first.name.startswith("m.yaml.") and first.name.endswith(".truth.yaml")
    (second,) = write_with_companions(path, b"run: 2\n", {".truth.yaml": b"truth: 2\n"})
    assert second != first and companions_of(path, ".truth.yaml") == [second]  # the old one removed
    assert companion_of(path, ".truth.yaml").read_bytes() == b"truth: 2\n"
    path.write_bytes(b"run: 2\nedited: true\n")  # a header changed by hand no longer finds a companion
    assert companion_of(path, ".truth.yaml") is None


def test_a_header_written_without_a_companion_removes_the_old_one(tmp_path):
    path = tmp_path / "r.yaml"
    write_with_companions(path, b"run: 1\n", {".csv": b"a,b\n"})
    assert write_with_companions(path, b"run: 2\n", {".csv": None}) == []
    assert companions_of(path, ".csv") == [] and path.read_bytes() == b"run: 2\n"


def test_a_route_like_pair_with_a_companion_keeps_the_headers_bytes(tmp_path):
    """The header's bytes do not depend on its companions: written with or without, the same file."""
    arrays = {"a": np.arange(6.0).reshape(2, 3)}
    write_with_arrays(tmp_path / "plain.yaml", {"format": "test"}, arrays)
    write_with_arrays(tmp_path / "with.yaml", {"format": "test"}, arrays, companions={".csv": b"x\n"})
    plain = (tmp_path / "plain.yaml").read_text().replace("plain.yaml", "")
    assert plain == (tmp_path / "with.yaml").read_text().replace("with.yaml", "")
    assert companion_of(tmp_path / "with.yaml", ".csv").read_bytes() == b"x\n"


def test_a_failed_header_write_removes_the_new_companions(tmp_path, monkeypatch):
    path = tmp_path / "m.yaml"
    write_with_companions(path, b"run: 1\n", {".truth.yaml": b"truth: 1\n"})
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    real = companion_module.write_atomic

    def full_disk(target, content):
        if Path(target) == path:
            raise OSError(28, "No space left on device")
        real(target, content)

    monkeypatch.setattr(companion_module, "write_atomic", full_disk)
    with pytest.raises(OSError, match="No space"):
        write_with_companions(path, b"run: 2\n", {".truth.yaml": b"truth: 2\n"})
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


SCRIPT = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    import numpy as np
    from posegen.io import write_with_arrays, write_with_companions
    out = Path(sys.argv[1])
    write_with_companions(out / "m.yaml", b"run: 2\\n", {".truth.yaml": b"run: 2\\n"})
    write_with_arrays(out / "r.yaml", {"run": 2}, {"a": np.full((2, 3), 2.0)}, companions={".csv": b"run: 2\\n"})
    """
)


def old_state(out: Path) -> None:
    write_with_companions(out / "m.yaml", b"run: 1\n", {".truth.yaml": b"run: 1\n"})
    write_with_arrays(out / "r.yaml", {"run": 1}, {"a": np.full((2, 3), 1.0)}, companions={".csv": b"run: 1\n"})


def test_a_kill_at_every_rename_boundary_leaves_each_header_with_its_own_companion(tmp_path):
    def check(out: Path, point: str) -> None:
        for name, suffix in (("m.yaml", ".truth.yaml"), ("r.yaml", ".csv")):
            header = (out / name).read_bytes()
            run = yaml.safe_load(header)["run"]
            assert companion_of(out / name, suffix).read_bytes() == f"run: {run}\n".encode(), point
        header = yaml.safe_load((out / "r.yaml").read_text())
        assert read_arrays(out / "r.yaml", header["arrays"], ("a",))["a"][0, 0] == header["run"]
        allowed = [*sidecars_of(out / "r.yaml"), *companions_of(out / "r.yaml", ".csv")]
        allowed += [*companions_of(out / "m.yaml", ".truth.yaml")]
        allowed += [*leftover_temporaries(out / "r.yaml"), *leftover_temporaries(out / "m.yaml")]
        hidden = [p for p in out.iterdir() if p.name not in ("r.yaml", "m.yaml")]
        assert all(p in allowed for p in hidden), (point, hidden)

    labels = kill_at_every_point(tmp_path, SCRIPT, old_state, check)
    assert "before m.yaml" in labels and "before r.yaml" in labels
    assert sum(label.startswith("before removing") for label in labels) == 3  # the old truth, CSV and sidecar
