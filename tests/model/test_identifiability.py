import numpy as np
import pytest

from posegen.model import (
    ContactModel,
    Contacts,
    Group,
    base_parameters,
    initial_planes,
    observability_o1,
    structural_base,
)


def pool_contacts(pool, chains, n=20):
    rows = [i for i, p in enumerate(pool.postures) if p.chain in chains][:n]
    joints = pool.joints()[rows]
    return Contacts(joints, tuple(pool.postures[i].chain for i in rows), ("s",) * len(rows), ("",) * len(rows))


@pytest.mark.parametrize("chain", ["left", "right"])
def test_base_parameters_per_chain(scene, example_pool, chain):
    """A clean numerical rank: 55 robot parameters and the 3 plane parameters per chain."""
    model = ContactModel(scene, [chain], ["s"])
    base = structural_base(model, pool_contacts(example_pool, [chain]))
    groups = [model.parameters[i].group for i in base.columns]
    assert groups.count(Group.PLANE) == 3
    assert base.size == 58
    assert base.diagonal.min() > 1e-3 * base.diagonal.max()  # far from the rank threshold (1e-4)


def test_two_chains_share_the_torso(scene, example_pool):
    model = ContactModel(scene, ["left", "right"], ["s"])
    base = structural_base(model, pool_contacts(example_pool, ["left", "right"]))
    assert base.size == 114  # 111 robot + 3 plane: one more than two separate chains (55 + 55)
    names = [model.parameters[i].name for i in base.columns]
    heights = [n for n in names if n in ("plane@s.z", "left_contact.z", "right_contact.z")]
    assert len(heights) <= 2  # at flush contact a chain's height offset is the plane's: the three span two


def test_the_floor_equations_identify_more_of_the_legs(scene, example_pool):
    """Both soles on one floor: leg combinations that only open the stance loop become identifiable."""
    model = ContactModel(scene, ["left", "right"], ["s"])
    contacts = pool_contacts(example_pool, ["left", "right"])
    contacts_only = structural_base(model, contacts)
    with_floor = structural_base(model, contacts, floor_sigma=(1e-4, 1e-4, 1e-4, 1.7e-4, 1.7e-4, 1.7e-4))
    assert with_floor.size == contacts_only.size + 2  # 114 -> 116 (measured)


def test_base_rank_matches_the_pool_regressor(scene, example_pool):
    """The structural base set has the rank of real-like data (flush, both soles down, one height)."""
    model = ContactModel(scene, ["left", "right"], ["s"])
    contacts = pool_contacts(example_pool, ["left", "right"], n=200)
    base = structural_base(model, contacts)
    theta = initial_planes(model, contacts, model.nominal())
    _, jac = model.jacobian(theta, contacts)
    sv = np.linalg.svd(jac[:, :, list(base.columns)].reshape(-1, base.size), compute_uv=False)
    assert sv[-1] > 1e-6 * sv[0]  # every base parameter is excited by pool postures


def test_grouping_reproduces_dependent_columns():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(50, 4))
    regressor = np.column_stack([a, a[:, 0] + 2 * a[:, 1], np.zeros(50)])
    base = base_parameters(regressor, np.ones(6), [list(range(6))])
    assert base.size == 4 and 5 in base.dependent  # the zero column is never a base parameter
    rebuilt = regressor[:, list(base.columns)] @ base.grouping
    assert rebuilt == pytest.approx(regressor[:, list(base.dependent)], abs=1e-10)


def test_priority_blocks_keep_preferred_columns():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(40, 3))
    regressor = np.column_stack([a, a[:, 2] * 5.0])  # column 3 duplicates column 2 with a larger norm
    plain = base_parameters(regressor, np.ones(4), [list(range(4))])
    preferred = base_parameters(regressor, np.ones(4), [[2], [0, 1, 3]])
    assert 3 in plain.columns  # pivoting alone picks the larger column
    assert 2 in preferred.columns and 3 not in preferred.columns


def test_o1_is_zero_below_rank_and_never_falls_when_rows_are_added():
    rng = np.random.default_rng(2)
    rows = rng.normal(size=(60, 3, 12))
    assert observability_o1(rows[:3].reshape(-1, 12), 3) == 0.0  # 9 rows < 12 parameters
    dets = []
    for k in range(4, 61):
        stacked = rows[:k].reshape(-1, 12)
        r = np.linalg.qr(stacked, mode="r")
        dets.append(np.sum(np.log(np.abs(np.diag(r)))))
        assert observability_o1(stacked, k) > 0
    assert np.all(np.diff(dets) >= -1e-12)  # log det of the information never decreases
