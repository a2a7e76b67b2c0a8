"""A chain at many postures in one pass: its elements stacked, their products, one row's derivatives.

The contact and floor models evaluate a chain at n postures thousands of times per
calibration. Here every element is handled at once, as stacked arrays ``(E, n, 4, 4)``
(E elements, n postures), instead of one small array operation per element:

* :func:`placement_stack`: the E placements ``M_k`` of a parameter block (E, 6), their
  inverses and their derivatives w.r.t. the six parameters;
* :func:`chain_pass`: each element's transform (``M R(q)`` down the chain, its inverse up
  from the sole), and the prefix products ``P_k = T_0 ... T_{k-1}``;
* :func:`row_derivatives`: the derivatives of one row ``w P_E S`` of the chain's frame
  (the measurement of a contact reads the third row of the frame in its plane frame) with
  respect to every placement parameter and every joint angle, from the prefix rows
  ``w P_k`` and the suffix products ``S_k = T_k ... T_{E-1} tip``.

With ``E = M R`` (down the chain) ``dE = dM R`` and ``dE/dq = E K``; with ``E = (M R)^-1``
(up from the sole) ``dE = -E dM M^-1`` and ``dE/dq = -K E``, K the generator of rotations
about the joint axis. So the row's derivative w.r.t. a placement parameter is
``a dM b`` with ``a = w P_k, b = R S_{k+1}`` down the chain and ``a = -w P_{k+1},
b = M^-1 S_{k+1}`` up from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posegen.robot import FloatArray

GENERATORS = np.zeros((3, 3, 3))  # skew(e_x), skew(e_y), skew(e_z)
GENERATORS[0, 2, 1], GENERATORS[0, 1, 2] = 1.0, -1.0
GENERATORS[1, 0, 2], GENERATORS[1, 2, 0] = 1.0, -1.0
GENERATORS[2, 1, 0], GENERATORS[2, 0, 1] = 1.0, -1.0


@dataclass(frozen=True)
class PlacementStack:
    """E placements and what their derivatives need."""

    matrices: FloatArray  # (E, 4, 4) M_k
    inverses: FloatArray  # (E, 4, 4) M_k^-1
    derivatives: FloatArray  # (E, 6, 4, 4) dM_k / d(px, py, pz, phix, phiy, phiz)


def _rpy_factors(phi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Rx(phix), Ry(phiy), Rz(phiz) of (E, 3) angles, rad. Shapes (E, 3, 3)."""
    c, s = np.cos(phi), np.sin(phi)  # (E, 3)
    out = np.zeros((3, len(phi), 3, 3))
    for axis in range(3):
        i, j = (axis + 1) % 3, (axis + 2) % 3
        out[axis, :, axis, axis] = 1.0
        out[axis, :, i, i] = c[:, axis]
        out[axis, :, j, j] = c[:, axis]
        out[axis, :, j, i] = s[:, axis]
        out[axis, :, i, j] = -s[:, axis]
    return out[0], out[1], out[2]


def placement_stack(params: FloatArray, derivatives: bool = True) -> PlacementStack:
    """URDF placements of (E, 6) parameters (px, py, pz m; phix, phiy, phiz rad, R = Rz Ry Rx).

    Example:
        >>> stack = placement_stack(np.zeros((3, 6)))
        >>> stack.matrices.shape, stack.derivatives.shape
        ((3, 4, 4), (3, 6, 4, 4))

    """
    params = np.asarray(params, dtype=float).reshape(-1, 6)
    e = params.shape[0]
    rx, ry, rz = _rpy_factors(params[:, 3:])
    zy = rz @ ry
    rotation = zy @ rx
    matrices = np.zeros((e, 4, 4))
    matrices[:, :3, :3] = rotation
    matrices[:, :3, 3] = params[:, :3]
    matrices[:, 3, 3] = 1.0
    inverses = np.zeros((e, 4, 4))
    rotation_t = np.swapaxes(rotation, 1, 2)
    inverses[:, :3, :3] = rotation_t
    inverses[:, :3, 3] = -(rotation_t @ params[:, :3, None])[:, :, 0]
    inverses[:, 3, 3] = 1.0
    out = np.zeros((e, 6, 4, 4) if derivatives else (e, 0, 4, 4))
    if derivatives:
        out[:, [0, 1, 2], [0, 1, 2], 3] = 1.0
        out[:, 3, :3, :3] = rotation @ GENERATORS[0]
        out[:, 4, :3, :3] = zy @ GENERATORS[1] @ rx
        out[:, 5, :3, :3] = GENERATORS[2] @ rotation
    return PlacementStack(matrices, inverses, out)


def joint_rotations(axes: FloatArray, angles: FloatArray) -> FloatArray:
    """Homogeneous rotations about E unit axes (E, 3) by angles (n, E) rad. Shape (E, n, 4, 4)."""
    skew = np.einsum("ea,aij->eij", axes, GENERATORS)  # (E, 3, 3)
    s = np.sin(angles.T)[:, :, None, None]  # (E, n, 1, 1)
    c = np.cos(angles.T)[:, :, None, None]
    out = np.zeros((*angles.T.shape, 4, 4))
    out[..., :3, :3] = np.eye(3) + s * skew[:, None] + (1.0 - c) * (skew @ skew)[:, None]
    out[..., 3, 3] = 1.0
    return out


def rigid_inverses(transforms: FloatArray) -> FloatArray:
    """Inverse of rigid transforms (..., 4, 4): [R p]^-1 = [R^T -R^T p]."""
    out = np.zeros_like(transforms)
    rot_t = np.swapaxes(transforms[..., :3, :3], -1, -2)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -(rot_t @ transforms[..., :3, 3:4])[..., 0]
    out[..., 3, 3] = 1.0
    return out


@dataclass(frozen=True)
class ChainPass:
    """A chain's E elements at n postures."""

    placements: PlacementStack
    rotations: FloatArray  # (E, n, 4, 4) R_k(q): the identity for a fixed placement
    transforms: FloatArray  # (E, n, 4, 4) T_k: M R down the chain, (M R)^-1 up from the sole
    prefixes: FloatArray  # (E + 1, n, 4, 4) P_k = T_0 ... T_{k-1}; P_0 the identity
    reverse: FloatArray  # (E,) bool: traversed up from the sole
    joints: FloatArray  # (E,) int: the element's joint in the scene's joints, -1 for a fixed placement
    axes: FloatArray  # (E, 3) unit joint axis (zeros for a fixed placement)


def chain_pass(
    placements: PlacementStack, rotations: FloatArray, reverse: FloatArray, joints: FloatArray, axes: FloatArray
) -> ChainPass:
    """Transforms and prefix products of E elements, given their placements and joint rotations (E, n, 4, 4)."""
    product = placements.matrices[:, None] @ rotations  # (E, n, 4, 4)
    transforms = np.where(reverse[:, None, None, None], rigid_inverses(product), product)
    n = rotations.shape[1]
    prefixes = np.empty((len(transforms) + 1, n, 4, 4))
    prefixes[0] = np.eye(4)
    for k, t in enumerate(transforms):
        np.matmul(prefixes[k], t, out=prefixes[k + 1])
    return ChainPass(placements, rotations, transforms, prefixes, reverse, joints, axes)


def row_derivatives(state: ChainPass, rows: FloatArray, tip: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Derivatives of the rows ``W P_E tip`` of the chain's frame w.r.t. every placement parameter and joint angle.

    Args:
        state: The chain at n postures.
        rows: (r, 4) or (n, r, 4) the rows W (of the frame they are expressed in) that
            multiply the chain's product on the left.
        tip: (4, 4) or (n, 4, 4) the transform after the last element.

    Returns:
        (n, E * 6, r, 4) per placement parameter (element by element, in PLACEMENT_FIELDS
        order), and (n, J, r, 4) per joint angle (the chain's J joint elements, in chain order).

    Example:
        >>> d_place, d_joint = row_derivatives(state, plane_inverse[2:3], tip)  # a contact's third row

    """
    transforms, reverse = state.transforms, state.reverse
    e, n = transforms.shape[:2]
    suffixes = np.empty((e + 1, n, 4, 4))
    suffixes[e] = tip
    for k in range(e - 1, -1, -1):
        np.matmul(transforms[k], suffixes[k + 1], out=suffixes[k])
    u = rows @ state.prefixes  # (E + 1, n, r, 4) rows W P_k
    r = u.shape[2]
    a = np.where(reverse[:, None, None, None], -u[1:], u[:-1])  # (E, n, r, 4)
    left = np.where(reverse[:, None, None, None], state.placements.inverses[:, None], state.rotations)
    b = left @ suffixes[1:]  # (E, n, 4, 4)
    derivatives = state.placements.derivatives.transpose(0, 2, 1, 3).reshape(e, 4, 24)  # (E, i, p j)
    c = (a.reshape(e, n * r, 4) @ derivatives).reshape(e, n, r * 6, 4)  # a dM: (E, n, r p, j)
    d_place = (c @ b).reshape(e, n, r, 6, 4).transpose(1, 0, 3, 2, 4).reshape(n, e * 6, r, 4)
    moving = np.flatnonzero(state.joints >= 0)
    generators = np.zeros((len(moving), 1, 4, 4))
    generators[:, 0, :3, :3] = np.einsum("ea,aij->eij", state.axes[moving], GENERATORS)
    back = reverse[moving][:, None, None, None]
    a_joint = np.where(back, -u[moving], u[moving + 1]) @ generators  # (J, n, r, 4)
    b_joint = np.where(back, suffixes[moving], suffixes[moving + 1])  # (J, n, 4, 4)
    return d_place, (a_joint @ b_joint).transpose(1, 0, 2, 3)
