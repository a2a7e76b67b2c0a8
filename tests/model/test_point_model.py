"""Point contacts through the model: one measured row, its Jacobian, identifiability, the design."""

import numpy as np
import pytest

from posegen.model import (
    DEFAULT_NOISE,
    UNIT_PRIOR_LENGTH_M,
    ContactModel,
    Contacts,
    Group,
    Parameter,
    base_at,
    build_design,
    initial_planes,
    level_postures,
    prior_scale,
    row_counts,
    weights_for,
)
from posegen.model.identifiability import RANK_TOLERANCE
from posegen.robot import FLUSH, POINT
from tests.conftest import RADIUS_M


def seeds(pool, chain, kind, session="s", n=20):
    """Pool postures of a chain, as contacts of one kind (``level_postures`` settles them)."""
    rows = [i for i, p in enumerate(pool.postures) if p.chain == chain][:n]
    m = len(rows)
    return Contacts(pool.joints()[rows], (chain,) * m, (session,) * m, ("",) * m, (kind,) * m)


@pytest.fixture(scope="module")
def point_postures(point_scene, example_pool):
    """100 standing point contacts of the left hand, settled on a level table: hand orientations vary."""
    model = ContactModel(point_scene, ["left"], ["s"], {"left": [POINT]})
    return model, level_postures(model, seeds(example_pool, "left", POINT), 100, seed=0)


@pytest.fixture(scope="module")
def mixed_postures(point_scene, example_pool):
    """The left hand's flush contacts in session 'a' and its point contacts in session 'b' (60 each)."""
    model = ContactModel(point_scene, ["left"], ["a", "b"], {"left": [FLUSH, POINT]})
    contacts = seeds(example_pool, "left", FLUSH, "a").concat(seeds(example_pool, "left", POINT, "b"))
    return model, level_postures(model, contacts, 60, seed=1)


def finite_difference_regressor(model, theta, contacts, step=1e-7):
    """Forward differences of every residual w.r.t. every parameter. Shape (n, 3, p)."""
    base = model.residuals(theta, contacts)
    out = np.zeros((len(contacts), 3, model.size))
    for i in range(model.size):
        shifted = theta.copy()
        shifted[i] += step
        out[:, :, i] = (model.residuals(shifted, contacts) - base) / step
    return out


def fd_rank(model, theta, contacts):
    """Numerical rank of the noise- and prior-scaled finite-difference regressor, and its singular values."""
    scale = prior_scale(model, weights_for(1.0, DEFAULT_NOISE))
    scale[~np.isfinite(scale)] = UNIT_PRIOR_LENGTH_M
    regressor = finite_difference_regressor(model, theta, contacts) / np.array(DEFAULT_NOISE)[None, :, None]
    sv = np.linalg.svd(regressor.reshape(-1, model.size) * scale, compute_uv=False)
    return int(np.sum(sv > RANK_TOLERANCE * sv[0])), sv


def test_a_point_contact_measures_its_height_above_the_plane_only(point_postures):
    model, contacts = point_postures
    assert set(row_counts(contacts.kinds)) == {1}
    names = {p.name for p in model.parameters}
    assert {"left_tip.x", "left_tip.y", "left_tip.z"} <= names and "left_contact.z" not in names
    theta = initial_planes(model, contacts, model.nominal())
    plane = theta[model.column(Parameter.plane("s", "z"))]
    residuals, jacobian = model.jacobian(theta, contacts)
    assert np.abs(residuals).max() < 1e-9  # settled: the tip's centre its radius above the plane
    assert np.all(jacobian[:, 1:] == 0.0) and np.all(residuals[:, 1:] == 0.0)  # roll, pitch: not measured
    lifted = theta.copy()
    lifted[model.column(Parameter.point("left_tip", "z"))] += 1e-3  # the point 1 mm further along the tip's z
    chain = model.chains["left"]
    tips = chain.sole_to_contact(contacts.joints, chain.nominal_placements(), np.zeros(3), POINT)  # level plane
    assert model.residuals(lifted, contacts)[:, 0] == pytest.approx(1e-3 * tips[:, 2, 2], abs=1e-12)
    assert tips[:, 2, 3] - plane == pytest.approx(RADIUS_M, abs=1e-9)  # the tip's centre, its radius above


@pytest.mark.parametrize("which", ["point", "mixed"])
def test_the_jacobian_matches_finite_differences(point_postures, mixed_postures, which):
    model, contacts = point_postures if which == "point" else mixed_postures
    theta = initial_planes(model, contacts, model.nominal())
    theta = theta + np.random.default_rng(3).normal(0.0, 1e-3, model.size)  # away from the nominal
    _, analytic = model.jacobian(theta, contacts.subset(range(0, len(contacts), 7)))
    numeric = finite_difference_regressor(model, theta, contacts.subset(range(0, len(contacts), 7)))
    assert np.abs(analytic - numeric).max() < 1e-5 * max(1.0, np.abs(analytic).max())


def test_point_identifiability_counts_agree_with_a_finite_difference_regressor(point_postures):
    """QR base parameters of the analytic regressor = rank of the finite-difference one, with a clean gap."""
    model, contacts = point_postures
    base = base_at(model, contacts)
    theta = initial_planes(model, contacts, model.nominal())
    rank, sv = fd_rank(model, theta, contacts)
    assert base.size == rank
    assert sv[rank - 1] > 3 * RANK_TOLERANCE * sv[0] and sv[rank] < 1e-3 * RANK_TOLERANCE * sv[0]  # clean gap
    planes = [model.parameters[i].group for i in base.columns].count(Group.PLANE)
    assert planes == 3  # the heights of points spread over the table see its tilt
    assert base.size == 59  # TALOS' left chain (flush: 55 + 3 planes = 58), measured


def test_a_mixed_chain_identifies_more_than_either_kind_alone(point_postures, mixed_postures):
    model, contacts = mixed_postures
    base = base_at(model, contacts)
    theta = initial_planes(model, contacts, model.nominal())
    rank, _ = fd_rank(model, theta, contacts)
    assert base.size == rank
    point_only = base_at(*point_postures)
    assert base.size > point_only.size
    flush_only = base_at(model, contacts.subset([i for i, s in enumerate(contacts.sessions) if s == "a"]))
    assert base.size > flush_only.size  # the point contacts see what the flush ones cannot
    groups = {model.parameters[i].group for i in base.columns}
    assert Group.PLANE in groups


def test_the_design_counts_the_rows_a_point_contact_measures(point_scene, point_postures):
    _, contacts = point_postures
    design, base = build_design(point_scene, contacts.joints, contacts.chains, kinds=contacts.kinds)
    assert np.all(design.rows == 1) and design.n_params == base.size
    assert design.fewest() == design.n_params  # one row per posture: nb postures at least
    assert np.linalg.matrix_rank(design.regressors[0]) == 1  # a point's information has rank 1
    ranked = list(range(design.size))
    assert design.log_det(ranked[: design.n_params - 1]) == -np.inf
    assert np.isfinite(design.log_det(ranked))
    o1 = [design.o1(ranked[:k]) for k in (design.n_params + 10, design.n_params + 40)]
    assert o1[0] > 0.0 and o1[1] > 0.0
    flush, _ = build_design(point_scene, contacts.joints, contacts.chains, kinds=(FLUSH,) * len(contacts))
    assert np.all(flush.rows == 3) and flush.fewest() == -(-flush.n_params // 3)


def test_a_batch_of_parameter_vectors_gives_each_ones_point_residuals(mixed_postures):
    """``residuals_batch`` of a chain making both kinds is ``residuals`` of each parameter vector."""
    model, contacts = mixed_postures
    rng = np.random.default_rng(8)
    thetas = model.nominal() + rng.normal(0.0, 1e-3, (3, model.size))
    batch = model.residuals_batch(thetas, contacts)
    for theta, residuals in zip(thetas, batch, strict=True):
        np.testing.assert_allclose(residuals, model.residuals(theta, contacts), rtol=0, atol=1e-14)
