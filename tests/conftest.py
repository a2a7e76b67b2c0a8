"""Shared fixtures: the default TALOS scene and a small pool generated once per session."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from posegen.config import Config, load_config
from posegen.generation import generate_pool
from posegen.pool import Pool
from posegen.scene import Scene

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
    from posegen.pool import load_pool

    return load_pool(EXAMPLE_POOL)
