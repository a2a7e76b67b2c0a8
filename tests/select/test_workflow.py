"""``posegen select`` from files to files: the same pool and settings give the same bytes."""

import pytest
import yaml

from posegen.errors import InputError
from posegen.io import write_yaml
from posegen.select import SelectionSettings, select_pool_file
from tests.conftest import EXAMPLE_POOL


def test_select_twice_gives_the_same_bytes(tmp_path):
    settings = SelectionSettings(k=40, runs=1, seed=3)
    for run in ("first", "second"):
        select_pool_file(str(EXAMPLE_POOL), str(tmp_path / run / "selected.yaml"), settings)
    names = ["selected.yaml", "selected_o1.png", "selected_detmax.png"]
    assert sorted(p.name for p in (tmp_path / "first").iterdir()) == sorted(names)
    for name in names:
        assert (tmp_path / "first" / name).read_bytes() == (tmp_path / "second" / name).read_bytes(), name
    figures = yaml.safe_load((tmp_path / "first" / "selected.yaml").read_text())["figures"]
    assert "timings_s" not in figures  # wall times are logged (-v), never written


def test_a_pool_of_another_robot_model_is_refused(tmp_path):
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["provenance"]["robot_model_sha256"] = "f" * 64
    write_yaml(tmp_path / "pool.yaml", data)
    with pytest.raises(InputError, match="made for another robot model"):
        select_pool_file(str(tmp_path / "pool.yaml"), str(tmp_path / "selected.yaml"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pool.yaml"]
