"""What the robot's sensors read in the simulation: encoders, wrist and sole force/torque sensors.

* An encoder reads its actuated joint's angle (MuJoCo's: the calibration model's joint
  angle, zero offset included in the placement), plus seeded noise; the passive spring
  after a compliant joint is not seen.
* A force/torque sensor reads the wrench the far side applies to it (the tool and what
  the tool touches, at a wrist; the floor, at a sole), in its frame, at its origin: its
  tool's weight, turning with the wrist, included. The wrist sensors add a constant offset
  and noise, drawn as ``posegen simulate --bag`` draws them (:class:`SensorNoise`); the
  sole sensors, which only the stabilizer reads, are noise-free.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from posegen.physics.builder import Layout, Sensor
from posegen.robot import FloatArray

TORQUE_ARM_M = 0.1  # a wrist's torque noise and offset: its force's x this lever (as ``simulate --bag``)


@dataclass(frozen=True)
class SensorNoise:
    """Noise of the simulated sensors (the sizes ``posegen simulate --bag`` uses)."""

    encoder_rad: float = 0.0  # sigma per sample
    force_n: float = 0.5  # sigma of each wrist force component per sample (torques: x TORQUE_ARM_M)
    force_offset_n: float = 3.0  # sigma of each wrist sensor's constant offset, per component


def sensor_wrench(data: mujoco.MjData, sensor: Sensor) -> FloatArray:
    """A sensor's true reading (6,): the far side's wrench on it (N, N m), in its frame."""
    # MuJoCo's force and torque sensors give the parent's wrench on the sensor's body: the far side's is its opposite
    return -np.concatenate([data.sensordata[sensor.force], data.sensordata[sensor.torque]])


class Sensors:
    """The readings of one run: noise drawn from one seeded stream, in sample order.

    Example:
        >>> sensors = Sensors(layout, SensorNoise(encoder_rad=1e-4), seed=7)
        >>> joints = sensors.encoders(data)

    """

    def __init__(self, layout: Layout, noise: SensorNoise, seed: int) -> None:
        self.layout = layout
        self.noise = noise
        self._rng = np.random.default_rng([seed, 4])  # [seed, 1..3]: the kinematic simulations' draws
        scale = np.array([1.0, 1.0, 1.0, TORQUE_ARM_M, TORQUE_ARM_M, TORQUE_ARM_M])
        self._scale = scale
        self.offsets = {c: self._rng.normal(0.0, noise.force_offset_n, 6) * scale for c in layout.wrists}

    def encoders(self, data: mujoco.MjData) -> FloatArray:
        """The encoders' readings (nj,) rad, scene joint order."""
        true = data.qpos[self.layout.qpos]
        if not self.noise.encoder_rad:
            return np.array(true)
        return np.asarray(true + self._rng.normal(0.0, self.noise.encoder_rad, true.shape))

    def wrists(self, data: mujoco.MjData) -> dict[str, FloatArray]:
        """Each wrist sensor's reading (6,): its tool's weight, its offset and noise included."""
        return {
            chain: sensor_wrench(data, sensor)
            + self.offsets[chain]
            + self._rng.normal(0.0, self.noise.force_n, 6) * self._scale
            for chain, sensor in self.layout.wrists.items()
        }

    def imu(self, data: mujoco.MjData) -> FloatArray:
        """The base's orientation (3, 3) in the world, as an IMU in the base reads it."""
        return np.array(data.xmat[self.layout.base_body].reshape(3, 3))

    def soles(self, data: mujoco.MjData) -> tuple[FloatArray, ...]:
        """Each sole sensor's reading (6,): the floor's wrench on the sole, sole frame (stance order)."""
        return tuple(sensor_wrench(data, sensor) for sensor in self.layout.soles.values())
