"""The experiment-design problem: one information matrix per candidate posture.

Built separately from solving it: the selection stage's optimal weights and subset
searches solve it, and the route stage's repair consults it when a selected posture
cannot be reached. Each posture's information is I_i = A_i^T A_i with A_i
its (3, nb) base regressor: the measurement Jacobian with respect to the base parameters
of both chains (shared torso once, one table session), rows scaled by the measurement
noise. A point contact's A_i has one non-zero row (its height; I_i has rank 1), a flush
contact's three: the formulas hold for both, and what counts rows counts the measured
ones (:attr:`Design.rows`). The regressors are whitened by the whole pool's information (A_i <- A_i R^-1 with
R^T R = sum_i I_i): log-det differences and every design criterion below are unchanged,
and the numbers stay well conditioned near saturation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg.blas
from numpy.typing import NDArray

from posegen.errors import InfeasibleError
from posegen.model.contact_model import ContactModel, Contacts, planned_kinds
from posegen.model.contact_rows import row_counts
from posegen.model.identifiability import RANK_TOLERANCE, BaseParameters
from posegen.model.planes import initial_planes
from posegen.model.pool_size import POOL_FACTOR, minimum_postures
from posegen.model.structural import structural_base
from posegen.model.weights import DEFAULT_NOISE, NOISE_FLOOR
from posegen.robot import ContactKind, FloatArray, Scene

SESSION = "plan"
SINGULAR = 1e-12  # |R_ii| below this times the largest: the set does not identify every parameter
DESIGN_CHUNK = 3 * 4096  # rows (3 per posture) built and factored at once: bounds memory on large pools
RIDGE = 1e-9  # added to the whitened information in searches (the whole pool's is the identity)


@dataclass(frozen=True)
class Design:
    """Candidate postures and their whitened base regressors."""

    regressors: FloatArray  # (n, 3, nb) whitened, noise-scaled base regressor of each posture
    log_det_pool: float  # log det of the unwhitened information of the whole pool
    base_names: tuple[str, ...]  # (nb,) the base parameters
    rows: NDArray[np.int_]  # (n,) measured rows of each posture: 3 (flush contact) or 1 (point contact)

    @property
    def size(self) -> int:
        """Number of candidate postures."""
        return int(self.regressors.shape[0])

    @property
    def n_params(self) -> int:
        """Number of base parameters, nb."""
        return int(self.regressors.shape[2])

    def measured(self, rows: Sequence[int]) -> int:
        """Number of measured rows of a set of postures."""
        return int(self.rows[list(rows)].sum())

    def fewest(self, ranking: Sequence[int] | None = None) -> int:
        """Fewest postures with as many measured rows as base parameters: the top of ``ranking``, or any.

        ceil(nb / 3) for flush contacts, nb for point contacts.
        """
        counts = self.rows[list(ranking)] if ranking is not None else np.sort(self.rows)[::-1]
        enough = np.flatnonzero(np.cumsum(counts) >= self.n_params)
        return int(enough[0]) + 1 if len(enough) else len(counts) + 1

    def stacked(self, rows: Sequence[int]) -> FloatArray:
        """Stacked whitened regressor of some postures. Shape (3 k, nb)."""
        return self.regressors[list(rows)].reshape(-1, self.n_params)

    def log_det(self, rows: Sequence[int]) -> float:
        """Exact log det of the (unwhitened) information of a set of postures, via QR.

        Returns:
            -inf when the set does not identify every base parameter.

        """
        if self.measured(rows) < self.n_params:
            return -np.inf
        r = np.linalg.qr(self.stacked(rows), mode="r")
        diag = np.abs(np.diag(r))
        if np.any(diag <= SINGULAR * diag.max()):
            return -np.inf
        return float(2.0 * np.sum(np.log(diag)) + self.log_det_pool)

    def score(self, rows: Sequence[int]) -> float:
        """Log det(I + RIDGE): finite for any set; more identified directions always score higher.

        Equal to :meth:`log_det` up to ~1e-9 relative on a set that identifies every
        parameter; on a deficient set each missing direction costs about log(RIDGE).
        """
        nb = self.n_params
        stacked = np.vstack([self.stacked(rows), np.sqrt(RIDGE) * np.eye(nb)])
        diag = np.abs(np.diag(np.linalg.qr(stacked, mode="r")))
        return float(2.0 * np.sum(np.log(diag)) + self.log_det_pool)

    def gains(self, rows: Sequence[int]) -> FloatArray:
        """Log det(I + RIDGE) gained by adding each candidate to a set of postures. Shape (n,).

        gain_j = log det(I_3 + A_j M^-1 A_j^T) with M the set's whitened information
        plus RIDGE; members of the set get -inf.
        """
        nb = self.n_params
        info = RIDGE * np.eye(nb)
        if len(rows):
            stacked = self.stacked(rows)
            info = info + stacked.T @ stacked
        c = np.linalg.solve(info, self.regressors.reshape(-1, nb).T).T.reshape(self.size, 3, nb)  # A_j M^-1
        sign, value = np.linalg.slogdet(np.eye(3)[None] + c @ self.regressors.transpose(0, 2, 1))
        gain = np.where(sign > 0, value, -np.inf)
        gain[list(rows)] = -np.inf
        return np.asarray(gain)

    def rank(self, rows: Sequence[int]) -> int:
        """Number of base parameters a set of postures identifies."""
        if not rows:
            return 0
        sv = np.linalg.svd(self.stacked(rows), compute_uv=False)
        return int(np.sum(sv > SINGULAR * 1e2 * sv[0]))

    def o1(self, rows: Sequence[int]) -> float:
        """Observability index O1 = det(I)^(1/(2 nb)) / sqrt(k) of a set of k postures (0 if deficient)."""
        value = self.log_det(rows)
        if not np.isfinite(value):
            return 0.0
        return float(np.exp(value / (2 * self.n_params)) / np.sqrt(len(rows)))

    def o1_of_weights(self, weights: FloatArray) -> float:
        """O1 of a continuous design: det(sum w_i I_i)^(1/(2 nb)), weights summing to one."""
        sign, value = np.linalg.slogdet(information(self.regressors, weights))
        if sign <= 0:
            return 0.0
        return float(np.exp((value + self.log_det_pool) / (2 * self.n_params)))


def information(regressors: FloatArray, weights: FloatArray) -> FloatArray:
    """M(w) = sum_i w_i A_i^T A_i of postures' regressors (n, 3, nb) weighted (n,) >= 0. Shape (nb, nb).

    One triangle computed (BLAS ``syrk`` on the rows scaled by ``sqrt(w_i)``), then mirrored.

    Example:
        >>> information(design.regressors, np.full(design.size, 1.0 / design.size))  # (nb, nb)

    """
    nb = regressors.shape[2]
    scaled = regressors.reshape(-1, nb) * np.sqrt(np.repeat(weights, 3))[:, None]  # (3 n, nb)
    upper = scipy.linalg.blas.dsyrk(1.0, scaled.T)  # (nb, nb): the upper triangle of scaled^T scaled
    return np.asarray(np.triu(upper) + np.triu(upper, 1).T)


def _chunks(count: int, size: int) -> list[slice]:
    """Consecutive ranges of at most ``size`` of ``count`` rows (one range for small pools)."""
    return [slice(start, min(start + size, count)) for start in range(0, count, size)]


def _r_factor(flat: FloatArray) -> FloatArray:
    """R of the QR decomposition of ``flat`` (m, nb), a chunk of rows at a time (TSQR). Shape (nb, nb)."""
    r: FloatArray | None = None
    for rows in _chunks(len(flat), DESIGN_CHUNK):
        block = flat[rows] if r is None else np.vstack([r, flat[rows]])
        r = np.linalg.qr(block, mode="r")  # type: ignore[assignment]
    assert r is not None
    return r


def build_design(
    scene: Scene,
    joints: FloatArray,
    chains: Sequence[str],
    noise: Sequence[float] = DEFAULT_NOISE,
    base: BaseParameters | None = None,
    kinds: Sequence[ContactKind] | None = None,
) -> tuple[Design, BaseParameters]:
    """Information of each candidate posture, in the base parameters of its chains.

    Args:
        scene: Scene.
        joints: (n, nj) candidate postures (contact postures, e.g. a pool).
        chains: Chain in contact at each posture.
        noise: Measurement noise (m, rad, rad) scaling the rows.
        base: Base parameters to use; None: structural base of these postures.
        kinds: Contact kind of each posture; None: what ``pool`` plans for its chain.

    Raises:
        InfeasibleError: No candidate, or the candidates do not identify the base parameters.

    """
    n = len(chains)
    if n == 0:
        raise InfeasibleError("the pool is empty: nothing to select from")
    made = tuple(kinds) if kinds is not None else planned_kinds(scene, chains)
    contacts = Contacts(np.asarray(joints, dtype=float), tuple(chains), (SESSION,) * n, ("",) * n, made)
    model = ContactModel(scene, sorted(set(chains)), [SESSION], contacts.kinds_by_chain())
    if base is None:
        base = structural_base(model, contacts)
    theta = initial_planes(model, contacts, model.nominal())
    sigma = np.maximum(np.asarray(noise, dtype=float), NOISE_FLOOR)
    columns = list(base.columns)
    nb = len(columns)
    regressors = np.empty((n, 3, nb))  # (n, 3, nb); the Jacobians are built a chunk at a time
    for rows in _chunks(n, DESIGN_CHUNK // 3):
        _, jac = model.jacobian(theta, contacts.subset(range(rows.start, rows.stop)))  # (chunk, 3, p)
        regressors[rows] = jac[:, :, columns] / sigma[None, :, None]
    flat = regressors.reshape(-1, nb)  # a view: whitened in place below
    r = _r_factor(flat)
    diag = np.abs(np.diag(r))
    measured = row_counts(contacts.kinds)
    if measured.sum() < nb or np.any(diag <= RANK_TOLERANCE * diag.max()):
        rank = int(np.sum(diag > RANK_TOLERANCE * diag.max()))
        per_contact = int(measured.max())
        least = minimum_postures(nb, per_contact)
        raise InfeasibleError(
            f"the pool is rank deficient: its {n} postures identify {rank} of the {nb} base parameters; "
            f"a contact measures {per_contact} number{'s' if per_contact > 1 else ''}: no fewer than {least} "
            f"postures can, and a pool needs more: sample {POOL_FACTOR * least} or more"
        )
    for rows in _chunks(3 * n, DESIGN_CHUNK):
        flat[rows] = np.linalg.solve(r.T, flat[rows].T).T  # A_i R^-1
    whitened = regressors
    return (
        Design(
            regressors=whitened,
            log_det_pool=float(2.0 * np.sum(np.log(diag))),
            base_names=tuple(model.parameters[i].name for i in base.columns),
            rows=measured,
        ),
        base,
    )
