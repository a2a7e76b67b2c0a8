"""Parameter names: one type makes the text artefacts use, and the model finds columns by it."""

import pytest

from posegen.model import OFFSET_FIELDS, PLACEMENT_FIELDS, ContactModel, Group, Parameter, Unit


@pytest.mark.parametrize(
    ("parameter", "text", "unit"),
    [
        (Parameter.placement("torso_1_joint", "px"), "torso_1_joint.px", Unit.LENGTH),
        (Parameter.placement("torso_1_joint", "phiz"), "torso_1_joint.phiz", Unit.ANGLE),
        (Parameter.contact("left_contact", "z"), "left_contact.z", Unit.LENGTH),
        (Parameter.contact("left_contact", "roll"), "left_contact.roll", Unit.ANGLE),
        (Parameter.plane("day1", "z"), "plane@day1.z", Unit.LENGTH),
        (Parameter.plane("day1", "pitch"), "plane@day1.pitch", Unit.ANGLE),
    ],
)
def test_names_and_units(parameter, text, unit):
    assert parameter.name == str(parameter) == text
    assert parameter.unit == unit


def test_columns_follow_the_names(scene):
    model = ContactModel(scene, ["left", "right"], ["a", "b"])
    assert len({p.name for p in model.parameters}) == model.size  # every name is unique
    for i, p in enumerate(model.parameters):
        assert model.column(p) == model.index[p.name] == i
    assert [model.parameters[c].field for c in model.plane_columns("b")] == list(OFFSET_FIELDS)
    assert {model.parameters[c].owner for c in model.plane_columns("b")} == {"b"}
    torso = model.placement_columns("torso_1_joint")
    assert [model.parameters[c].name for c in torso] == [f"torso_1_joint.{f}" for f in PLACEMENT_FIELDS]
    assert [model.parameters[c].group for c in model.contact_columns("right_contact")] == [Group.CONTACT] * 3
