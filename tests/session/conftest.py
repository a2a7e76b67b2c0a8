"""The session every test of a session starts from: one arm of the example pool, started, and played twice.

``started`` is the session before its first batch is played; ``rehearsed`` a copy of it
with two batches played by a simulated robot (seed 3, compliant hips), whose recordings
the tests add again. Both are made once per test run (about two minutes) with their own
workers.
"""

import shutil

import pytest

from posegen.io import load_pool, write_yaml
from posegen.parallel import open_backend
from posegen.session import Robot, SessionSettings, rehearse_session, start_session
from tests.conftest import EXAMPLE_POOL

CHAIN = "left"
SETTINGS = SessionSettings(
    target_mm=1.0, seed=0, margin=0.0, batch_postures=3, candidates=("offsets", "offsets_hip_pitch"), fold_seeds=1
)
ROBOT = Robot(seed=3, compliance_rad_per_knm=0.3)


@pytest.fixture(scope="session")
def started(tmp_path_factory):
    folder = tmp_path_factory.mktemp("session")
    data = load_pool(EXAMPLE_POOL).to_dict()
    data["postures"] = [p for p in data["postures"] if p["chain"] == CHAIN]
    write_yaml(folder / "pool.yaml", data)
    with open_backend(2) as backend:
        start_session(str(folder / "pool.yaml"), str(folder / "started"), SETTINGS, backend)
    return folder / "started"


@pytest.fixture(scope="session")
def rehearsed(started, tmp_path_factory):
    copy = tmp_path_factory.mktemp("rehearsed") / "session"
    shutil.copytree(started, copy)
    with open_backend(2) as backend:
        return copy, rehearse_session(str(copy), ROBOT, backend, max_batches=2)
