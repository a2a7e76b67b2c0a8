"""A simulated recording: the robot follows the route, and holds each contact flush on the true robot."""

import numpy as np
import pytest

from posegen.calibrate import Perturbation, simulate
from posegen.calibrate.simulated_recording import ContactPhase, Motion, SensorSettings, hermite, simulate_recording
from posegen.calibrate.simulation import contact_offsets
from posegen.model import Contacts


def test_hermite_reproduces_cubics_and_holds_the_ends():
    times = np.array([0.0, 0.7, 1.5, 3.0])
    cubic = lambda t: 0.3 * t**3 - t**2 + 2 * t - 1  # noqa: E731
    slope = lambda t: 0.9 * t**2 - 2 * t + 2  # noqa: E731
    at = np.linspace(-1.0, 4.0, 301)
    values = hermite(times, cubic(times)[:, None], slope(times)[:, None], at)[:, 0]
    inside = (at >= 0) & (at <= 3)
    assert np.allclose(values[inside], cubic(at[inside]))
    assert np.allclose(values[at < 0], cubic(0.0)) and np.allclose(values[at > 3], cubic(3.0))


@pytest.fixture(scope="module")
def two_contacts(example_pool):
    rows = [next(i for i, p in enumerate(example_pool.postures) if p.chain == c) for c in ("left", "right")]
    a, b = example_pool.joints()[rows]
    times = np.array([0.0, 1.0, 2.0, 3.0, 5.0, 6.0, 7.0, 8.0])
    positions = np.array([a, a, a, a, b, b, b, b])
    contacts = (
        ContactPhase("left", "posture 0", a, 0.0, 1.0, 2.0, 3.0),
        ContactPhase("right", "posture 1", b, 5.0, 6.0, 7.0, 8.0),
    )
    return Motion(example_pool.joint_names, times, positions, np.zeros_like(positions), contacts), (a, b)


def test_each_hold_is_flush_on_the_true_robot(scene, two_contacts):
    motion, (a, b) = two_contacts
    settings = SensorSettings(rate_hz=100.0, force_noise_n=0.0, force_offset_n=0.0)
    recording = simulate_recording(scene, motion, "sim", Perturbation(), settings, seed=4)
    times = recording.times_s - recording.route_start_s
    for k, (chain, planned) in enumerate((("left", a), ("right", b))):
        hold = (times >= motion.contacts[k].hold_s) & (times <= motion.contacts[k].lift_s)
        held = recording.positions[hold]
        assert np.ptp(held, axis=0).max() < 1e-12  # still
        contact = Contacts(held[:1], (chain,), ("sim",), ("",))
        model = recording.model
        flush = model.evaluate(recording.theta, model.observations(contact)).contact
        assert np.abs(flush).max() < 1e-9  # flush on the true robot
        assert np.abs(held[0] - planned).max() > 1e-4  # ... which the planned posture is not
        assert np.allclose(recording.forces[chain][hold, 2], -settings.contact_force_n)
        other = "right" if chain == "left" else "left"
        assert np.allclose(recording.forces[other][hold], 0.0)
    free = (times > 3.2) & (times < 4.8)
    assert np.allclose(recording.forces["left"][free], 0.0) and np.allclose(recording.forces["right"][free], 0.0)
    at_rest = times < 0
    assert np.allclose(recording.positions[at_rest], a)


def test_the_true_robot_is_the_one_simulate_makes(scene, two_contacts):
    motion, (a, b) = two_contacts
    perturbation = Perturbation(encoder_noise_rad=1e-4)
    recording = simulate_recording(scene, motion, "sim", perturbation, SensorSettings(rate_hz=50.0), seed=9)
    again = simulate_recording(scene, motion, "sim", perturbation, SensorSettings(rate_hz=50.0), seed=9)
    planned = Contacts(np.array([a, b]), ("left", "right"), ("sim", "sim"), ("", ""))
    _, _, theta = simulate(scene, planned, perturbation, seed=9)
    assert np.array_equal(recording.theta, theta)
    assert np.array_equal(recording.positions, again.positions)
    assert all(np.array_equal(recording.forces[c], again.forces[c]) for c in recording.forces)
    noise = recording.positions[recording.times_s < 0.9] - a
    assert 0.5e-4 < noise.std() < 2e-4


def test_with_contact_noise_each_hold_is_flush_on_its_local_plane(scene, two_contacts):
    motion, (a, b) = two_contacts
    perturbation = Perturbation(contact_noise_m=3e-3, contact_noise_rad=float(np.deg2rad(0.3)))
    settings = SensorSettings(rate_hz=100.0, force_noise_n=0.0, force_offset_n=0.0)
    recording = simulate_recording(scene, motion, "sim", perturbation, settings, seed=4)
    clean = simulate_recording(scene, motion, "sim", Perturbation(), settings, seed=4)
    assert np.array_equal(recording.theta, clean.theta)  # the same robot and table
    planned = Contacts(np.array([a, b]), ("left", "right"), ("sim", "sim"), ("", ""))
    offsets = contact_offsets(planned, perturbation, seed=4)  # as simulate draws them at these postures
    times = recording.times_s - recording.route_start_s
    model = recording.model
    for k, chain in enumerate(("left", "right")):
        hold = np.flatnonzero((times >= motion.contacts[k].hold_s) & (times <= motion.contacts[k].lift_s))[0]
        contact = Contacts(recording.positions[hold : hold + 1], (chain,), ("sim",), ("",))
        flush = model.evaluate(recording.theta, model.observations(contact)).contact[0]
        assert np.abs(flush - offsets[k]).max() < 1e-9 and np.abs(offsets[k]).min() > 1e-6
        assert np.abs(recording.positions[hold] - clean.positions[hold]).max() > 1e-5  # the joints carry it
