"""The next postures to record: those that shrink the predicted error of the weakest chain most.

After a calibration, a chain whose predicted held-out error is too large needs more
contacts. The design starts from the information already measured: the given
contacts' whitened regressor in the free directions of the calibration's model, plus
the prior of those directions (a Bayesian design, so no base-parameter reduction is
needed). A pool posture adds its own rows (its chain's contact, in the table session
its chain was measured in: 3 for a flush contact, 1 for a point contact, whose other two
are zero; with the floor equations, 6 more).

The criterion is the figure the calibration predicts, reports and a session stops on:
the mean posterior variance of the weakest chain's contact height (mm^2) over that
chain's pool postures. Roll and pitch still inform the posterior (every measured row
enters it); they are not what the design lowers. Postures are added greedily, each the
one that lowers it most, with rank-3 (Woodbury) updates of the posterior covariance.
(Measured in docs/benchmarks.md: on simulated robots with compliant hips, designing for
the height alone gave a lower true held-out height error than designing for height, roll
and pitch in units of 1 mm and 0.1 deg.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InputError, reason
from posegen.io import read_yaml
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    CalibrationModel,
    Contacts,
    candidate_spec,
    planned_kinds,
    spec_for_rows,
    start_point,
)
from posegen.robot import CandidateConfig, FloatArray, Scene, parse_candidate


@dataclass(frozen=True)
class FollowUp:
    """Postures chosen to follow up a calibration."""

    rows: tuple[int, ...]  # pool rows, in the order chosen
    chain: str  # the chain whose predicted error is shrunk
    height_std_mm: dict[str, tuple[float, float]]  # chain -> predicted height sigma, before and after (model)
    gains: tuple[float, ...]  # decrease of the criterion (mm^2) brought by each posture, in order


def _session_of(chain: str, given: Contacts) -> str:
    """The table session of the given contacts with the most rows of ``chain`` (or of any chain)."""
    mine = [s for c, s in zip(given.chains, given.sessions, strict=True) if c == chain] or list(given.sessions)
    return max(sorted(set(mine)), key=mine.count)


def follow_up(
    scene: Scene,
    joints: FloatArray,
    chains: Sequence[str],
    given: Contacts,
    candidate: CandidateConfig,
    prior_scale: float,
    noise: Sequence[float],
    k: int,
    weakest: str | None = None,
    exclude: Sequence[int] = (),
) -> FollowUp:
    """Choose ``k`` pool postures for the weakest chain.

    Args:
        scene: Scene (its calibration section gives the priors and compliance groups).
        joints: (n, nj) pool postures.
        chains: Chain in contact at each pool posture.
        given: Contacts already measured.
        candidate: The calibration's model.
        prior_scale: Its prior scale.
        noise: Its contact noise (height m, roll rad, pitch rad).
        k: Postures to choose.
        weakest: The chain to improve (from cross-validation); None: the chain with the
            largest predicted height variance under this model.
        exclude: Pool rows never to choose (postures already measured or planned);
            the weakest chain's error is still predicted over all its pool postures.

    Raises:
        InputError: No pool posture of the weakest chain, k out of range, or fewer
            postures left than k.

    """
    posterior = _posterior(scene, joints, chains, given, candidate, prior_scale, noise)
    before = posterior.height_std_mm(posterior.covariance)
    chain = weakest or max(before, key=lambda c: before[c])
    excluded = _checked_choice(posterior, chain, k, exclude)
    heights = posterior.targets[posterior.chain_rows[chain], 0] * 1e3  # (m, f) the chain's height rows, mm
    target = heights.T @ heights / len(heights)  # (f, f) mean over the chain's postures
    chosen, gains, covariance = _greedy(posterior.candidates, posterior.covariance, target, k, excluded)
    after = posterior.height_std_mm(covariance)
    return FollowUp(
        rows=tuple(chosen),
        chain=chain,
        height_std_mm={c: (before[c], after[c]) for c in before},
        gains=tuple(gains),
    )


@dataclass(frozen=True)
class _Posterior:
    """The calibration's posterior and the pool's rows in its free parameters."""

    candidates: FloatArray  # (n, m, f) whitened rows of each pool posture (contact, and floor if modelled)
    targets: FloatArray  # (n, 3, f) unwhitened contact rows of each pool posture
    covariance: FloatArray  # (f, f) posterior covariance after the given contacts
    chain_rows: dict[str, NDArray[np.int_]]  # pool rows of each chain

    def height_std_mm(self, covariance: FloatArray) -> dict[str, float]:
        """Each chain's predicted height sigma (mm, rms over its pool postures) under ``covariance``."""
        out = {}
        for chain, rows in self.chain_rows.items():
            heights = self.targets[rows, 0]  # (m, f)
            out[chain] = float(np.sqrt(np.mean(np.einsum("nf,fg,ng->n", heights, covariance, heights))) * 1e3)
        return out


def _posterior(
    scene: Scene,
    joints: FloatArray,
    chains: Sequence[str],
    given: Contacts,
    candidate: CandidateConfig,
    prior_scale: float,
    noise: Sequence[float],
) -> _Posterior:
    """The model's posterior after ``given``, and the rows of every pool posture."""
    all_chains = sorted(set(chains) | set(given.chains))
    pool = Contacts(
        np.asarray(joints, dtype=float),
        tuple(chains),
        tuple(_session_of(c, given) for c in chains),
        ("",) * len(chains),
        planned_kinds(scene, chains),
    )
    kinds = given.concat(pool).kinds_by_chain()
    compliance = scene.calibration.compliance
    model = CalibrationModel(scene, all_chains, sorted(set(given.sessions)), compliance, kinds)
    spec = spec_for_rows(
        model, candidate_spec(model, candidate, scene.calibration.prior, prior_scale), set(given.sessions)
    )
    free = list(spec.free)
    basis = model.basis[:, free]
    x = start_point(model, model.observations(given))
    sigma = np.array(noise, dtype=float)

    def rows(contacts: Contacts) -> tuple[FloatArray, FloatArray]:
        """Whitened regressor per posture (n, 3 or 9, f), and the unwhitened contact rows (n, 3, f)."""
        out = model.evaluate(x, model.observations(contacts), jacobian=True, floor=spec.floor)
        contact = np.einsum("nmx,xf->nmf", out.contact_jacobian, basis)
        whitened = [contact / sigma[None, :, None]]
        if spec.floor:
            floor_sigma = np.array(DEFAULT_FLOOR_NOISE)
            whitened.append(np.einsum("nmx,xf->nmf", out.floor_jacobian, basis) / floor_sigma[None, :, None])
        return np.concatenate(whitened, axis=1), contact

    measured, _ = rows(given)
    candidates, targets = rows(pool)
    sd = spec.prior_sd[free]
    precision = np.where(np.isfinite(sd), 1.0 / np.where(np.isfinite(sd), sd, 1.0) ** 2, 0.0)
    flat = measured.reshape(-1, len(free))
    information = flat.T @ flat + np.diag(precision) + 1e-12 * np.eye(len(free))
    chain_rows = {c: np.flatnonzero(np.array(chains) == c) for c in sorted(set(chains))}
    return _Posterior(candidates, targets, np.linalg.inv(information), chain_rows)


def _checked_choice(posterior: _Posterior, chain: str, k: int, exclude: Sequence[int]) -> list[int]:
    """The excluded rows, sorted, once the chain, ``k`` and the exclusions are checked against the pool.

    Raises:
        InputError: No pool posture of the chain, k out of range, or fewer postures left than k.

    """
    count = len(posterior.candidates)
    if chain not in posterior.chain_rows:
        raise InputError(f"the pool has no posture of chain '{chain}'; its chains: {', '.join(posterior.chain_rows)}")
    if not 1 <= k <= count:
        raise InputError(f"k={k}: choose between 1 and {count} postures", parameter="k")
    excluded = sorted({int(r) for r in exclude})
    if excluded and not 0 <= excluded[0] <= excluded[-1] < count:
        raise InputError(f"excluded pool rows must lie in 0..{count - 1}")
    if k > count - len(excluded):
        raise InputError(f"k={k}: only {count - len(excluded)} pool postures are left to choose from", parameter="k")
    return excluded


def _greedy(
    candidates: FloatArray, covariance: FloatArray, target: FloatArray, k: int, excluded: list[int]
) -> tuple[list[int], list[float], FloatArray]:
    """``k`` rows chosen one at a time, each lowering ``trace(target S)`` the most; their gains; the final S."""
    chosen: list[int] = []
    gains: list[float] = []
    for _ in range(k):
        spread = candidates @ covariance  # B_i = A_i S, (n, m, f)
        inner = spread @ np.swapaxes(candidates, 1, 2)  # A_i S A_i^T, (n, m, m)
        gain_matrix = (spread @ target) @ np.swapaxes(spread, 1, 2)  # B_i T B_i^T
        damping = np.linalg.inv(np.eye(inner.shape[1])[None] + inner)  # (I + A_i S A_i^T)^-1
        gain = np.einsum("nmk,nkm->n", damping, gain_matrix)
        gain[chosen] = -np.inf
        gain[excluded] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        gains.append(float(gain[best]))
        covariance = covariance - spread[best].T @ damping[best] @ spread[best]
    return chosen, gains, covariance


CALIBRATION_VERSION = 3  # of the calibration.yaml read here (posegen.calibrate writes it)


def read_calibration_model(path: str, scene: Scene) -> tuple[CandidateConfig, float, tuple[float, ...], str]:
    """The model, prior scale, contact noise (m, rad, rad) and weakest chain a ``calibration.yaml`` records.

    What ``posegen select --given --calibration`` designs with (the chain the
    calibration's cross-validation predicts worst is the one to improve).

    Raises:
        PosegenError: Not a calibration of this robot's config, or values out of range.

    """
    report = read_yaml(path, "posegen-calibration")
    provenance = report.get("provenance", {})
    scene.check_made_for(provenance if isinstance(provenance, dict) else {}, path)  # another robot's: refused
    if report.get("format_version") != CALIBRATION_VERSION:
        raise InputError(
            f"{path}: calibration format_version {report.get('format_version')!r}; this posegen reads "
            f"{CALIBRATION_VERSION} (calibrate again)"
        )
    try:
        model = report["model"]
        candidate = parse_candidate(
            str(model["candidate"]),
            {"fit": model["fit"], "floor": model["floor_equations"], "compliance": model["compliance"]},
            f"{path}: model",
            scene.calibration.compliance,
        )
        scale = float(model["prior_scale"])
        shown = report["noise"]["contact"]
        noise = (float(shown["z_mm"]) * 1e-3, math.radians(shown["roll_deg"]), math.radians(shown["pitch_deg"]))
        predicted = model["predicted_error"]  # the interpretable model's, by chain
        weakest = str(max(sorted(predicted), key=lambda c: float(predicted[c]["mean_abs"]["z_mm"])))
    except (KeyError, TypeError, ValueError, AttributeError, IndexError, OverflowError) as exc:
        raise InputError(f"{path}: not a posegen calibration ({reason(exc)})") from exc
    if not all(math.isfinite(v) and v > 0 for v in (scale, *noise)):
        raise InputError(f"{path}: the prior scale and the contact noise must be positive numbers")
    return candidate, scale, noise, weakest
