"""A sample's outcome depends on (config, seed, index) only: the ground of same-bytes resumes."""

from posegen.pool import PostureSampler, Rejection
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


def test_a_colliding_sample_is_rejected_before_its_assessment(scene, monkeypatch):
    """Collisions reject 4 in 10 samples and the other invariants almost none: the assessment is spared them."""
    import posegen.pool.sampler as sampler_module

    assessed = []
    assess = sampler_module.assess

    def counted(*args, **kwargs):
        assessed.append(1)
        return assess(*args, **kwargs)

    monkeypatch.setattr(sampler_module, "assess", counted)
    outcomes = [PostureSampler(scene, 0).evaluate(i) for i in range(30)]
    colliding = outcomes.count(Rejection.COLLISION)
    converged = len(outcomes) - outcomes.count(Rejection.NOT_CONVERGED)
    assert colliding >= 5  # the property is exercised
    assert len(assessed) == converged - colliding
