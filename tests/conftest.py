"""Shared fixtures: the default TALOS scene and a small pool generated once per session."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from posegen.pool import generate_pool
from posegen.robot import Config, Pool, Scene, load_config

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "talos_table.yaml"
REAL_DATA = ROOT.parent / "shared" / "data" / "talos_real"
EXAMPLE_POOL = ROOT / "plans" / "talos" / "pool.yaml"


@pytest.fixture(scope="session")
def config() -> Config:
    return load_config(CONFIG)


@pytest.fixture(scope="session")
def scene(config: Config) -> Scene:
    return Scene(config)


@pytest.fixture(scope="session")
def small_pool(config: Config) -> Pool:
    return generate_pool(config, n=24, seed=7, workers=1)


@pytest.fixture(scope="session")
def example_pool() -> Pool:
    from posegen.robot import load_pool

    return load_pool(EXAMPLE_POOL)
