"""Which files ship: the URDF alone by the lowest rigid score, the compensation when a compliant model predicts best."""

from posegen.calibrate import CvResult, DeliverableKind, Estimate, Noise
from posegen.calibrate.deliverables import choose_deliverables
from posegen.calibrate.model_selection import NOMINAL, ModelSelection
from posegen.calibrate.scoring import ChainError, lowest_score
from posegen.robot import CandidateConfig

NOISE = Noise((1e-3, 1e-3, 1e-3), (1e-4,) * 6)
RIGID = CandidateConfig("rigid", ("*.joint_offset",))
BIG = CandidateConfig("big", ("*.*",))
SOFT = CandidateConfig("soft", ("*.joint_offset",), compliance=("hip",))


def result(candidate, scale, free, score, plausible=True):
    error = ChainError((1e-3, 1e-3, 1e-3), (1e-3, 1e-3, 1e-3), score)
    return CvResult(candidate, scale, free, score, 1.0, (score,), (1.0,), {"left": error}, NOISE, (1.0, 0.1), plausible)


def selection(results, nominal_score):
    nominal = result(NOMINAL.name, 10.0, 6, nominal_score)
    estimates = {(r.candidate, r.prior_scale): Estimate(None, None, NOISE, 0, None) for r in [*results, nominal]}
    best = min((r for r in results if r.plausible), key=lambda r: r.score)
    return ModelSelection(tuple(results), best, best, (), estimates, nominal)


def test_the_urdf_is_the_lowest_rigid_score_and_the_compensation_the_lowest_of_all():
    results = [
        result("rigid", 3.0, 40, 120.0),
        result("big", 10.0, 200, 110.0),  # lowest rigid, more parameters: the file only predicts
        result("big", 30.0, 200, 1.0, plausible=False),  # implausible: never shipped
        result("soft", 10.0, 41, 40.0),
    ]
    chosen = choose_deliverables(selection(results, 500.0), [RIGID, BIG, SOFT])
    assert (chosen.urdf.candidate.name, chosen.urdf.result.prior_scale) == ("big", 10.0)
    assert chosen.compensated is not None and chosen.compensated.candidate.name == "soft"
    assert chosen.compensated.kind == DeliverableKind.COMPENSATED and not chosen.warnings


def test_no_compensation_when_a_rigid_model_predicts_best():
    results = [result("rigid", 3.0, 40, 50.0), result("soft", 10.0, 41, 60.0)]
    chosen = choose_deliverables(selection(results, 500.0), [RIGID, SOFT])
    assert chosen.urdf.candidate.name == "rigid" and chosen.compensated is None
    assert [d.kind for d in chosen.all()] == [DeliverableKind.URDF]


def test_the_nominal_urdf_is_kept_when_no_rigid_model_beats_it():
    results = [result("rigid", 3.0, 40, 130.0), result("soft", 10.0, 41, 40.0)]
    chosen = choose_deliverables(selection(results, 120.0), [RIGID, SOFT])
    assert chosen.urdf.nominal and "nominal URDF" in chosen.warnings[0] and "130.0 against 120.0" in chosen.warnings[0]
    assert chosen.compensated is not None  # the compensation still beats it


def test_lowest_score_breaks_ties_by_fewer_parameters_then_stronger_prior():
    results = [result("big", 10.0, 200, 50.0), result("rigid", 30.0, 40, 50.0), result("rigid", 3.0, 40, 50.0)]
    pick = lowest_score(results, lambda r: True)
    assert (pick.candidate, pick.prior_scale) == ("rigid", 3.0)
    assert lowest_score(results, lambda r: r.candidate == "none") is None
