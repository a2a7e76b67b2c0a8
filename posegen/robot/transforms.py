"""Homogeneous transforms of URDF placements and offsets, their derivatives, and tilt measurements.

A placement carries six URDF parameters (px, py, pz in m; phix, phiy, phiz in rad, URDF
rpy: R = Rz Ry Rx); an offset three (z in m; roll, pitch in rad: a contact frame's or a
table plane's); a translation three (x, y, z in m: a contact point's). The tilt
measurement of a frame in a plane frame is its height (m), roll and pitch (rad).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.robot.geometry import FloatArray


def rpy_matrix(phi: FloatArray) -> FloatArray:
    """URDF rpy rotation Rz(phiz) Ry(phiy) Rx(phix). phi: (3,), returns (3, 3)."""
    return np.asarray(pin.rpy.rpyToMatrix(float(phi[0]), float(phi[1]), float(phi[2])))


def _skew(axis: int) -> FloatArray:
    e = np.zeros(3)
    e[axis] = 1.0
    return np.asarray(pin.skew(e))


def rpy_derivatives(phi: FloatArray) -> FloatArray:
    """Derivatives of the rpy rotation with respect to phix, phiy, phiz. Shape (3, 3, 3)."""
    rx = pin.rpy.rpyToMatrix(float(phi[0]), 0.0, 0.0)
    ry = pin.rpy.rpyToMatrix(0.0, float(phi[1]), 0.0)
    rz = pin.rpy.rpyToMatrix(0.0, 0.0, float(phi[2]))
    return np.array([rz @ ry @ rx @ _skew(0), rz @ ry @ _skew(1) @ rx, _skew(2) @ rz @ ry @ rx])


def placement_matrix(params: FloatArray) -> FloatArray:
    """Homogeneous transform of (px, py, pz, phix, phiy, phiz). Shape (4, 4)."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(params[3:])
    out[:3, 3] = params[:3]
    return out


def placement_derivatives(params: FloatArray) -> FloatArray:
    """Derivatives of :func:`placement_matrix` w.r.t. its six parameters. Shape (6, 4, 4)."""
    out = np.zeros((6, 4, 4))
    for i in range(3):
        out[i, i, 3] = 1.0
    out[3:, :3, :3] = rpy_derivatives(params[3:])
    return out


def offset_matrix(z: float, roll: float, pitch: float) -> FloatArray:
    """Transform Trans(0, 0, z) Rot_rpy(roll, pitch, 0) (a plane or contact offset). Shape (4, 4)."""
    return placement_matrix(np.array([0.0, 0.0, z, roll, pitch, 0.0]))


def offset_derivatives(offset: FloatArray) -> FloatArray:
    """Derivatives of offset_matrix(z, roll, pitch) w.r.t. its three arguments. Shape (3, 4, 4)."""
    z, roll, pitch = offset
    return placement_derivatives(np.array([0.0, 0.0, z, roll, pitch, 0.0]))[2:5]


def translation_matrix(xyz: FloatArray) -> FloatArray:
    """Transform Trans(x, y, z) (a contact point's offset). Shape (4, 4)."""
    out = np.eye(4)
    out[:3, 3] = xyz
    return out


TRANSLATION_DERIVATIVES = np.zeros((3, 4, 4))  # derivatives of Trans(x, y, z) w.r.t. x, y, z
TRANSLATION_DERIVATIVES[[0, 1, 2], [0, 1, 2], 3] = 1.0
TRANSLATION_DERIVATIVES.flags.writeable = False


def tilt_measurement(frames: FloatArray) -> FloatArray:
    """Height (m), roll and pitch (rad) of frames expressed in the plane frame.

    Args:
        frames: (n, 4, 4) contact frames in the plane frame.

    Returns:
        (n, 3) measurements.

    """
    roll = np.arctan2(frames[:, 2, 1], frames[:, 2, 2])
    pitch = np.arcsin(np.clip(-frames[:, 2, 0], -1.0, 1.0))
    return np.column_stack([frames[:, 2, 3], roll, pitch])


def tilt_measurement_jacobian(row: FloatArray, d_row: FloatArray) -> FloatArray:
    """Derivative of :func:`tilt_measurement` given the third row of the frame.

    Args:
        row: (n, 4) third row of the frame (R20, R21, R22, z).
        d_row: (n, p, 4) its derivatives with respect to p parameters.

    Returns:
        (n, 3, p) derivatives of (z, roll, pitch).

    """
    r20, r21, r22 = row[:, 0, None], row[:, 1, None], row[:, 2, None]
    d_z = d_row[:, :, 3]
    d_roll = (r22 * d_row[:, :, 1] - r21 * d_row[:, :, 2]) / (r21**2 + r22**2)
    d_pitch = -d_row[:, :, 0] / np.sqrt(np.maximum(1.0 - r20**2, 1e-12))
    return np.stack([d_z, d_roll, d_pitch], axis=1)
