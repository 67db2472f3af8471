"""Relocalizing: a real SimRobot seen through SLAM's map frame (issue 24).

The pose every reader outside the simulator gets is the truth moved by `error`: where SLAM
believes the robot is (`error` zero: SLAM is right). `jump_after` makes SLAM's belief jump to a
new error once the true robot has walked (or turned) that far, as a loop closure or a
relocalization does: the state then counts it (`relocalized`) and carries it (`jumps`), as the
Go2 robot reports SLAM's map -> odom jumps, and gives odometry's own pose (`odometry`). The
simulator inside keeps the truth.
"""

from __future__ import annotations

import dataclasses
import math

from shadowhound import SimRobot
from shadowhound.state import RobotState, compose, inverse
from tests.lying_odometry import LyingOdometry

Pose = tuple[float, float, float]


class Relocalizing(LyingOdometry):
    """The Robot protocol over a real SimRobot, in a SLAM map that may be off and jump."""

    def __init__(self, sim: SimRobot | None = None, error: Pose = (0.0, 0.0, 0.0)) -> None:
        super().__init__(sim)
        self.lies = {}
        self.error = error
        self.jumps: Pose = (0.0, 0.0, 0.0)
        self.relocalized = 0
        self._pending: tuple[float, float, Pose] | None = None
        self._counted = True
        self.corrected = 0  # corrections made, counted or not

    def jump_after(
        self, to: Pose, metres: float = 0.0, degrees: float = 0.0, counted: bool = True
    ) -> None:
        """SLAM's error becomes `to` once the truth has walked `metres` or turned `degrees`
        from now. `counted` False: a correction smaller than a jump, which the Go2 robot
        absorbs (the map pose moves, `relocalized` and `jumps` stay)."""
        now = self.sim.get_state()
        self._pending = (
            now.distance_travelled + metres,
            now.angle_turned + math.radians(degrees),
            to,
        )
        self._counted = counted

    def _lie(self, state: RobotState) -> RobotState:
        pending = self._pending
        if pending is not None and (
            state.distance_travelled >= pending[0] and state.angle_turned >= pending[1]
        ):
            if self._counted:
                moved = compose(pending[2], inverse(self.error))  # how the map moved under it
                self.jumps = compose(moved, self.jumps)
                self.relocalized += 1
            self.error, self._pending = pending[2], None
            self.corrected += 1
        x, y, yaw = compose(self.error, (state.x, state.y, state.yaw))
        return dataclasses.replace(  # odometry's own pose is the simulator's, as a Go2's
            state,
            x=x,
            y=y,
            yaw=yaw,
            relocalized=self.relocalized,
            jumps=self.jumps,
            odometry=(state.x, state.y, state.yaw),
        )
