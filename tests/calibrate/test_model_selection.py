"""The one-standard-error rule, plausibility and stability, on made-up scores (no fits)."""

from pathlib import Path

import numpy as np

from posegen.calibrate import CvResult, Noise
from posegen.calibrate.scoring import ChainError, one_standard_error

NOISE = Noise((1e-3, 1e-3, 1e-3), (1e-4,) * 6)


def result(candidate, scale, free, score, se, plausible=True):
    error = ChainError((1e-3, 1e-3, 1e-3), (1e-3, 1e-3, 1e-3), score)
    return CvResult(candidate, scale, free, score, se, (score,), (se,), {"left": error}, NOISE, (1.0, 0.1), plausible)


def pick(results):
    scores = np.array([r.score for r in results])
    errors = np.array([r.se for r in results])
    chosen = results[one_standard_error(results, scores, errors)]
    return chosen.candidate, chosen.prior_scale


def test_simplest_within_one_standard_error_then_its_strongest_prior():
    results = [
        result("big", 10.0, 200, 50.0, 5.0),  # the best: bound 55
        result("small", 3.0, 40, 58.0, 4.0),  # outside
        result("small", 10.0, 40, 54.0, 4.0),  # inside, fewest parameters
        result("small", 30.0, 40, 52.0, 4.0),  # inside too, weaker prior
        result("medium", 1.0, 100, 53.0, 4.0),
    ]
    assert pick(results) == ("small", 10.0)


def test_the_best_is_kept_when_nothing_simpler_is_close():
    results = [result("big", 10.0, 200, 50.0, 1.0), result("small", 10.0, 40, 60.0, 1.0)]
    assert pick(results) == ("big", 10.0)


def test_implausible_pairs_never_win():
    """A degenerate fit scoring best is left out, and the bound comes from the best plausible pair."""
    results = [
        result("degenerate", 300.0, 200, 5.0, 1.0, plausible=False),
        result("big", 10.0, 200, 50.0, 2.0),
        result("small", 10.0, 40, 53.0, 2.0),
    ]
    assert pick(results) == ("big", 10.0)


def test_the_valley_search_picks_what_the_exhaustive_search_picked(scene, real_data):
    """On the real recordings, every default candidate: the same model and deliverables as ``make bench`` recorded."""
    import yaml

    from posegen.calibrate import calibrate
    from posegen.model import read_measurements
    from posegen.parallel import ProcessBackend

    recorded = yaml.safe_load((Path(__file__).parent / "real_exhaustive_pick.yaml").read_text())
    train = read_measurements(real_data / "left_train.csv", scene).contacts.concat(
        read_measurements(real_data / "right_train.csv", scene).contacts
    )
    with ProcessBackend(2) as backend:
        calibration = calibrate(scene, train, ["left_train", "right_train", "left_validation"], backend=backend)
    chosen = calibration.selection.chosen
    assert [chosen.candidate, chosen.prior_scale] == recorded["model"]
    for deliverable in calibration.deliverables.all():
        assert [deliverable.candidate.name, deliverable.result.prior_scale] == recorded[deliverable.kind.value]
    assert {d.kind.value for d in calibration.deliverables.all()} == set(recorded) - {"note", "model"}


def test_the_same_bytes_for_any_number_of_workers(lean_scene, example_pool, tmp_path):
    """Candidates cross-validated, and plots drawn, in this process or over two workers: the same calibration folder."""
    import numpy as np

    from posegen.calibrate import Perturbation, Settings, calibrate, simulate, write_calibration
    from posegen.calibrate.calibration_file import write_calibration_files
    from posegen.calibrate.plots import drawing
    from posegen.model import Contacts
    from posegen.parallel import ProcessBackend

    rows = list(range(30))
    plan = Contacts(
        example_pool.joints()[rows],
        tuple(example_pool.postures[i].chain for i in rows),
        ("sim",) * len(rows),
        tuple(f"sim.yaml:{i}:c{i}" for i in rows),
    )
    recorded, _, _ = simulate(lean_scene, plan, Perturbation(compliance_rad_per_nm=3e-4), seed=5)
    folders = []
    for workers in (1, 2):
        folders.append(tmp_path / f"w{workers}")
        with ProcessBackend(workers) as backend:
            calibration = calibrate(lean_scene, recorded, ["sim"], Settings(fold_seeds=1), backend=backend)
            if workers == 1:
                write_calibration(calibration, None, folders[-1], seed=0)
            else:  # as the command writes it: the plots drawn on the workers
                _, plots = write_calibration_files(calibration, None, folders[-1], seed=0)
                with drawing(plots, backend):
                    assert (folders[-1] / "calibration.yaml").is_file()  # the report can read the folder meanwhile
    names = sorted(str(p.relative_to(folders[0])) for p in folders[0].rglob("*") if p.is_file())
    assert names == sorted(str(p.relative_to(folders[1])) for p in folders[1].rglob("*") if p.is_file())
    assert {"calibration.yaml", "calibrated.urdf", "offsets.yaml", "residuals.csv", "parameters.png"} <= set(names)
    for name in names:
        if name.endswith((".yaml", ".urdf", ".csv", ".png")):
            assert (folders[0] / name).read_bytes() == (folders[1] / name).read_bytes(), name
    assert (
        np.load(folders[0] / "posterior.npz")["covariance"].tobytes()
        == np.load(folders[1] / "posterior.npz")["covariance"].tobytes()
    )
