"""Shared fixtures: the default TALOS scene, a small pool generated once per session, the real data.

The real TALOS recordings are read from ``$POSEGEN_REAL_DATA`` when it is set, else from
``shared/data/talos_real`` beside the checkout; tests that need them are skipped, with
the reason, when they are not there.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, settings

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from posegen.calibrate import Calibration
from posegen.io import Pool, write_yaml
from posegen.model import Contacts
from posegen.pool import generate_pool
from posegen.robot import Config, Scene, load_config
from posegen.route import Planner, Unplanned, plan_stop, route_postures_file
from posegen.select import select_pool_file

# Hypothesis: derandomized, so that CI and a laptop see the same cases. Loaded here, before any
# test module (a module of another folder may import a fuzz module, whose @settings then take
# the profile loaded at that time). ``HYPOTHESIS_PROFILE=explore`` draws new cases each run, ten
# times as many (for a search, not for CI); ``fuzz`` (``make fuzz``) is the long run of the fuzz
# suites (``test_fuzz.py``, ``test_fuzz_surfaces.py``, ``test_readers.py``; ``tests/session/test_journal.py``'s kills).
settings.register_profile(
    "posegen",
    max_examples=40,
    deadline=None,
    derandomize=True,
    database=None,  # no .hypothesis folder in the checkout
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.register_profile("explore", parent=settings.get_profile("posegen"), max_examples=400, derandomize=False)
settings.register_profile("fuzz", parent=settings.get_profile("posegen"), max_examples=800, derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "posegen"))

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "talos_table.yaml"
REAL_DATA = (  # $POSEGEN_REAL_DATA; else shared/data/talos_real beside the checkout, or beside a folder holding it
    Path(os.environ["POSEGEN_REAL_DATA"])
    if os.environ.get("POSEGEN_REAL_DATA")
    else next(
        (p / "shared" / "data" / "talos_real" for p in ROOT.parents if (p / "shared" / "data" / "talos_real").is_dir()),
        ROOT.parent / "shared" / "data" / "talos_real",
    )
)
REAL_FILES = ("left_train.csv", "left_validation.csv", "right_train.csv")
EXAMPLE_POOL = ROOT / "plans" / "talos" / "pool.yaml"
RADIUS_M = 0.01  # tip radius of the point contacts of point_config_data
DETOUR_ROWS = (1, 6)
"""Two example-pool postures whose approach poses no straight line joins, with raised midpoints and more than one
via path, the first found not the fastest. tests/route/test_free_motion.py asserts each property (its fixtures, and
its test of the fastest via path), so that a regenerated example pool fails there, saying which; pick another pair
then, from the pairs of routable rows that have them all."""


def routable_rows(scene: Scene, pool: Pool, first: int, count: int) -> list[int]:
    """The first ``count`` pool rows from ``first`` on whose stop plans: a vertical approach and lift exist."""
    planner, rows = Planner(scene, seed=0), []
    for row in range(first, len(pool.postures)):
        posture = pool.postures[row]
        if not isinstance(plan_stop(planner, (row, tuple(posture.joints), posture.chain)), Unplanned):
            rows.append(row)
        if len(rows) == count:
            return rows
    raise AssertionError(f"fewer than {count} routable postures from row {first} of the example pool")


def point_config_data(cone_deg: float = 30.0) -> dict:
    """TALOS touching the table with the tip of its third finger (a declared frame at the tip's centre)."""
    data = yaml.safe_load(CONFIG.read_text())
    data["robot"]["frames"] = {
        f"{side}_tip": {"parent": f"gripper_{side}_fingertip_3_link", "xyz_m": [0.0, 0.0, -0.03 + RADIUS_M]}
        for side in ("left", "right")
    }
    for side in ("left", "right"):
        data["chains"][side].update(
            contact_kind="point", point_frame=f"{side}_tip", point_radius_m=RADIUS_M, point_cone_deg=cone_deg
        )
    return data


@pytest.fixture(scope="session")
def config() -> Config:
    return load_config(CONFIG)


@pytest.fixture(scope="session")
def scene(config: Config) -> Scene:
    return Scene(config)


@pytest.fixture(scope="session")
def point_scene() -> Scene:
    """TALOS whose chains plan point contacts (and still declare their flush contact: sessions may mix)."""
    from posegen.robot import parse_config

    return Scene(parse_config(point_config_data()))


@pytest.fixture(scope="session")
def small_pool(config: Config) -> Pool:
    return generate_pool(config, n=24, seed=7, workers=1)


@pytest.fixture(scope="session")
def example_pool() -> Pool:
    from posegen.io import load_pool

    return load_pool(EXAMPLE_POOL)


@dataclass(frozen=True)
class CalibrationFolder:
    """A calibration of a simulated robot, written to a folder, with what made it."""

    path: Path
    calibration: Calibration
    held_out: Contacts


@pytest.fixture(scope="session")
def calibration_folder(scene: Scene, example_pool: Pool, tmp_path_factory: pytest.TempPathFactory) -> CalibrationFolder:
    """60 training and 20 held-out contacts of a perturbed TALOS, calibrated with one candidate and a fixed prior."""
    from posegen.calibrate import Perturbation, Settings, calibrate, simulate, write_calibration

    rows = list(range(80))
    chains = tuple(example_pool.postures[i].chain for i in rows)
    labels = tuple(example_pool.postures[i].spot for i in rows)
    plan = Contacts(example_pool.joints()[rows], chains, ("sim",) * len(rows), labels)
    recorded, _, _ = simulate(scene, plan, Perturbation(), seed=3)
    train, held_out = recorded.subset(range(60)), recorded.subset(range(60, len(recorded)))  # unreachable ones dropped
    calibration = calibrate(
        scene, train, ["sim"], Settings(candidates=("offsets_legs",), prior_scale=5.0, fold_seeds=1)
    )
    path = tmp_path_factory.mktemp("calibration")
    write_calibration(calibration, held_out, path, seed=3)
    return CalibrationFolder(path, calibration, held_out)


ROUTE_ROWS = [0, 1]


@pytest.fixture(scope="session")
def selection_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """IROC's selection from the example pool (where O1 peaks)."""
    path = tmp_path_factory.mktemp("selection") / "selected.yaml"
    select_pool_file(str(EXAMPLE_POOL), str(path))
    return path


@pytest.fixture(scope="session")
def route_file(example_pool: Pool, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The route through two postures of the example pool."""
    folder = tmp_path_factory.mktemp("route")
    data = example_pool.to_dict()
    data["postures"] = [data["postures"][i] for i in ROUTE_ROWS]
    plan = folder / "two.yaml"
    write_yaml(plan, data)
    route_postures_file(str(plan), str(folder / "route.yaml"), 0, None)
    return folder / "route.yaml"


@pytest.fixture(scope="session")
def real_data() -> Path:
    """The folder of the real TALOS recordings; skips the test when they are not there."""
    missing = [name for name in REAL_FILES if not (REAL_DATA / name).is_file()]
    if missing:
        pytest.skip(f"real TALOS data not found in {REAL_DATA} (set POSEGEN_REAL_DATA to its folder)")
    return REAL_DATA


@pytest.fixture
def figure_draws(monkeypatch: pytest.MonkeyPatch) -> list[object]:
    """Every matplotlib figure drawn while the test runs (a figure drawn twice is in it twice)."""
    from matplotlib.figure import Figure

    draws: list[object] = []
    original = Figure.draw

    def counted(self: Figure, renderer: object) -> object:
        draws.append(self)
        return original(self, renderer)

    monkeypatch.setattr(Figure, "draw", counted)
    return draws
