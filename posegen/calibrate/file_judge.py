"""A calibration's file judged as a stack that loads it sees it: the figures printed, written and reported.

A stack loads a URDF (and, with ``with_compliance/``, corrects its encoder angles by
``compliance.yaml`` first, :func:`posegen.calibrate.compensate`); it knows nothing of the
fit that made the file. Before it touches a table it must know where the table is. So a
file is judged with:

* its kinematics frozen: the URDF's placements as written, the encoders compensated by
  the compliance as written (holding torques from the file's own URDF, as a stack computes
  them);
* only each training session's table plane (height, roll, pitch) and each chain's contact
  tilt (roll, pitch of a flush contact frame) fitted, by least squares on the training rows
  kept, weighed as the experiment design weighs a contact (1 mm, 0.1 deg, 0.1 deg);
* a held-out session judged with the plane of the training session that holds most kept
  rows of its chain (the table's height is only known relative to the chain it was
  fitted with).

The nominal URDF, each deliverable and the interpretable model are judged alike, so their
figures compare. ``posegen calibrate`` judges each deliverable from the files it wrote
(read back), so what it prints is what a stack loading them gets.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from posegen.calibrate.compliance import Compliance, compensate
from posegen.calibrate.estimation import Noise, fit
from posegen.calibrate.scoring import column_stats
from posegen.errors import InfeasibleError
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    CalibrationModel,
    Contacts,
    Group,
    Kind,
    Spec,
    masked,
    spec_for_rows,
    start_point,
)
from posegen.robot import FloatArray, Scene

JUDGED_AS = (
    "as a stack loads the file: its kinematics frozen (with_compliance/: the encoder angles corrected by its "
    "compliance.yaml first); only each training session's table plane and each chain's contact tilt fitted, on "
    "the training rows kept, weighed 1 mm, 0.1 deg, 0.1 deg; a held-out session takes the plane of its chain's "
    "training session"
)
FIT_ITERATIONS = 100  # Levenberg-Marquardt steps of the plane and tilt fit at most (it takes a few)


@dataclass(frozen=True)
class Judged:
    """A file's residuals as a stack loading it sees them (m, rad, rad; NaN where a contact measures nothing)."""

    training: FloatArray  # (n, 3) every training row read, the rows left out too (judged with the same planes)
    held_out: FloatArray | None  # (m, 3) the held-out rows; None without any


@dataclass(frozen=True)
class SetErrors:
    """Mean absolute and RMS of some contacts' residuals (m, rad, rad; NaN: not measured)."""

    contacts: int
    mean_abs: tuple[float, float, float]
    rms: tuple[float, float, float]


def judge(
    scene: Scene,
    train: Contacts,
    kept: Sequence[int],
    held_out: Contacts | None = None,
    compliance: Compliance | None = None,
    parameters: Mapping[str, float] | None = None,
) -> Judged:
    """Judge a robot's kinematics as a stack loading them would (see the module's docstring).

    Args:
        scene: The robot as the file describes it (its URDF, its config's frames).
        train: Every training row read.
        kept: Rows of ``train`` the planes and tilts are fitted on (the calibration's kept rows).
        held_out: Held-out rows, judged with the training planes; None: none.
        compliance: The file's compliance; None: a URDF alone.
        parameters: Contact-model parameters on ``scene`` by name (the interpretable model,
            not written); None: the scene as it is (a file).

    Example:
        >>> judged = judge(Scene(load_config("plans/calibration/calibrated.yaml")), train, kept, held_out)
        >>> errors_by_chain(judged.held_out, held_out)["left"].mean_abs  # m, rad, rad

    """
    everything = train if held_out is None else train.concat(held_out)
    if compliance is not None:
        everything = everything.at(compensate(scene, everything.joints, compliance))
    sessions = list(dict.fromkeys(everything.sessions))
    model = CalibrationModel(scene, sorted(set(everything.chains)), sessions, {}, everything.kinds_by_chain())
    fitted = model.observations(everything.subset(list(kept)))
    free = tuple(model.columns([Kind.PLANE, Kind.CONTACT_TILT]))
    spec = spec_for_rows(model, Spec(free, np.full(model.size, np.inf), floor=False), set(fitted.contacts.sessions))
    start = start_point(model, fitted)
    for i, p in enumerate(model.contact.parameters):
        if parameters is not None and p.group != Group.PLANE:
            start[i] = parameters[p.name]
    delta, _ = fit(model, fitted, spec, Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE), start, FIT_ITERATIONS)
    held = everything.subset(range(len(train), len(everything)))
    x = with_training_planes(model, model.x_of(delta), fitted.contacts, held)
    residuals = masked(model.evaluate(x, model.observations(everything), floor=False).contact, everything.kinds)
    return Judged(residuals[: len(train)], None if held_out is None else residuals[len(train) :])


def with_training_planes(model: CalibrationModel, x: FloatArray, fitted: Contacts, held_out: Contacts) -> FloatArray:
    """``x`` (nx,) with each held-out session's plane that of the training session with most fitted rows of its chain.

    A session also fitted keeps its own plane.

    Raises:
        InfeasibleError: A held-out session whose chain has no fitted row.

    Example:
        >>> x = with_training_planes(model, x, training_contacts, held_out_contacts)

    """
    out = x.copy()
    for session in sorted(set(held_out.sessions) - set(fitted.sessions)):
        chains = [c for c, s in zip(held_out.chains, held_out.sessions, strict=True) if s == session]
        chain = max(sorted(set(chains)), key=chains.count)
        counts = {
            s: sum(1 for c, t in zip(fitted.chains, fitted.sessions, strict=True) if c == chain and t == s)
            for s in set(fitted.sessions)
        }
        source = max(sorted(counts), key=lambda s: counts[s])
        if counts[source] == 0:
            raise InfeasibleError(f"chain '{chain}' of held-out session '{session}' has no training contact")
        out[model.contact.plane_columns(session)] = x[model.contact.plane_columns(source)]
    return out


def errors_by_chain(residuals: FloatArray, contacts: Contacts | Sequence[str]) -> dict[str, SetErrors]:
    """Mean absolute and RMS of residuals (n, 3) over all rows ("all") and per chain, chains in name order.

    Example:
        >>> errors_by_chain(judged.held_out, held_out)["all"].contacts

    """
    chains = np.array(contacts.chains if isinstance(contacts, Contacts) else list(contacts))
    out = {}
    for name in ["all", *sorted(set(chains.tolist()))]:
        rows = residuals if name == "all" else residuals[chains == name]
        mean_abs, rms = column_stats(rows)
        out[name] = SetErrors(len(rows), _triple(mean_abs), _triple(rms))
    return out


def _triple(values: FloatArray) -> tuple[float, float, float]:
    return float(values[0]), float(values[1]), float(values[2])
