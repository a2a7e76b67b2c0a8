"""A sample's outcome depends on (config, seed, index) only: the ground of same-bytes resumes."""

from posegen.pool import PostureSampler
from tests.pool.test_checkpoint import bits


def test_an_outcome_does_not_depend_on_what_the_sampler_did_before(scene):
    indices = range(20, 28)
    fresh = [bits(PostureSampler(scene, 5).evaluate(i)) for i in indices]
    busy = PostureSampler(scene, 5)
    for i in range(12):  # a worker that has been busy with other samples, accepted and rejected
        busy.evaluate(i)
    after_others = [bits(busy.evaluate(i)) for i in reversed(indices)][::-1]
    assert after_others == fresh
    assert any(not isinstance(o, str) for o in fresh)  # postures were compared, not only rejections
