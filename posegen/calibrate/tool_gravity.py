"""The weight of the tool on a wrist force/torque sensor, fitted from a recording and removed.

A wrist sensor carries the gripper: its reading is the gripper's weight, which turns
with the wrist, plus a constant offset, plus the contact wrench. Removing a constant
offset alone (the median) leaves the weight's turning part (a 1.4 kg gripper: up to
~28 N between two wrist orientations), enough to take a free motion for a contact or
to miss one.

The weight seen in the sensor frame is linear in the gravity direction in that frame,
``g_s = R^T g`` (``R``: the sensor frame's orientation in the world, from the recorded
joints with the anchor sole flat on the floor): force ``m g_s`` and torque
``m c x g_s``. posegen fits the general affine map ``w = K g_s + w0`` (``K`` (6, 3),
``w0`` (6,)): it holds whatever the sign convention of the sensor and absorbs a fixed
rotation between the sensor and the configured ``wrench_frame``. The mass is ``K``'s
force block's mean singular value (``g_s`` in m/s^2), the CoM's distance from the
sensor the torque block's largest singular value over the mass.

The free samples are found by iterated trimming: first those whose force is within the
contact threshold of its median, then, after each fit, those whose residual force is
below half the threshold (a contact's wrench, tens of newtons, is an outlier), until
the set stops changing. A fit is refused, and the constant offset
kept (said so), when the wrist hardly turned during the recording (gravity spans less
than ``MIN_SPREAD`` in the sensor frame: mass and offset are confounded) or too few
samples are free. With ``tool_mass_kg`` and ``tool_com_m`` in the chain's config, those
are used (``K`` from them, the sensor frame taken as ``wrench_frame``) and only ``w0`` is fitted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.io import Wrenches
from posegen.robot import FloatArray, Scene

MIN_SPREAD = 0.1  # of |g|: the standard deviation of the gravity direction needed, in at least two axes
MIN_FREE = 0.3  # fraction of the samples that must be free for a fit
FREE_FORCE_FRACTION = 0.5  # a sample is free when its residual force is below this x the contact threshold
MIN_MASS_KG = 0.05  # lighter: no CoM is reported
ROUNDS = 8  # trimming rounds at most
RATE_HZ = 50.0  # the sensor's orientation is computed at this rate and interpolated


@dataclass(frozen=True)
class ToolGravity:
    """The tool's weight model of one wrist sensor (what is removed from its readings)."""

    chain: str
    gain: FloatArray  # (6, 3) wrench per gravity vector in the sensor frame (m/s^2 -> N, N m)
    offset: FloatArray  # (6,) N, N m: the sensor's constant offset
    fitted: bool  # False: the constant offset alone (see ``note``)
    mass_kg: float  # 0 when not fitted
    com_distance_m: float  # from the sensor's origin; 0 when not fitted
    free_fraction: float  # of the samples used
    note: str  # how it was obtained, in words

    def residual(self, gravity: FloatArray, forces: FloatArray, torques: FloatArray) -> FloatArray:
        """(n, 6) the readings less the tool's weight and the offset."""
        wrench = np.hstack([forces, torques])
        return np.asarray(wrench - gravity @ self.gain.T - self.offset)


def sensor_gravity(scene: Scene, chain: str, times: FloatArray, joints: FloatArray, at: FloatArray) -> FloatArray:
    """Gravity (n, 3) m/s^2 in the chain's sensor frame at times ``at``, from joint angles (t, nj) at ``times``.

    The floating base is placed by the anchor sole, flat on the floor (as in every stage).
    """
    model = scene.model
    data = model.createData()
    frame = scene.frame_id(scene.chain(chain).sensor_frame)
    rate_hz = (len(times) - 1) / max(float(times[-1] - times[0]), 1e-9)
    step = max(1, round(rate_hz / RATE_HZ))
    picked = np.unique(np.append(np.arange(0, len(times), step), len(times) - 1))
    gravity = np.array(model.gravity.linear, dtype=float)
    samples = np.zeros((len(picked), 3))
    for k, i in enumerate(picked):
        pin.framesForwardKinematics(model, data, scene.configuration(joints[i]))
        samples[k] = data.oMf[frame].rotation.T @ gravity
    return np.column_stack([np.interp(at, times[picked], samples[:, d]) for d in range(3)])


def fit_tool_gravity(
    scene: Scene, chain: str, gravity: FloatArray, forces: FloatArray, torques: FloatArray, threshold_n: float
) -> ToolGravity:
    """The tool's weight model of one wrist from a whole recording (see the module docstring).

    Args:
        scene: Scene (the chain's optional ``tool_mass_kg`` and ``tool_com_m``).
        chain: The chain.
        gravity: (n, 3) m/s^2, gravity in the sensor frame at each wrench sample.
        forces: (n, 3) N, the readings.
        torques: (n, 3) N m.
        threshold_n: The contact force threshold (``recording.force_threshold_n``).

    """
    wrench = np.hstack([forces, torques])  # (n, 6)
    config = scene.chain(chain)
    known = config.tool_mass_kg is not None
    design = np.hstack([gravity, np.ones((len(gravity), 1))])  # (n, 4)
    gain = _known_gain(config.tool_mass_kg, config.tool_com_m) if known else np.zeros((6, 3))
    spread = gravity.std(axis=0) / max(float(np.linalg.norm(gravity.mean(axis=0))), 1e-9)
    if not known and np.sort(spread)[-2] < MIN_SPREAD:
        return _offset_only(chain, wrench, f"the wrist hardly turned (gravity spread {np.max(spread):.3f} of |g|)")
    offset = np.median(wrench - gravity @ gain.T, axis=0)
    free = np.linalg.norm((wrench - gravity @ gain.T - offset)[:, :3], axis=1) < threshold_n  # no clear contact
    for _ in range(ROUNDS):
        if free.mean() < MIN_FREE:
            return _offset_only(chain, wrench, f"only {100 * free.mean():.0f} % of the samples are free of contact")
        if known:
            offset = np.median(wrench[free] - gravity[free] @ gain.T, axis=0)
        else:
            solution = np.linalg.lstsq(design[free], wrench[free], rcond=None)[0]  # (4, 6)
            gain, offset = solution[:3].T, solution[3]
        residual = np.linalg.norm((wrench - gravity @ gain.T - offset)[:, :3], axis=1)
        again = residual < FREE_FORCE_FRACTION * threshold_n
        if np.array_equal(again, free):
            break
        free = again
    mass = float(np.mean(np.linalg.svd(gain[:3], compute_uv=False)))  # K's force block: m times a rotation
    distance = float(np.linalg.svd(gain[3:], compute_uv=False)[0]) / mass if mass > MIN_MASS_KG else 0.0
    how = "from the config" if known else "fitted"
    where = f", CoM {100 * distance:.1f} cm from the sensor" if mass > MIN_MASS_KG else " (no tool weight seen)"
    note = f"tool {mass:.2f} kg{where} ({how}; {100 * free.mean():.0f} % of the samples free of contact)"
    return ToolGravity(chain, gain, offset, True, mass, distance, float(free.mean()), note)


def _known_gain(mass_kg: float | None, com_m: tuple[float, float, float] | None) -> FloatArray:
    """K of a tool of known mass and CoM (sensor frame): force ``m g_s``, torque ``m c x g_s``."""
    mass = float(mass_kg or 0.0)
    com = np.zeros(3) if com_m is None else np.asarray(com_m, dtype=float)
    return np.vstack([mass * np.eye(3), mass * pin.skew(com)])


def _offset_only(chain: str, wrench: FloatArray, why: str) -> ToolGravity:
    """The constant offset (each component's median), as before a tool model existed."""
    note = f"offset only: {why}"
    return ToolGravity(chain, np.zeros((6, 3)), np.median(wrench, axis=0), False, 0.0, 0.0, 1.0, note)


def wrist_forces(
    scene: Scene, times: FloatArray, joints: FloatArray, wrenches: dict[str, Wrenches], threshold_n: float
) -> tuple[dict[str, FloatArray], tuple[ToolGravity, ...]]:
    """Each wrist's contact force magnitude at the joint-state times, its tool's weight and offset removed.

    Args:
        scene: Scene.
        times: (n,) s, the joint states' times.
        joints: (n, nj) rad, in the robot's order.
        wrenches: Per chain, its wrist sensor's readings.
        threshold_n: The contact force threshold (``recording.force_threshold_n``).

    Returns:
        Per chain the force magnitude (n,) N, and each wrist's tool model.

    Example:
        >>> forces, tools = wrist_forces(scene, joints.times_s, positions, {"left": wrench}, 15.0)

    """
    forces: dict[str, FloatArray] = {}
    tools = []
    for chain, wrench in wrenches.items():
        gravity = sensor_gravity(scene, chain, times, joints, wrench.times_s)
        tool = fit_tool_gravity(scene, chain, gravity, wrench.forces, wrench.torques, threshold_n)
        magnitude = np.linalg.norm(tool.residual(gravity, wrench.forces, wrench.torques)[:, :3], axis=1)
        forces[chain] = np.asarray(np.interp(times, wrench.times_s, magnitude))
        tools.append(tool)
    return forces, tuple(tools)
