"""The pool checkpoint: what goes in comes out bit for bit, so a resumed pool is byte-identical."""

import struct
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from posegen.errors import InputError
from posegen.io import Posture
from posegen.pool import Rejection
from posegen.pool.checkpoint import Checkpoint

N_JOINTS = 4
FLOATS = st.floats(allow_nan=False, allow_infinity=False)  # subnormals, -0.0 and extremes included


def bits(outcome):
    """An outcome with every float as its 8 bytes (-0.0 is not 0.0 here)."""
    if isinstance(outcome, Rejection):
        return outcome.value
    values = (
        *outcome.joints,
        *outcome.contact_xy_m,
        outcome.contact_yaw_rad,
        outcome.min_distance_m,
        outcome.com_margin_m,
    )
    return (outcome.sample, outcome.chain, outcome.spot, [struct.pack("<d", v) for v in values])


POSTURES = st.builds(
    Posture,
    sample=st.integers(0, 2**40),
    chain=st.text(min_size=1, max_size=8),
    spot=st.text(max_size=8),
    joints=st.tuples(*[FLOATS] * N_JOINTS),
    contact_xy_m=st.tuples(FLOATS, FLOATS),
    contact_yaw_rad=FLOATS,
    min_distance_m=FLOATS,
    com_margin_m=FLOATS,
)


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(chunks=st.lists(st.lists(POSTURES | st.sampled_from(list(Rejection)), max_size=4), max_size=4))
def test_chunks_come_back_bit_for_bit(chunks):
    with tempfile.TemporaryDirectory() as folder:
        checkpoint = Checkpoint(Path(folder) / "pool.yaml.partial.jsonl", "key", N_JOINTS)
        checkpoint.start(chunks[:1])
        for chunk in chunks[1:]:
            checkpoint.append(chunk)
        loaded = checkpoint.load()
    assert [[bits(o) for o in chunk] for chunk in loaded] == [[bits(o) for o in chunk] for chunk in chunks]


def test_a_checkpoint_of_another_run_is_refused(tmp_path):
    Checkpoint(tmp_path / "c.jsonl", "one run", N_JOINTS).start([])
    with pytest.raises(InputError, match="belongs to a different run"):
        Checkpoint(tmp_path / "c.jsonl", "another run", N_JOINTS).load()


def test_a_line_cut_by_a_kill_and_all_after_it_are_redone(tmp_path):
    posture = Posture(1, "left", "s", (0.1,) * N_JOINTS, (0.0, 0.0), 0.0, 0.01, 0.02)
    checkpoint = Checkpoint(tmp_path / "c.jsonl", "key", N_JOINTS)
    checkpoint.start([[posture], [Rejection.COM]])
    with checkpoint.path.open("a") as handle:
        handle.write('[{"sample": 2, "chain": "le')
    checkpoint.append([Rejection.SOLE])  # written after the cut line: not trusted either
    assert checkpoint.load() == [[posture], [Rejection.COM]]
