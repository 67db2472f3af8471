"""LyingOdometry: a real SimRobot whose odometry, as the agent reads it, lies (issue 21).

A Go2's odometry can deliver NaN or infinite poses. This robot wraps a real simulator and
hands every reader outside it (the agent, skills, interfaces) a state with the fields in
`lies` replaced, while the simulator inside keeps its own true pose (its camera and physics
still work). Set `lies` to {} and the odometry tells the truth again.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from shadowhound import SimRobot
from shadowhound.robot.base import Stall
from shadowhound.state import CameraFrame, Posture, RobotState, Scan

if TYPE_CHECKING:
    from shadowhound.robot.navigator import Navigator
    from shadowhound.world import Belief, KnownObject
    from shadowhound.world.image_sighting import Bearing


class LyingOdometry:
    """The Robot protocol over a real SimRobot, with a lying pose."""

    def __init__(self, sim: SimRobot | None = None, **lies: float) -> None:
        self.sim = sim or SimRobot(time_scale=0.0)
        self.name = self.sim.name
        self.description = self.sim.description
        self.lies: dict[str, float] = lies or {"x": math.nan}

    def _lie(self, state: RobotState) -> RobotState:
        return dataclasses.replace(state, **self.lies) if self.lies else state

    @property
    def time_scale(self) -> float:
        return self.sim.time_scale

    @property
    def realtime(self) -> bool:
        return self.sim.realtime

    def get_state(self) -> RobotState:
        return self._lie(self.sim.get_state())

    def last_state(self) -> RobotState:
        return self._lie(self.sim.last_state())

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        self.sim.send_velocity(vx, vy, wz)

    def stop(self) -> None:
        self.sim.stop()

    def emergency_stop(self) -> None:
        self.sim.emergency_stop()

    def release_estop(self) -> None:
        self.sim.release_estop()

    def watch_estop(self, listener: Callable[[bool], None]) -> None:
        self.sim.watch_estop(listener)

    def set_posture(self, posture: Posture) -> None:
        self.sim.set_posture(posture)

    def perform(self, trick: str) -> None:
        self.sim.perform(trick)

    def now(self) -> float:
        return self.sim.now()

    def sleep(self, seconds: float) -> None:
        self.sim.sleep(seconds)

    def get_camera_frame(self) -> CameraFrame | None:
        return self.sim.get_camera_frame()

    def get_scan(self) -> Scan | None:
        return self.sim.get_scan()

    def belief(self) -> Belief | None:
        return self.sim.belief()

    def look(self) -> None:
        self.sim.look()

    def say(self, text: str) -> None:
        self.sim.say(text)

    latency = 0.0  # its pose lies, but not late

    def stalls(self, since: float) -> tuple[Stall, ...]:
        return self.sim.stalls(since)

    def vocabulary(self) -> frozenset[str]:
        return self.sim.vocabulary()

    def bearings(self) -> tuple[Bearing, ...]:
        return self.sim.bearings()

    def known_objects(self) -> tuple[KnownObject, ...]:
        return self.sim.known_objects()

    def navigator(self) -> Navigator | None:
        return self.sim.navigator()

    def close(self) -> None:
        self.sim.close()
