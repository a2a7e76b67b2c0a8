"""The run loop: the true robot, its controllers and its sensors, stepped through a planned route.

The simulator steps at ``TIMESTEP_S`` (implicitfast); the controllers run and the
sensors are recorded every ``stride`` steps (the recording rate). Each control period:

1. the sensors are read (encoders, wrist and sole force/torque sensors);
2. the nominal model is updated at the encoders' angles (:class:`NominalRobot`);
3. the hands' contact controllers give their twists (:class:`HandControl`), the
   stabilizer the soles' (:class:`Stabilizer`; its references moved by the hands' planned
   pushes, steady through a hold, not by their measured force), and their joint offset is integrated
   (:class:`JointOffsets`);
4. each joint loop is sent the planned angle plus the offset, the planned velocity, and
   the static torque of the posture as feed-forward (gravity, both soles' shares; a
   hand's push is left to the joint loops).

The robot starts at the route's first posture, its anchor sole flat at its place and its
second leg closed on the floor (the robot put down on its feet: the second leg's angles
solved on the true robot, the stabilizer's offset starting there), and rests
``rest_s`` before the route starts and after it ends. The route's clock waits at the end
of a go-to-contact until the hand's force is reached (:meth:`HandControl.holds_back`): the
recording is that much longer than the plan. A fall (the base lower than planned by
``FALL_M``) ends the run.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from posegen.physics.builder import Built, glue_feet
from posegen.physics.contact_control import SEARCH_TIMEOUT_S, ContactTimes, HandControl
from posegen.physics.gains import SATURATION_RAD, Gains
from posegen.physics.monitor import Monitor, Truth
from posegen.physics.nominal import NominalRobot
from posegen.physics.offsets import JointOffsets
from posegen.physics.plan import Plan
from posegen.physics.sensors import Sensors
from posegen.physics.stabilizer import Reference, SoleReadings, Stabilizer
from posegen.physics.stance import put_down
from posegen.physics.tool import Tool
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import FloatArray, Scene

FALL_M = 0.2  # the base this far below its planned height: fallen
FEED_FORWARD_EVERY = 5  # control periods between two computations of the static feed-forward
LAGGING_RAD = 1.5 * SATURATION_RAD  # a joint this far from its command is held back by its effort limit
PROGRESS_S = 1.0  # robot time between progress reports


@dataclass(frozen=True)
class Recorded:
    """What the robot's sensors recorded (the bag's content), at the recording rate."""

    times_s: FloatArray  # (n,) s from the run's start
    encoders: FloatArray  # (n, nj) rad, scene joint order
    wrists: dict[str, FloatArray]  # chain -> (n, 6) force N, torque N m, sensor frame


@dataclass(frozen=True)
class RunResult:
    """A run: the recording, the ground truth, and where it ended."""

    recorded: Recorded
    truth: Truth
    plan: Plan
    route_index: NDArray[np.int64]  # (n,) the plan's sample each recorded sample ran (the route's clock waits)
    fell_at_s: float | None  # run time of a fall; None: the run completed
    soles_at_start: tuple[FloatArray, ...]  # (4, 4) each true sole frame's world pose when the route starts
    waited_s: dict[str, float]  # contact label -> how long the route waited for its force


class Run:
    """One run of a route on a built robot; :meth:`run` steps it to the end."""

    def __init__(
        self,
        scene: Scene,
        built: Built,
        gains: Gains,
        plan: Plan,
        contacts: tuple[ContactTimes, ...],
        sensors: Sensors,
        tools: dict[str, Tool],
        force_n: float,
        stride: int,
    ) -> None:
        self.scene, self.built, self.gains, self.plan = scene, built, gains, plan
        self.model, self.layout = built.model, built.layout
        self.data = mujoco.MjData(self.model)
        self.sensors = sensors
        self.robot = NominalRobot(scene, tools)
        self.hands = HandControl(self.robot, contacts, force_n)
        self.stabilizer = Stabilizer(scene, self.robot, glued_feet=bool(self.layout.glue))
        self.offsets = JointOffsets(scene, self.robot)
        self.force_n = force_n
        self.stride = stride
        self.period_s = stride * self.model.opt.timestep
        samples = len(plan.times_s) + len(contacts) * int(np.ceil(SEARCH_TIMEOUT_S / self.period_s) + 1)
        self.monitor = Monitor(self.model, self.layout, samples, (scene.stance.foot_x_m, scene.stance.foot_y_m))
        self.encoders = np.zeros((samples, len(scene.joint_names)))
        self.wrists = {c: np.zeros((samples, 6)) for c in self.layout.wrists}
        self.route_index = np.zeros(samples, dtype=np.int64)
        self._torque: FloatArray = np.zeros(len(scene.joint_names))
        self._moving = {chain: np.array(self.offsets.moving(chain), dtype=np.intp) for chain in self.offsets.arms}

    def _control(self, sample: int, index: int) -> None:
        """Read the sensors of ``sample``, record them, and set the joint loops' commands at the plan's ``index``."""
        data, plan = self.data, self.plan
        encoders = self.sensors.encoders(data)
        wrists = self.sensors.wrists(data)
        self.encoders[sample] = encoders
        self.route_index[sample] = index
        for chain, reading in wrists.items():
            self.wrists[chain][sample] = reading
        t_route = plan.times_s[index] - plan.route_start_s
        imu = self.sensors.imu(data)
        self.robot.update(encoders, imu)
        planned = {chain: poses[index] for chain, poses in plan.hands.items()}
        commanded = plan.positions[index] + self.offsets.dq  # within the joint limits
        lag = np.abs(commanded - encoders)
        for chain, moving in self._moving.items():
            self.hands.saturated[chain] = bool((lag[moving] > LAGGING_RAD).any())
        hands = self.hands.step(t_route, wrists, planned, commanded, self.period_s)
        soles = SoleReadings(self.sensors.soles(data))
        attitude = (imu, plan.base_rotation[index])
        reference = Reference(plan.com[index], plan.com_velocity[index], plan.zmp[index], float(plan.pelvis_z[index]))
        pushes = {c: np.array([0.0, 0.0, self.hands.planned_push(c, t_route), 0.0, 0.0, 0.0]) for c in wrists}
        holding = self.hands.holding(t_route)
        feet = self.stabilizer.step(soles, pushes, attitude, reference, self.period_s, holding)
        lagging = frozenset(chain for chain, lags in self.hands.saturated.items() if lags)
        free = not self.hands.in_contact(t_route)
        offset = self.offsets.step(feet, hands, plan.positions[index], self.period_s, free, lagging)
        target = plan.positions[index] + offset
        if sample % FEED_FORWARD_EVERY == 0:  # the posture's statics change slowly
            self._torque = self.robot.static_torques({})
        torque = self._torque
        gains = self.gains
        data.ctrl[self.layout.actuator] = target + (torque + gains.kd * plan.velocities[index]) / gains.kp

    def start(self) -> None:
        """Put the robot down at the route's first posture and settle its state."""
        closed = put_down(self.scene, self.model, self.data, self.layout, self.plan.positions[0])
        self.offsets.dq[:] = closed - self.plan.positions[0]
        if self.layout.glue:
            glue_feet(self.model, self.data, self.layout.glue)

    def run(self, progress: ProgressCallback = ignore_progress) -> RunResult:
        """Step to the end of the plan (or a fall).

        Args:
            progress: Told the robot time done, in seconds, about once per ``PROGRESS_S``.

        """
        self.start()
        plan, data = self.plan, self.data
        soles_at_start: tuple[FloatArray, ...] = ()
        start_index = round(plan.route_start_s / self.period_s)
        fell_at = None
        every = max(round(PROGRESS_S / self.period_s), 1)
        total = int(np.ceil(plan.times_s[-1]))
        sample, index = 0, 0
        while index < len(plan.times_s) and sample < len(self.route_index):
            self._control(sample, index)
            time_s = sample * self.period_s
            self.monitor.record(data, sample, time_s)
            if index == start_index and not soles_at_start:
                soles_at_start = self._sole_poses()
            if self.monitor.truth.pelvis_z[sample] < plan.pelvis_z[index] - FALL_M:
                fell_at = time_s
                sample += 1
                break
            for _ in range(self.stride):
                mujoco.mj_step(self.model, data)
            now, then = (plan.times_s[min(k, len(plan.times_s) - 1)] - plan.route_start_s for k in (index, index + 1))
            if not self.hands.holds_back(now, then, self.period_s):
                index += 1
            if sample % every == 0:
                progress(Progress(min(int(plan.times_s[index - 1]), total), total, "second"))
            sample += 1
        return RunResult(
            self._recorded(sample),
            self._truth(sample),
            plan,
            self.route_index[:sample].copy(),
            fell_at,
            soles_at_start,
            dict(self.hands.waited_s),
        )

    def _sole_poses(self) -> tuple[FloatArray, ...]:
        poses = []
        for sensor in self.layout.soles.values():
            pose = np.eye(4)
            pose[:3, :3] = self.data.site_xmat[sensor.site].reshape(3, 3)
            pose[:3, 3] = self.data.site_xpos[sensor.site]
            poses.append(pose)
        return tuple(poses)

    def _recorded(self, samples: int) -> Recorded:
        times = np.arange(samples) * self.period_s
        return Recorded(times, self.encoders[:samples], {c: w[:samples] for c, w in self.wrists.items()})

    def _truth(self, samples: int) -> Truth:
        truth = self.monitor.truth
        return Truth(
            truth.pelvis_z[:samples],
            truth.soles_xy[:samples],
            truth.zmp_margin[:samples],
            truth.torque_ratio[:samples],
            truth.worst_joint[:samples],
            {c: f[:samples] for c, f in truth.contact_force.items()},
            truth.touches,
        )
