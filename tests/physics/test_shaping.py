"""The controllers' deadband and saturations: np.clip's numbers, a deadband's shape."""

import numpy as np

from posegen.physics.shaping import beyond, bounded_rate, clamp, saturate


def test_clamp_and_saturate_are_np_clip_bit_for_bit():
    rng = np.random.default_rng(3)
    values = np.concatenate([rng.normal(0.0, 2.0, 200), [0.0, -0.0, np.nan, np.inf, -np.inf, 1.0, -1.0]])
    lower, upper = -rng.uniform(0.5, 1.5, values.shape), rng.uniform(0.5, 1.5, values.shape)
    for got, want in (
        (clamp(values, lower, upper), np.clip(values, lower, upper)),
        (saturate(values, 1.0), np.clip(values, -1.0, 1.0)),
    ):
        assert np.array_equal(got, want, equal_nan=True)
        assert np.array_equal(np.signbit(got), np.signbit(want))  # -0.0 stays -0.0


def test_beyond_is_zero_within_its_band_and_continuous_outside():
    values = np.linspace(-1.0, 1.0, 401)
    out = beyond(values, 0.25)
    assert np.all(out[np.abs(values) <= 0.25] == 0.0)
    outside = np.abs(values) > 0.25
    assert np.allclose(out[outside], values[outside] - np.sign(values[outside]) * 0.25, rtol=0.0, atol=1e-15)
    assert np.array_equal(beyond(values, np.full(401, 0.25)), out)  # a band per value, or one for all
    assert float(beyond(-0.4, 0.25)) == -0.4 + 0.25  # a scalar


def test_a_bounded_rate_stops_only_past_its_bound():
    rates = np.array([0.3, 0.3, -0.3, -0.1, 0.1, 0.0])
    values = np.array([0.0, 0.05, 0.05, -0.06, -0.06, 0.05])  # free; at the bound twice; beyond it twice; still
    out = bounded_rate(rates, 0.2, values, 0.05)
    assert np.array_equal(out, [0.2, 0.0, -0.2, 0.0, 0.1, 0.0])  # saturated; stopped; back; stopped; back; still
    assert np.array_equal(bounded_rate(rates, 0.2, np.zeros(6), 0.05), saturate(rates, 0.2))
