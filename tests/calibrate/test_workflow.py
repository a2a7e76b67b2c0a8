"""The calibrate stage's file-level checks: which files are read, and as which session."""

from __future__ import annotations

import pytest

from posegen.calibrate.workflow import read_contacts
from posegen.errors import InputError
from posegen.model import Contacts, write_measurements


def test_a_file_name_with_an_at_sign_is_read_with_at_at(scene, tmp_path):
    contacts = Contacts(scene.reference[None, :].copy(), ("left",), ("saved",), ("c",))
    path = tmp_path / "day@2.yaml"
    write_measurements(path, scene, contacts, {"seed": 0})
    rejected: list[str] = []
    assert read_contacts([f"{tmp_path}/day@@2.yaml"], scene, rejected).sessions == ("saved",)
    assert read_contacts([f"{tmp_path}/day@@2.yaml@morning"], scene, rejected).sessions == ("morning",)
    with pytest.raises(InputError, match="not found"):  # a single '@' starts the session: the file is 'day'
        read_contacts([f"{tmp_path}/day@2.yaml"], scene, rejected)
