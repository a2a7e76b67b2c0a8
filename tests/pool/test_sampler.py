"""A sample's outcome depends on (config, seed, index) only: the ground of same-bytes resumes."""

from posegen.pool import PostureSampler, Rejection
from posegen.robot import Projection
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
    """A posture still colliding after its separation is rejected without the assessment (separations failing here)."""
    import posegen.pool.sampler as sampler_module

    assessed = []
    assess = sampler_module.assess

    def counted(*args, **kwargs):
        assessed.append(1)
        return assess(*args, **kwargs)

    monkeypatch.setattr(sampler_module, "assess", counted)
    sampler = PostureSampler(scene, 0)
    monkeypatch.setattr(sampler.projector, "separate", lambda joints, *_: Projection(joints, False, 0))
    outcomes = [sampler.evaluate(i) for i in range(30)]
    colliding = outcomes.count(Rejection.COLLISION)
    converged = len(outcomes) - outcomes.count(Rejection.NOT_CONVERGED)
    assert colliding >= 5  # the property is exercised
    assert len(assessed) == converged - colliding


def test_separation_turns_colliding_samples_into_feasible_postures(scene, monkeypatch):
    """Samples whose projection collides (TALOS: mostly the thighs) are moved apart and pass every invariant."""
    from posegen.pool.check import verify_postures

    separating = PostureSampler(scene, 0)
    without = PostureSampler(scene, 0)
    monkeypatch.setattr(without.projector, "separate", lambda joints, *_: Projection(joints, False, 0))
    indices = range(30)
    saved = [
        separating.evaluate(i)
        for i, before in zip(indices, map(without.evaluate, indices), strict=True)
        if before == Rejection.COLLISION
    ]
    postures = [o for o in saved if not isinstance(o, Rejection)]
    assert len(saved) >= 5 and len(postures) >= 0.8 * len(saved)
    assert verify_postures(scene, postures).ok  # meshes, torques, balance: re-checked by the independent check
