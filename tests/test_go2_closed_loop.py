"""The motion skills on a robot whose odometry is late, as a Go2's is, judged by the truth.

`LateRobot` is a SimRobot (the truth, on its own virtual clock) seen only through odometry
samples that arrive `delay` seconds late at `rate` Hz, read through the Go2 robot's
MotionTracker: the closed loop gets what a Go2 on go2_ros2_sdk gives it, and nothing more.
Over DDS, tests/ros/test_go2_truth.py checks the same with the real driver and processes.
"""

from __future__ import annotations

import math
from collections import deque

import pytest

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import ShadowHoundConfig
from shadowhound.robot.go2_motion import GO2_MOTION, MotionTracker
from shadowhound.robot.sim import SimRobot
from shadowhound.state import CameraFrame, Posture, RobotState


class LateRobot:
    """The Robot protocol over a SimRobot whose pose is known only from late odometry."""

    name = "late-odometry"

    def __init__(self, rate: float, delay: float) -> None:
        self.sim = SimRobot(time_scale=0)
        self.tracker = MotionTracker()
        self.period, self.delay = 1.0 / rate, delay
        self._pending: deque[tuple[float, tuple[float, float, float]]] = deque()
        self._next = 0.0
        self.sleep(1.0)

    def get_state(self) -> RobotState:
        now = self.sim.now()
        x, y, yaw = self.tracker.pose(now)
        vx, vy, wz = self.tracker.velocity(now)
        return RobotState(x=x, y=y, yaw=yaw, vx=vx, vy=vy, wz=wz, battery=None,
                          posture=self.sim.get_state().posture, stamp=now)

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        if not (vx or vy or wz):
            self.stop()
            return
        self.sim.send_velocity(vx, vy, wz)
        self.tracker.command(self.sim.now(), vx, vy, wz)

    def stop(self) -> None:
        self.sim.stop()
        self.tracker.command(self.sim.now(), 0.0, 0.0, 0.0)

    def set_posture(self, posture: Posture) -> None:
        self.sim.set_posture(posture)

    def perform(self, trick: str) -> None:
        self.sim.perform(trick)

    def now(self) -> float:
        return self.sim.now()

    def sleep(self, seconds: float) -> None:
        end = self.sim.now() + seconds
        while self.sim.now() < end - 1e-9:
            self.sim.sleep(min(0.005, end - self.sim.now()))
            now = self.sim.now()
            while self._next <= now + 1e-9:
                s = self.sim.get_state()
                self._pending.append((self._next + self.delay, (s.x, s.y, s.yaw)))
                self._next += self.period
            while self._pending and self._pending[0][0] <= now + 1e-9:
                t, pose = self._pending.popleft()
                self.tracker.odometry(t, *pose)

    def get_camera_frame(self) -> CameraFrame | None:
        return None

    def close(self) -> None:
        self.sim.close()


@pytest.mark.parametrize(("rate", "delay"), [(20.0, 0.0), (20.0, 0.2), (10.0, 0.5)])
def test_walk_and_turn_end_on_target_in_truth_and_report_the_truth(rate: float,
                                                                    delay: float) -> None:
    robot = LateRobot(rate, delay)
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    result = agent.execute_mission("walk forward 1 meter and turn left 90 degrees")
    assert result.success, result.response
    truth = robot.sim.get_state()
    assert math.hypot(truth.x - 1.0, truth.y) < 0.05, (truth.x, truth.y)
    assert abs(math.degrees(truth.yaw) - 90.0) < 3.0, math.degrees(truth.yaw)
    reported = result.robot
    assert math.hypot(reported.x - truth.x, reported.y - truth.y) < 0.05
    assert abs(math.degrees(math.remainder(reported.yaw - truth.yaw, math.tau))) < 3.0
    assert "battery level unknown" in result.response


def test_a_robot_without_a_battery_source_never_claims_a_level() -> None:
    agent = RobotAgent(RobotAgentConfig(robot=LateRobot(20.0, 0.2)))
    assert agent.chat("how is your battery?") == \
        "I cannot tell my battery level: this robot reports none."
    assert agent.get_robot_status()["battery"] is None
    assert "battery unknown" in agent.execute_mission("report your status").response


def test_a_wrong_delay_is_corrected_at_rest_not_reported_as_done() -> None:
    """Odometry later than the robot believes (0.5 s, told 0.2 s, the first guess before any
    measure): the first approach stops off the goal, and a slow approach from rest, with its
    own stall clock, corrects it; the step is judged on the pose at rest."""
    robot = LateRobot(10.0, 0.5)
    robot.tracker = MotionTracker(latency=0.2)
    robot.sleep(1.0)
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    result = agent.execute_mission("walk forward 1 meter")
    assert result.success, result.response
    truth = robot.sim.get_state()
    assert math.hypot(truth.x - 1.0, truth.y) < 0.05, (truth.x, truth.y)
