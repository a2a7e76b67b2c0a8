"""Initial estimates of the table planes, from the contacts themselves."""

from __future__ import annotations

import numpy as np

from posegen.model.contact_model import ContactModel, Contacts
from posegen.model.parameters import Parameter
from posegen.robot import FloatArray


def initial_planes(model: ContactModel, contacts: Contacts, theta: FloatArray) -> FloatArray:
    """Parameters with the contacts' sessions' planes level at their contacts' mean height."""
    out = theta.copy()
    present = sorted(set(contacts.sessions))
    for session in present:
        out[model.plane_columns(session)] = 0.0
    heights = model.residuals(out, contacts)[:, 0]
    sessions = np.array(contacts.sessions)
    for session in present:
        out[model.column(Parameter.plane(session, "z"))] = float(np.mean(heights[sessions == session]))
    return out


def level_planes(model: ContactModel, theta: FloatArray) -> FloatArray:
    """Parameters with every session's plane level (roll and pitch zero), heights kept."""
    out = theta.copy()
    for session in model.sessions:
        out[[model.column(Parameter.plane(session, f)) for f in ("roll", "pitch")]] = 0.0
    return out
