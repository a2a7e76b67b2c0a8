"""Contact kinds as objects: the built-in ones' geometry, and a toy kind added from here.

The toy kind, a line contact (an edge along the contact frame's x axis lying on the
table: its height and pitch are measured, its roll is free), is defined and registered
in this file only. The config reader, the contact model (residuals, Jacobian, joint
derivatives), the row counts and the prior's kind basis take it without a change to
posegen: what "adding a kind is one module plus its registration" promises.
"""

from __future__ import annotations

import numpy as np
import pytest

import posegen.robot.contact_kinds as contact_kinds
from posegen.errors import ConfigError
from posegen.model import CalibrationModel, ContactModel, Contacts, Kind, Parameter, row_counts, row_mask
from posegen.robot import (
    FLUSH,
    POINT,
    ContactKind,
    FloatArray,
    Scene,
    contact_placement,
    kind_named,
    offset_derivatives,
    offset_matrix,
    parse_config,
    registered_kinds,
    tilt_measurement,
    tilt_measurement_jacobian,
)
from tests.conftest import point_config_data


class LineContact(ContactKind):
    """Toy kind: an edge along the contact frame's x on the table; height and pitch, roll free."""

    value = "line"
    frame_title = "line frame"
    required_field = "fingertip_frames"
    group = "contact"
    fields = ("z", "pitch")
    rows = (True, False, True)
    aligned = True
    folded = True

    def declared(self, chain):
        return bool(chain.fingertip_frames)

    def check(self, chain, planned):
        if planned and not chain.fingertip_frames:
            raise ConfigError(f"chains.{chain.name}.fingertip_frames: missing (needed by contact_kind line)")

    def frame(self, chain):
        return chain.contact_frame

    def carried_frames(self, chain):
        return tuple(chain.fingertip_frames)

    def nominal_tip(self, scene, chain):
        placement = scene.contact_placements.get(chain.name)
        return None if placement is None else np.array(placement.homogeneous)

    def placement_in_gripper(self, model, data, chain, q):
        return np.array(contact_placement(model, chain, q).homogeneous)

    def lift_m(self, chain):
        return 0.0

    def excess(self, assessment, height_tol_m, angle_tol_rad):
        return max(abs(assessment.contact_height_m) - height_tol_m, abs(assessment.contact_pitch_rad) - angle_tol_rad)

    def detail(self, assessment):
        return f"height {assessment.contact_height_m:.2e} m, pitch {assessment.contact_pitch_rad:.2e} rad"

    def tip_offset(self, params):
        return offset_matrix(params[0], 0.0, params[1])

    def tip_offset_derivatives(self, params):
        return offset_derivatives(np.array([params[0], 0.0, params[1]]))[[0, 2]]

    def measure(self, frames, chain):
        out = tilt_measurement(frames)
        out[:, 1] = 0.0
        return out

    def measure_jacobian(self, row, d_row):
        out = tilt_measurement_jacobian(row, d_row)
        out[:, 1] = 0.0
        return out


LINE = LineContact()


@pytest.fixture
def registered(monkeypatch):
    """The toy kind registered beside the built-in ones (for this test only)."""
    monkeypatch.setattr(contact_kinds, "KINDS", (*contact_kinds.KINDS, LINE))
    return LINE


def left_contacts(pool, kind: ContactKind, n: int = 12, session: str = "s") -> Contacts:
    rows = [i for i, p in enumerate(pool.postures) if p.chain == "left"][:n]
    return Contacts(pool.joints()[rows], ("left",) * len(rows), (session,) * len(rows), ("",) * len(rows), (kind,) * n)


def central_differences(function, x: FloatArray, step: float) -> FloatArray:
    """d function / d x, the last axis of the result indexing x."""
    columns = []
    for i in range(len(x)):
        e = np.zeros_like(x)
        e[i] = step
        columns.append((function(x + e) - function(x - e)) / (2 * step))
    return np.stack(columns, axis=-1)


@pytest.mark.parametrize("kind", [FLUSH, POINT, LINE], ids=lambda k: k.value)
def test_a_kinds_tip_offset_derivatives_match_finite_differences(kind):
    params = np.random.default_rng(0).normal(0.0, 0.1, len(kind.fields))
    numeric = central_differences(kind.tip_offset, params, 1e-6)  # (4, 4, m)
    assert np.moveaxis(kind.tip_offset_derivatives(params), 0, -1) == pytest.approx(numeric, abs=1e-8)
    assert kind.tip_offset(np.zeros(len(kind.fields))) == pytest.approx(np.eye(4))  # zero offset: the nominal tip


def test_kinds_compare_sort_and_are_found_by_name_as_registered(registered):
    assert registered_kinds() == (FLUSH, POINT, LINE) and kind_named("line") is LINE
    assert sorted([POINT, LINE, FLUSH]) == [FLUSH, LINE, POINT] and LineContact() == LINE and LINE != FLUSH
    assert len({FLUSH, POINT, LINE, LineContact()}) == 3
    with pytest.raises(ValueError, match="valid kinds: flush, point, line"):
        kind_named("edge")


def test_an_unregistered_kind_is_not_read_from_a_config():
    data = point_config_data()
    data["chains"]["left"]["contact_kind"] = "line"
    unknown = r"chains\.left\.contact_kind: unknown kind 'line'; valid kinds: flush, point$"
    with pytest.raises(ConfigError, match=unknown):
        parse_config(data)


def test_a_registered_kind_is_read_from_a_config_and_declared_by_its_chains(registered):
    data = point_config_data()
    data["chains"]["left"]["contact_kind"] = "line"
    config = parse_config(data)
    chain = config.chain("left")
    assert chain.contact_kind is LINE and chain.kinds == (FLUSH, POINT, LINE)
    assert chain.frame(LINE) == chain.contact_frame
    del data["chains"]["left"]["point_frame"]  # a line-only chain: saved and read back as one
    saved = parse_config(data).to_dict()
    assert saved["chains"]["left"]["contact_kind"] == "line" and "point_frame" not in saved["chains"]["left"]
    assert parse_config(saved).chain("left").contact_kind is LINE
    del data["chains"]["left"]["fingertip_frames"]
    with pytest.raises(ConfigError, match=r"chains\.left\.fingertip_frames: missing"):
        parse_config(data)


def test_the_model_measures_a_toy_kind_as_the_kind_says(scene: Scene, example_pool):
    """Residuals of the line kind = the flush kind's height and pitch, at any offsets; roll rows are zero."""
    line = ContactModel(scene, ["left"], ["s"], {"left": [LINE]})
    flush = ContactModel(scene, ["left"], ["s"], {"left": [FLUSH]})
    frame = scene.chain("left").contact_frame
    names = [p.name for p in line.parameters[-5:]]
    assert names == [f"{frame}.z", f"{frame}.pitch", "plane@s.z", "plane@s.roll", "plane@s.pitch"]
    assert line.size == flush.size - 1  # no roll offset: a line's roll is not measured
    rng = np.random.default_rng(1)
    theta_line = line.nominal() + rng.normal(0.0, 1e-3, line.size)
    theta_flush = np.zeros(flush.size)
    for p in flush.parameters:  # the same robot, plane and offsets; the flush frame's roll offset zero
        theta_flush[flush.column(p)] = theta_line[line.index[p.name]] if p.name in line.index else 0.0
    contacts = left_contacts(example_pool, LINE)
    residuals = line.residuals(theta_line, contacts)
    expected = flush.residuals(theta_flush, left_contacts(example_pool, FLUSH))
    assert residuals[:, [0, 2]] == pytest.approx(expected[:, [0, 2]], abs=1e-12)
    assert np.all(residuals[:, 1] == 0.0) and np.abs(residuals[:, [0, 2]]).min() > 0.0
    assert row_counts(contacts.kinds).tolist() == [2] * len(contacts)
    assert row_mask(contacts.kinds[:1]).tolist() == [[True, False, True]]


def test_the_models_jacobians_of_a_toy_kind_match_finite_differences(scene: Scene, example_pool):
    """d residuals / d parameters and d residuals / d joints, mixed with point contacts in another session."""
    point_scene = Scene(parse_config(point_config_data()))
    model = ContactModel(point_scene, ["left"], ["a", "b"], {"left": [LINE, POINT]})
    assert model.kinds["left"] == (LINE, POINT)  # in their names' order
    contacts = left_contacts(example_pool, LINE, 8, "a").concat(left_contacts(example_pool, POINT, 8, "b"))
    theta = model.nominal() + np.random.default_rng(2).normal(0.0, 1e-3, model.size)
    residuals, jacobian, by_joint = model.derivatives(theta, contacts)
    numeric = central_differences(lambda x: model.residuals(x, contacts), theta, 1e-6)
    assert np.abs(jacobian - numeric).max() < 1e-7 * max(1.0, np.abs(jacobian).max())
    line_columns = model.tip_columns("left", LINE)
    assert np.abs(jacobian[:8][:, [0, 2]][:, :, line_columns]).max() > 0.1  # its own offsets move what it measures
    assert np.all(jacobian[:, 1] == 0.0) and np.all(jacobian[8:, :, line_columns] == 0.0)

    def at_joints(flat: FloatArray) -> FloatArray:
        return model.residuals(theta, contacts.at(flat.reshape(contacts.joints.shape)))

    numeric_joints = central_differences(at_joints, contacts.joints.ravel(), 1e-6)  # (n, 3, n * nj)
    n, nj = contacts.joints.shape
    own = np.stack([numeric_joints[i][:, i * nj : (i + 1) * nj] for i in range(n)])  # each contact's own angles
    assert np.abs(by_joint - own).max() < 1e-7 * max(1.0, np.abs(by_joint).max())
    assert residuals == pytest.approx(model.residuals(theta, contacts), abs=0.0)


def test_the_prior_reads_a_toy_kinds_parameters_by_their_units(scene: Scene):
    model = CalibrationModel(scene, ["left"], ["s"], {}, {"left": [LINE]})
    frame = scene.chain("left").contact_frame
    kinds = {d.name: d.kind for d in model.directions if d.owner == frame}
    assert kinds == {f"{frame}.z": Kind.CONTACT_HEIGHT, f"{frame}.pitch": Kind.CONTACT_TILT}


def test_a_model_refuses_contacts_of_a_kind_it_was_not_given(scene: Scene, example_pool):
    model = ContactModel(scene, ["left"], ["s"], {"left": [FLUSH]})
    with pytest.raises(ValueError, match="line contacts of chain 'left': the model has no such contact"):
        model.residuals(model.nominal(), left_contacts(example_pool, LINE))
    assert Parameter.contact(scene.chain("left").contact_frame, "roll").name in model.index


def test_two_kinds_of_one_chain_may_not_share_their_parameters(scene: Scene):
    with pytest.raises(ValueError, match="name the same parameters"):
        ContactModel(scene, ["left"], ["s"], {"left": [FLUSH, LINE]})  # both offset the contact frame's z, pitch
