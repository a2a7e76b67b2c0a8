"""The shipped files: found outside the checkout; setup.py ships folders the lookup covers."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

from posegen.resources import CHECKOUT, DEFAULT_CONFIG, ROOTS, shipped_path
from posegen.robot import load_config

ROOT = Path(__file__).resolve().parents[1]


def shipped_by_setup() -> tuple[str, ...]:
    tree = ast.parse((ROOT / "setup.py").read_text())
    [copied] = [
        ast.literal_eval(n.value)
        for n in tree.body
        if isinstance(n, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "SHIPPED" for t in n.targets)
    ]
    return tuple(copied)


def test_setup_py_ships_the_default_config_and_the_example_pool_inside_the_looked_up_folders():
    folders = shipped_by_setup()
    assert all(Path(folder).parts[0] in ROOTS and (ROOT / folder).is_dir() for folder in folders)
    shipped = {p.relative_to(ROOT).as_posix() for f in folders for p in (ROOT / f).rglob("*") if p.is_file()}
    assert DEFAULT_CONFIG in shipped and "plans/talos/pool.yaml" in shipped
    assert CHECKOUT == ROOT


def test_a_shipped_config_is_found_from_elsewhere_and_a_local_file_wins(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert shipped_path(DEFAULT_CONFIG) == ROOT / DEFAULT_CONFIG
    assert load_config(DEFAULT_CONFIG) == load_config(ROOT / DEFAULT_CONFIG)
    assert shipped_path("configs/none.yaml") == Path("configs/none.yaml")  # missing stays missing: its error names it
    assert shipped_path("elsewhere/talos_table.yaml") == Path("elsewhere/talos_table.yaml")
    local = tmp_path / DEFAULT_CONFIG
    local.parent.mkdir()
    local.write_text("robot: mine\n")
    assert shipped_path(DEFAULT_CONFIG) == Path(DEFAULT_CONFIG)  # the user's own configs/ comes first


def test_the_command_finds_its_default_config_outside_the_checkout(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "posegen.cli", "pool", "--n", "3", "--workers", "1", "-q", "-o", "pool.yaml"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "pool.yaml").is_file() and not (tmp_path / "configs").exists()
