"""Following up a calibration: the next postures shrink the weakest chain's predicted error."""

import numpy as np
import pytest
import yaml

from posegen.errors import InputError
from posegen.model import Contacts
from posegen.robot import CandidateConfig
from posegen.select import follow_up, read_calibration_model

CANDIDATE = CandidateConfig("offsets_legs", ("*.joint_offset", "leg.*"))


@pytest.fixture(scope="module")
def pool_and_given(example_pool):
    """Given contacts: many of the left chain, few of the right; the pool: the rest of the example pool."""
    chains = [p.chain for p in example_pool.postures]
    left = [i for i, c in enumerate(chains) if c == "left"][:30]
    right = [i for i, c in enumerate(chains) if c == "right"][:6]
    rows = left + right
    given = Contacts(
        example_pool.joints()[rows], tuple(chains[i] for i in rows), ("day",) * len(rows), ("",) * len(rows)
    )
    rest = [i for i in range(len(chains)) if i not in rows]
    return example_pool.joints()[rest], [chains[i] for i in rest], given


def test_the_weakest_chain_is_followed_up_and_its_predicted_error_shrinks(scene, pool_and_given):
    joints, chains, given = pool_and_given
    result = follow_up(scene, joints, chains, given, CANDIDATE, 10.0, (1e-3, np.deg2rad(0.1), np.deg2rad(0.1)), 8)
    assert result.chain == "right"  # six contacts predict worse than thirty
    before, after = result.height_std_mm["right"]
    assert after < 0.8 * before
    assert len(set(result.rows)) == 8
    assert sum(chains[i] == "right" for i in result.rows) >= 6  # the weak chain's own postures help it most
    assert all(a >= b for a, b in zip(result.gains, result.gains[1:], strict=False))  # greedy: gains do not rise


def test_the_criterion_is_the_weakest_chains_mean_height_variance(scene, pool_and_given):
    # the gains add up to the fall of the mean height variance (mm^2) the follow-up reports: that, and only
    # that, is what the design lowers (a criterion with roll and pitch in it would not sum to this)
    joints, chains, given = pool_and_given
    result = follow_up(scene, joints, chains, given, CANDIDATE, 10.0, (1e-3, np.deg2rad(0.1), np.deg2rad(0.1)), 5)
    before, after = result.height_std_mm[result.chain]
    assert sum(result.gains) == pytest.approx(before**2 - after**2, rel=1e-6)


def test_the_greedy_choice_beats_random_postures(scene, pool_and_given):
    joints, chains, given = pool_and_given
    noise = (1e-3, np.deg2rad(0.1), np.deg2rad(0.1))
    chosen = follow_up(scene, joints, chains, given, CANDIDATE, 10.0, noise, 6, weakest="right")
    rng = np.random.default_rng(0)
    right = [i for i, c in enumerate(chains) if c == "right"]
    picked = rng.choice(right, 6, replace=False)
    extra = Contacts(joints[picked], tuple(chains[i] for i in picked), ("day",) * 6, ("",) * 6)
    random = follow_up(scene, joints, chains, given.concat(extra), CANDIDATE, 10.0, noise, 1, weakest="right")
    assert chosen.height_std_mm["right"][1] < random.height_std_mm["right"][0]  # random six leave more error


def test_cli_writes_a_selection_file_for_route_and_simulate(tmp_path, example_pool):
    from posegen.cli.main import main
    from posegen.model import write_measurements
    from posegen.robot import Scene, load_config
    from tests.conftest import CONFIG, EXAMPLE_POOL

    scene = Scene(load_config(CONFIG))
    rows = list(range(20))
    given = Contacts(
        example_pool.joints()[rows], tuple(example_pool.postures[i].chain for i in rows), ("day",) * 20, ("",) * 20
    )
    measured = tmp_path / "measured.yaml"
    write_measurements(measured, scene, given, scene.provenance(0))
    out = tmp_path / "next.yaml"
    assert main(["select", str(EXAMPLE_POOL), "--given", str(measured), "--k", "5", "-q", "-o", str(out)]) == 0
    data = yaml.safe_load(out.read_text())
    assert data["format"] == "posegen-selection" and data["method"] == "followup" and len(data["postures"]) == 5
    assert main(["simulate", str(out), "-o", str(tmp_path / "sim.yaml")]) == 0


def test_the_model_of_a_calibration_is_read_back(calibration_folder, scene):
    """``select --given --calibration`` designs with the calibration's model, prior scale, noise and weakest chain."""
    found = read_calibration_model(str(calibration_folder.path / "calibration.yaml"), scene)
    candidate, scale, noise, weakest = found
    calibration = calibration_folder.calibration
    chosen = calibration.selection.chosen
    assert candidate == calibration.candidate and scale == chosen.prior_scale
    assert noise == pytest.approx(calibration.after.noise.contact, rel=1e-2)  # m, rad (written rounded, mm and deg)
    assert weakest == max(sorted(chosen.chains), key=lambda c: chosen.chains[c].mean_abs[0])


def test_point_postures_follow_up_flush_contacts(scene, point_scene, pool_and_given):
    """A chain whose pool plans point contacts, measured flush so far: its model holds both contacts' parameters."""
    joints, chains, given = pool_and_given
    noise = (1e-3, np.deg2rad(0.1), np.deg2rad(0.1))
    point = follow_up(point_scene, joints, chains, given, CANDIDATE, 10.0, noise, 8, weakest="right")
    flush = follow_up(scene, joints, chains, given, CANDIDATE, 10.0, noise, 8, weakest="right")
    before, after = point.height_std_mm["right"]
    assert after < 0.9 * before
    assert flush.height_std_mm["right"][1] < after  # 8 flush contacts (3 rows each) tell more than 8 points


def test_excluded_postures_are_never_chosen(scene, example_pool):
    """A session's follow-up on its whole pool: the postures it holds already are left out of the candidates."""
    chains = [p.chain for p in example_pool.postures]
    right = [i for i, c in enumerate(chains) if c == "right"]
    measured = [i for i, c in enumerate(chains) if c == "left"][:30] + right[:8]
    given = Contacts(example_pool.joints()[measured], tuple(chains[i] for i in measured), ("day",) * 38, ("",) * 38)
    noise = (1e-3, np.deg2rad(0.1), np.deg2rad(0.1))
    args = (scene, example_pool.joints(), chains, given, CANDIDATE, 10.0, noise)
    free = follow_up(*args, 10, weakest="right")
    excluded = [*measured, *free.rows[:3]]  # the measured ones, and the three best new ones (planned, say)
    kept = follow_up(*args, 10, weakest="right", exclude=excluded)
    assert len(set(kept.rows)) == 10 and not set(kept.rows) & set(excluded)  # free.rows[:3] were the best
    assert kept.height_std_mm["right"][1] < 0.9 * kept.height_std_mm["right"][0]  # the others still help
    left = len(chains) - len(excluded)
    assert sorted(follow_up(*args, left, exclude=excluded).rows) == sorted(set(range(len(chains))) - set(excluded))
    with pytest.raises(InputError, match="left to choose from"):
        follow_up(*args, left + 1, exclude=excluded)
