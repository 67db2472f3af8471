"""The `Robot` protocol: the small surface every robot (simulated or real) implements.

Skills drive robots only through this protocol. Motion is commanded as body-frame velocity
and closed on the measured pose (`get_state`), so the same skill code runs on the simulator
and on a Go2 through ROS 2.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from ..state import CameraFrame, Posture, RobotState, Scan
from .navigator import Navigator


class RobotError(Exception):
    """The robot refused or failed a command. The message is for people."""


@runtime_checkable
class Robot(Protocol):
    """A quadruped the agent can drive. Implementations must make `stop` thread-safe."""

    name: str

    def get_state(self) -> RobotState:
        """The latest state (pose from odometry, posture, battery)."""
        ...

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Command body-frame velocity (m/s, m/s, rad/s). Ignored unless standing."""
        ...

    def stop(self) -> None:
        """Zero velocity now. Safe to call from any thread, at any time."""
        ...

    def set_posture(self, posture: Posture) -> None:
        """Stand, sit or lie down; returns when the transition is done. Raises RobotError."""
        ...

    def perform(self, trick: str) -> None:
        """Run a sport-mode trick by name (see go2_api.TRICKS); returns when done."""
        ...

    def now(self) -> float:
        """Seconds on the robot's clock (simulated or wall)."""
        ...

    def sleep(self, seconds: float) -> None:
        """Let `seconds` of robot time pass (the control loop's tick)."""
        ...

    def get_camera_frame(self) -> CameraFrame | None:
        """The robot's own latest camera frame, if it has a camera."""
        ...

    def get_scan(self) -> Scan | None:
        """The latest planar range scan, or None for a robot without a range sensor."""
        ...

    def navigator(self) -> Navigator | None:
        """The robot's navigation server (Nav2's NavigateToPose), or None when it has none."""
        ...

    def close(self) -> None:
        """Stop and release resources."""
        ...
