"""Screening the training rows: feet off the floor, and contacts the model cannot explain.

* **Feet.** Every posture stands on both soles. A row whose second sole, under the
  URDF, is further from the session's median pose than both the config's tolerance and
  six robust standard deviations of the rows did not stand: it is left out before
  anything is fitted.
* **Bad rows.** A robust fit (a Cauchy loss on each posture's normalised residual,
  by iteratively reweighted least squares) cannot be pulled far by one bad row, so that
  row keeps a large residual. Each row's residual is studentised (divided by the noise
  and by sqrt(1 - leverage) of the weighted fit) and flagged above the chi bound
  (3 dof for a flush contact, 1 for a point contact, 6 more with the floor equations)
  at which a clean set of n rows shows any with probability ``false_alarm``
  (Bonferroni). Flagged rows are left out and the rest screened again (:class:`Screening`):
  monotone (a row left out stays out), bounded (at most ``calibration.max_left_out`` of
  the rows, then it stops and warns) and never fails.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.stats

from posegen.calibrate.estimation import Noise, fit, frozen_jacobian
from posegen.model import CalibrationModel, Observations, Spec, row_counts, row_mask
from posegen.robot import CalibrationConfig, FloatArray

CAUCHY_SCALE = 2.385  # Cauchy constant of 95 % efficiency, per degree of freedom of a row
ROBUST_ITERATIONS = 8
MAX_ROUNDS = 6  # robust fits of one screening run, each without the rows the last one flagged


@dataclass(frozen=True)
class Flag:
    """A training row left out, and why."""

    row: int  # index in the rows read
    label: str  # file:line:spot
    reason: str  # "feet" or "residual"
    value: float  # normalised residual (chi) or the sole's offset (mm / deg, the larger)
    round: int  # screening round that flagged it (0: feet, before any fit)


def chi_threshold(n: int, false_alarm: float, dof: int = 3) -> float:
    """Normalised residual above which one of n rows is flagged (Bonferroni over n rows)."""
    return float(np.sqrt(scipy.stats.chi2.ppf(1.0 - false_alarm / max(n, 1), dof)))


def row_dof(observations: Observations, floor: bool) -> FloatArray:
    """Degrees of freedom of each row's residual: its contact's measured rows, 6 more with the floor. Shape (n,)."""
    return np.asarray(row_counts(observations.contacts.kinds) + (6 if floor else 0), dtype=float)


def chi_thresholds(dof: FloatArray, false_alarm: float) -> FloatArray:
    """:func:`chi_threshold` of each row, given its degrees of freedom (n,). Shape (n,)."""
    return np.array([chi_threshold(len(dof), false_alarm, int(d)) for d in dof])


def feet_offsets(model: CalibrationModel, observations: Observations) -> FloatArray:
    """Second sole's pose under the URDF less its session's median: (n, 6) m, m, m, rad, rad, rad."""
    assert model.floor is not None
    contacts = observations.contacts
    pose = model.floor.measure(model.contact.nominal(), contacts.joints)  # (n, 6)
    sessions = np.array(contacts.sessions)
    offset = pose.copy()
    for session in set(contacts.sessions):
        rows = sessions == session
        offset[rows] -= np.median(pose[rows], axis=0)
    return offset


def feet_off_the_floor(offsets: FloatArray, tolerance_m: float, tolerance_rad: float) -> FloatArray:
    """How far beyond its bound each row's sole offset is (> 1: off the floor). Shape (n,).

    A component's bound is the larger of the tolerance and six robust standard deviations
    (1.4826 x the median absolute offset) of that component over the rows: far beyond the
    noise, and beyond what a standing robot does.
    """
    spread = 1.4826 * np.median(np.abs(offsets), axis=0)  # (6,)
    tolerance = np.array([tolerance_m] * 3 + [tolerance_rad] * 3)
    bound = np.maximum(tolerance, 6.0 * spread)
    return np.max(np.abs(offsets) / bound, axis=1)


def robust_residuals(
    model: CalibrationModel, observations: Observations, spec: Spec, noise: Noise, start: FloatArray
) -> tuple[FloatArray, FloatArray, Noise]:
    """Studentised residual of each row under a Cauchy-weighted fit (n,), the fit's parameters, its noise.

    A row's residual has 3 degrees of freedom (a flush contact; 1 for a point contact), 6
    more with the floor equations (:func:`row_dof`).
    """
    n = len(observations)
    weights = np.ones(n)
    x = start
    comps = 9 if spec.floor else 3
    dof = row_dof(observations, spec.floor)  # (n,)
    measured = np.hstack([row_mask(observations.contacts.kinds), np.ones((n, comps - 3), dtype=bool)])  # (n, comps)
    studentised = np.zeros(n)
    for _ in range(ROBUST_ITERATIONS):
        delta, _ = fit(model, observations, spec, noise, x, weights=weights)
        x = model.x_of(delta)
        out = model.evaluate(x, observations, floor=spec.floor)
        raw = np.hstack([out.contact, out.floor]) if spec.floor else out.contact  # (n, comps)
        sigma = np.array(noise.contact + noise.floor)[:comps]
        per_posture, prior_rows = frozen_jacobian(model, observations, spec, noise, x)
        weighted = per_posture * np.sqrt(weights)[:, None, None]
        flat = weighted.reshape(-1, weighted.shape[2])
        information = flat.T @ flat + prior_rows.T @ prior_rows
        leverage = np.sum((flat @ np.linalg.pinv(information)) * flat, axis=1).reshape(n, comps)
        scaled = (raw / sigma) ** 2 / np.clip(1.0 - leverage, 0.05, 1.0)  # (n, comps)
        studentised = np.sqrt(scaled.sum(axis=1))
        # noise of the well-fitting rows: weighted, leverage-corrected mean square over the measured rows
        weight_rows = (weights[:, None] * measured).sum(axis=0)  # (comps,)
        mean_square = (weights[:, None] * raw**2 / np.clip(1.0 - leverage, 0.05, 1.0)).sum(axis=0)
        rms = np.where(weight_rows > 0, np.sqrt(mean_square / np.maximum(weight_rows, 1e-300)), sigma)
        noise = Noise.of(rms[:3], rms[3:] if spec.floor else np.array(noise.floor))
        weights = 1.0 / (1.0 + studentised**2 / (dof * CAUCHY_SCALE**2))
    return studentised, x, noise


class Screening:
    """Monotone screening of the usable rows: a row left out stays out, and at most a share of them.

    Each :meth:`run` fits the kept rows robustly with a given model, leaves out the rows
    beyond their bound, and repeats without them (a gross error can hide a smaller one:
    masking) until nothing more is flagged, at most ``max_rounds`` times. Rows are never
    taken back, so the rows kept can only shrink: the screening ends. It stops leaving
    rows out at ``config.max_left_out`` of the usable rows and says so in
    :attr:`warnings`; it never fails.

    Example:
        >>> screen = Screening(model, observations, labels, usable, config, drop=True)
        >>> screen.run(spec, noise, start)  # True: new rows were flagged
        >>> screen.kept, screen.flags, screen.warnings

    """

    def __init__(
        self,
        model: CalibrationModel,
        observations: Observations,
        labels: Sequence[str],
        usable: Sequence[int],
        config: CalibrationConfig,
        drop: bool,
        max_rounds: int = MAX_ROUNDS,
    ) -> None:
        self._model = model
        self._observations = observations
        self._labels = tuple(labels)
        self._usable = tuple(usable)
        self._false_alarm = config.outlier_false_alarm
        self._drop = drop
        self._max_rounds = max_rounds
        self._share = config.max_left_out
        self.limit = int(np.floor(config.max_left_out * len(usable)))  # rows that may be left out
        self.flags: list[Flag] = []
        self.warnings: list[str] = []
        self._round = 0

    @property
    def kept(self) -> list[int]:
        """Rows the fits use: the usable ones less those left out (all of them with ``drop`` off)."""
        out = {f.row for f in self.flags} if self._drop else set()
        return [i for i in self._usable if i not in out]

    @property
    def dropped(self) -> list[Flag]:
        """The flags of the rows left out."""
        return list(self.flags) if self._drop else []

    def run(self, spec: Spec, noise: Noise, start: FloatArray) -> bool:
        """Screen the kept rows with a model until nothing more is flagged; whether any new row was.

        Args:
            spec: The model (free directions, prior, floor equations) of the robust fit.
            noise: Starting noise of the robust fit.
            start: (nx,) starting parameters.

        """
        flagged_any = False
        for _ in range(self._max_rounds):
            self._round += 1
            rows = [i for i in self._usable if i not in {f.row for f in self.flags}]
            subset = self._observations.subset(rows)
            studentised, _, noise = robust_residuals(self._model, subset, spec, noise, start)
            bounds = chi_thresholds(row_dof(subset, spec.floor), self._false_alarm)
            beyond = sorted(
                ((float(v), row) for row, v, b in zip(rows, studentised, bounds, strict=True) if v > b), reverse=True
            )
            if not beyond:
                return flagged_any
            room = self.limit - len(self.flags)
            for value, row in beyond[: max(room, 0)]:
                self.flags.append(Flag(row, self._labels[row], "residual", value, self._round))
                flagged_any = True
            if len(beyond) > room:
                self.warnings.append(
                    f"screening stopped at its limit of {self.limit} rows left out ({self._share:.0%} of "
                    f"{len(self._usable)}, calibration.max_left_out): "
                    f"{len(beyond) - max(room, 0)} more row(s) beyond their bound kept, largest residual "
                    f"{beyond[max(room, 0)][0]:.1f}; the data may hold a systematic error the model lacks"
                )
                return flagged_any
            if not self._drop:
                return flagged_any  # flagged rows stay in: the next round would see the same
        self.warnings.append(f"screening still flagged rows after {self._max_rounds} rounds; the rest are kept")
        return flagged_any
