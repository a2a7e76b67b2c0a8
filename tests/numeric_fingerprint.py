"""A name for how this machine's floating point comes out through posegen's numeric stack.

The pipeline's bytes are the same from run to run and whatever the number of workers, on one
machine. On a machine whose CPU has other vector instructions (AVX-512 or not), numpy's
vectorised functions and the BLAS/LAPACK kernels round differently in the last bits, the
projections diverge from there, and so do the artefacts. The byte manifest is therefore
kept per fingerprint: the hash of a fixed set of computations through numpy's functions,
numpy's and scipy's BLAS/LAPACK and pinocchio, each of which rounds by the kernels the CPU
selects.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pinocchio as pin
import scipy.linalg
from example_robot_data import load


def numeric_fingerprint() -> str:
    """12 hex digits naming this machine's rounding through numpy, BLAS/LAPACK (numpy's and scipy's) and pinocchio.

    Example:
        >>> numeric_fingerprint()  # e.g. 'a3f09c21b7e4'

    """
    rng = np.random.default_rng(0)
    x = rng.uniform(-3.0, 3.0, 4099)  # odd length: the vector loops' tails too
    a = rng.standard_normal((211, 211))  # large enough for the blocked kernels
    b = rng.standard_normal((211, 7))
    probes = [
        np.exp(x),
        np.log1p(x * x),
        np.sin(x),
        np.cos(x),
        np.arctan2(x, x[::-1]),
        np.sqrt(np.abs(x)),
        np.sum(rng.standard_normal(100_003)),
        a @ a,
        a @ b,
        np.linalg.solve(a, b),
        np.linalg.svd(a, compute_uv=False),
        np.linalg.eigvalsh(a + a.T),
        np.linalg.lstsq(a[:, :50], b, rcond=None)[0],
        scipy.linalg.qr(a, mode="economic", pivoting=True)[1],
        scipy.linalg.cho_solve(scipy.linalg.cho_factor(a.T @ a), b),
    ]
    robot = load("talos")
    model, data = robot.model, robot.model.createData()
    q = pin.neutral(model)
    q[7:] = x[: model.nq - 7] / 3.0  # the free flyer at the origin, every joint within +-1 rad
    probes += [pin.rnea(model, data, q, x[: model.nv], x[model.nv : 2 * model.nv]), pin.crba(model, data, q)]
    digest = hashlib.sha256()
    for probe in probes:
        digest.update(np.ascontiguousarray(probe, dtype=float).tobytes())
    return digest.hexdigest()[:12]
