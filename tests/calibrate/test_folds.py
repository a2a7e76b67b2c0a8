"""Grouped CV folds: regions of the table, whole spots, whole sessions, one chain at a time."""

import numpy as np
import pytest

from posegen.calibrate import repeated_folds, spot_of
from posegen.calibrate.folds import contact_positions
from posegen.model import ContactModel, Contacts


@pytest.fixture(scope="module")
def contacts(example_pool):
    """The first 30 contacts of each chain (4 regions of 7-8: with 5, balance can push a region past its neighbour)."""
    chains = [p.chain for p in example_pool.postures]
    rows = [i for i, c in enumerate(chains) if c == "left"][:30] + [i for i, c in enumerate(chains) if c == "right"][
        :30
    ]
    postures = [example_pool.postures[i] for i in rows]
    labels = tuple(f"f.csv:{i}:{p.spot}" for i, p in enumerate(postures))
    return Contacts(example_pool.joints()[rows], tuple(p.chain for p in postures), ("day",) * 60, labels)


@pytest.fixture(scope="module")
def model(scene):
    return ContactModel(scene, ["left", "right"], ["day", "day2"])


def test_each_row_is_held_out_once_per_seed_with_its_spot_and_chain(model, contacts):
    folds = repeated_folds(model, contacts, 5, range(3))
    for seed in range(3):
        mine = [f for f in folds if f.seed == seed]
        held = np.concatenate([f.test for f in mine])
        assert sorted(held) == list(range(len(contacts)))  # a partition of the rows
        for fold in mine:
            assert {contacts.chains[i] for i in fold.test} == {fold.chain}  # one chain at a time
            assert set(fold.train) | set(fold.test) == set(range(len(contacts)))
            assert not set(fold.train) & set(fold.test)
            spots = {spot_of(contacts.labels[i]) for i in fold.test}
            outside = {spot_of(contacts.labels[i]) for i in fold.train if contacts.chains[i] == fold.chain}
            assert not spots & outside  # a spot is never split
            assert not fold.new_session


def test_regions_are_contiguous_balanced_and_move_with_the_seed(model, contacts):
    positions = contact_positions(model, contacts)
    partitions = []
    for seed in (0, 1):
        folds = [f for f in repeated_folds(model, contacts, 4, [seed]) if f.chain == "left"]
        n = sum(len(f.test) for f in folds)
        biggest_spot = max(
            sum(1 for i in f.test if spot_of(contacts.labels[i]) == s)
            for f in folds
            for s in {spot_of(contacts.labels[i]) for i in f.test}
        )
        assert max(len(f.test) for f in folds) <= np.ceil(n / 4) + biggest_spot
        # contiguous: held-out rows are nearer their own region's centre than the other regions' centres, on average
        centres = [positions[list(f.test)].mean(axis=0) for f in folds]
        for k, fold in enumerate(folds):
            own = np.linalg.norm(positions[list(fold.test)] - centres[k], axis=1).mean()
            other = min(
                np.linalg.norm(positions[list(fold.test)] - c, axis=1).mean() for j, c in enumerate(centres) if j != k
            )
            assert own < other
        partitions.append({frozenset(f.test) for f in folds})
    assert partitions[0] != partitions[1]


def test_a_chain_with_several_sessions_is_split_by_session(model, contacts):
    sessions = tuple("day" if i % 3 else "day2" for i in range(len(contacts)))
    split = Contacts(contacts.joints, contacts.chains, sessions, contacts.labels)
    folds = repeated_folds(model, split, 5, [0])
    for fold in folds:
        assert fold.new_session
        assert len({split.sessions[i] for i in fold.test}) == 1
        same = [
            i for i in fold.train if split.chains[i] == fold.chain and split.sessions[i] == split.sessions[fold.test[0]]
        ]
        assert not same  # the whole session of that chain is held out
