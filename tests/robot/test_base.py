"""BaseRobot: a backend that inherits it writes only what it has (issue 25, part 1)."""

from __future__ import annotations

import pytest

from shadowhound.robot.base import BaseRobot, Robot, RobotError
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.state import Posture, RobotState


class Minimal(BaseRobot):
    """A robot with a pose, velocity, stops, a latch and postures, and nothing else."""

    name = "minimal"
    description = "a minimal robot"

    def __init__(self) -> None:
        self.state = RobotState()
        self.stops = 0

    def get_state(self) -> RobotState:
        return self.state

    def last_state(self) -> RobotState:
        return self.state

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        pass

    def stop(self) -> None:
        self.stops += 1

    def emergency_stop(self) -> None:
        self.stop()

    def release_estop(self) -> None:
        pass

    def set_posture(self, posture: Posture) -> None:
        pass


def test_a_minimal_backend_is_a_robot_with_the_defaults() -> None:
    robot = Minimal()
    assert isinstance(robot, Robot)
    assert (robot.time_scale, robot.realtime, robot.latency) == (1.0, True, 0.0)
    before = robot.now()
    robot.sleep(0.01)
    assert robot.now() >= before + 0.01
    assert robot.get_camera_frame() is None and robot.get_scan() is None
    assert robot.belief() is None and robot.navigator() is None
    assert robot.known_objects() == () and robot.bearings() == ()
    assert robot.vocabulary() == frozenset()
    robot.look()
    heard: list[bool] = []
    robot.watch_estop(heard.append)
    assert heard == []
    with pytest.raises(RobotError, match="a minimal robot has no voice"):
        robot.say("hello")
    with pytest.raises(RobotError, match="a minimal robot performs no tricks"):
        robot.perform("hello")
    robot.close()
    assert robot.stops == 1  # closing stops it


def test_what_every_robot_must_say_for_itself_is_abstract() -> None:
    class Nameless(BaseRobot):
        pass

    with pytest.raises(TypeError, match="abstract"):
        Nameless()  # type: ignore[abstract]


def test_the_simulator_inherits_the_defaults_it_shares() -> None:
    robot = SimRobot(time_scale=0.0)
    assert isinstance(robot, BaseRobot)
    assert robot.bearings() == () and robot.navigator() is None and robot.latency == 0.0
    assert robot.time_scale == 0.0 and not robot.realtime  # its own clock, not the wall's
    robot.say("hello")  # its own voice: the record
    assert robot.spoken == ["hello"]
