"""How many postures a pool needs: the base parameters of generic contacts, the same as a real pool's."""

import math

import pytest

from posegen.errors import InfeasibleError
from posegen.model import ContactModel, Contacts, build_design, planned_kinds, pool_size, structural_base


def test_each_chain_has_the_base_parameters_of_its_pool_contacts(scene, example_pool):
    size = pool_size(scene)
    for chain in ("left", "right"):
        rows = [i for i, p in enumerate(example_pool.postures) if p.chain == chain]
        kinds = planned_kinds(scene, (chain,) * len(rows))
        n = len(rows)
        contacts = Contacts(example_pool.joints()[rows], (chain,) * n, ("s",) * n, ("",) * n, kinds)
        model = ContactModel(scene, [chain], ["s"], contacts.kinds_by_chain())
        assert size.base_parameters[chain] == len(structural_base(model, contacts).columns)
        assert size.rows[chain] == 3  # flush: height, roll, pitch
    assert size.minimum == sum(math.ceil(n / 3) for n in size.base_parameters.values())
    assert size.recommended == 4 * size.minimum
    assert f"at least {size.minimum} postures" in size.describe()


def test_select_on_a_too_small_pool_says_how_many_it_needs(scene, example_pool):
    n = 20
    joints, chains = example_pool.joints()[:n], [p.chain for p in example_pool.postures[:n]]
    with pytest.raises(InfeasibleError, match=r"no fewer than (\d+) postures can") as raised:
        build_design(scene, joints, chains)
    least = int(str(raised.value).split("no fewer than ")[1].split()[0])
    assert least > n and f"sample {4 * least} or more" in str(raised.value)
