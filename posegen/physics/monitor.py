"""What really happened in a run, sample by sample: the simulator's ground truth, which no controller reads.

Per sample: the free base's height, each sole's position, the true ZMP's margin inside
the true support polygon (the sole boxes where they are), the largest joint torque over
its effort limit, each hand's normal force on the table (the tip spheres' contacts), and
every contact of another robot shape with the floor or the table (an unwanted contact).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from posegen.physics.builder import Layout
from posegen.physics.geometry import ShapeRole
from posegen.physics.sensors import sensor_wrench
from posegen.robot import FloatArray, centre_of_pressure, convex_hull_clockwise, cross, polygon_margin

_CODES = {role: k for k, role in enumerate(ShapeRole)}
_TIP, _BODY = _CODES[ShapeRole.TIP], _CODES[ShapeRole.BODY]
ZMP_EVERY = 10  # samples between two ZMP margins (50 Hz at the default rate: the polygon's hull costs)


@dataclass(frozen=True)
class Touch:
    """An unwanted contact: a robot link on the floor or the table."""

    time_s: float
    link: str
    obstacle: str  # "floor" or "table"
    depth_m: float  # penetration


@dataclass
class Truth:
    """The ground truth of every sample (arrays filled by :class:`Monitor`)."""

    pelvis_z: FloatArray  # (n,) m
    soles_xy: FloatArray  # (n, 2, 2) m, each sole frame's origin
    zmp_margin: FloatArray  # (n,) m, negative outside the polygon; every ZMP_EVERY-th sample, NaN between
    torque_ratio: FloatArray  # (n,) the largest |torque| / effort
    worst_joint: np.ndarray  # (n,) its index (scene order)
    contact_force: dict[str, FloatArray]  # chain -> (n,) N, normal force on the table
    touches: list[Touch] = field(default_factory=list)


class Monitor:
    """Reads the ground truth of a sample from the simulator's state.

    Example:
        >>> monitor = Monitor(model, layout, samples=1000, foot=(x_range, y_range))
        >>> monitor.record(data, index=0, time_s=0.0)

    """

    def __init__(
        self,
        model: mujoco.MjModel,
        layout: Layout,
        samples: int,
        foot: tuple[tuple[float, float], tuple[float, float]],
    ) -> None:
        self.model = model
        self.layout = layout
        chains = sorted({s.chain for s in layout.shapes if s.role == ShapeRole.TIP})
        self.truth = Truth(
            np.zeros(samples),
            np.zeros((samples, 2, 2)),
            np.zeros(samples),
            np.zeros(samples),
            np.zeros(samples, dtype=np.int64),
            {c: np.zeros(samples) for c in chains},
        )
        (x0, x1), (y0, y1) = foot
        self._corners = np.array([[x, y, 0.0] for x in (x0, x1) for y in (y0, y1)])  # (4, 3) in a sole frame
        self._role_codes = np.array([_CODES[s.role] for s in layout.shapes])
        self._tip_chain = [s.chain for s in layout.shapes]
        self._effort = layout.effort
        self._last_touch: dict[tuple[str, str], float] = {}
        self._wrench = np.zeros(6)

    def _sole_frames(self, data: mujoco.MjData) -> list[tuple[FloatArray, FloatArray]]:
        """(rotation (3, 3), origin (3,)) of each sole frame (its sensor site), stance order."""
        out = []
        for sensor in self.layout.soles.values():
            site = sensor.site
            out.append((data.site_xmat[site].reshape(3, 3), data.site_xpos[site].copy()))
        return out

    def _zmp_margin(self, data: mujoco.MjData, soles: list[tuple[FloatArray, FloatArray]]) -> float:
        total = np.zeros(6)
        corners: list[FloatArray] = []
        for (rotation, origin), sensor in zip(soles, self.layout.soles.values(), strict=True):
            wrench = sensor_wrench(data, sensor)
            force = rotation @ wrench[:3]
            total += np.concatenate([force, rotation @ wrench[3:] + cross(origin, force)])
            if force[2] > 1.0:  # a sole that carries the robot
                corners.extend((self._corners @ rotation.T + origin)[:, :2])
        if total[2] <= 1.0 or not corners:
            return -np.inf
        zmp = centre_of_pressure(total[2], total[3:5])
        return float(polygon_margin(convex_hull_clockwise(np.array(corners)), zmp))

    def _contacts(self, data: mujoco.MjData, index: int, time_s: float) -> None:
        for chain in self.truth.contact_force:
            self.truth.contact_force[chain][index] = 0.0
        if not data.ncon:
            return
        pairs = data.contact.geom[: data.ncon]  # (ncon, 2)
        roles = self._role_codes[pairs]  # (ncon, 2)
        for k in np.flatnonzero((roles == _TIP).any(axis=1)):
            tip = pairs[k][int(roles[k][1] == _TIP)]
            mujoco.mj_contactForce(self.model, data, int(k), self._wrench)
            self.truth.contact_force[self._tip_chain[tip]][index] += abs(self._wrench[0])
        for k in np.flatnonzero((roles == _BODY).any(axis=1)):
            side = int(roles[k][1] == _BODY)
            body, other = int(pairs[k][side]), int(pairs[k][1 - side])
            link, obstacle = self.layout.shapes[body].link, self.layout.shapes[other].name
            if time_s - self._last_touch.get((link, obstacle), -np.inf) > 0.1:  # one report per episode
                self.truth.touches.append(Touch(time_s, link, obstacle, float(-data.contact.dist[k])))
            self._last_touch[(link, obstacle)] = time_s

    def record(self, data: mujoco.MjData, index: int, time_s: float) -> None:
        """Record sample ``index`` from the simulator's current state."""
        truth = self.truth
        truth.pelvis_z[index] = data.xpos[self.layout.base_body][2]
        soles = self._sole_frames(data)
        truth.soles_xy[index] = [origin[:2] for _, origin in soles]
        truth.zmp_margin[index] = self._zmp_margin(data, soles) if index % ZMP_EVERY == 0 else np.nan
        ratio = np.abs(data.actuator_force[self.layout.actuator]) / self._effort
        worst = int(np.argmax(ratio))
        truth.torque_ratio[index], truth.worst_joint[index] = ratio[worst], worst
        self._contacts(data, index, time_s)
