"""A navigator: something outside the agent that walks the robot to a goal along its own path
(Nav2's NavigateToPose on a Go2; the `navigate_to_pose` server of `shadowhound sim-driver`).

A robot declares whether it has one (`Robot.navigator()`, None when not); `nav.goto` uses it
according to the `navigation` setting (auto | nav2 | direct). Pure Python: the ROS client is in
robot/go2_nav2.py. Nav2's error codes are put into words here, in one table.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Protocol


class NavStatus(enum.Enum):
    """Where a goal stands."""

    PENDING = "pending"  # sent, not yet accepted
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"  # rejected or aborted by the navigator
    CANCELED = "canceled"


@dataclass(frozen=True)
class NavFeedback:
    """Nav2's NavigateToPose feedback, in SI units."""

    distance_remaining: float  # metres along the navigator's path
    recoveries: int  # recovery behaviours run so far (spin, back up, clearing the costmap)
    navigation_time: float  # seconds since the goal started
    estimated_time_remaining: float  # seconds


@dataclass(frozen=True)
class NavReport:
    """A goal's status, its latest feedback (None before the first) and, once it has ended
    without success, why, in words."""

    status: NavStatus
    feedback: NavFeedback | None = None
    message: str = ""

    @property
    def done(self) -> bool:
        return self.status in (NavStatus.SUCCEEDED, NavStatus.FAILED, NavStatus.CANCELED)


class NavGoal(Protocol):
    """One goal in flight. Both methods are thread-safe and never block for long."""

    def report(self) -> NavReport: ...

    def cancel(self) -> None:
        """Ask the navigator to cancel this goal (no-op once it has ended)."""
        ...


class Navigator(Protocol):
    """A navigation server the robot can hand goals to."""

    @property
    def name(self) -> str:
        """For messages: "Nav2 (/navigate_to_pose)"."""
        ...

    def ready(self, timeout: float) -> bool:
        """True when the server answers, waiting at most `timeout` seconds for it."""
        ...

    def navigate(self, x: float, y: float, yaw: float) -> NavGoal:
        """Send a goal (odom frame, metres and radians). Raises RobotError when the goal
        cannot be sent; a refusal by the server shows in the goal's report."""
        ...

    def cancel_all(self) -> None:
        """Cancel every goal this client sent that is still running (stop and e-stop)."""
        ...


# Nav2 Jazzy's error codes (nav2_msgs action results; the NavigateToPose result carries the
# code of the server that failed), in words for people.
NAV2_ERRORS: dict[int, str] = {
    100: "the controller failed (unknown error)",
    101: "the controller plugin asked for does not exist",
    102: "the controller could not transform the robot's pose (TF error)",
    103: "the controller was given an invalid path",
    104: "the controller's patience ran out (the robot was blocked too long)",
    105: "the robot failed to make progress along the path",
    106: "the controller found no valid velocity command (no collision-free motion)",
    107: "the controller timed out",
    200: "the planner failed (unknown error)",
    201: "the planner plugin asked for does not exist",
    202: "the planner could not transform the poses (TF error)",
    203: "the robot's position is outside the map",
    204: "the goal is outside the map",
    205: "the robot's position is occupied on the costmap",
    206: "the goal is occupied on the costmap (inside an obstacle or its inflation)",
    207: "the planner timed out",
    208: "there is no valid path to the goal",
    300: "the planner failed (unknown error)",
    304: "a goal is outside the map",
    306: "a goal is occupied on the costmap",
    308: "there is no valid path through the poses",
    500: "the path smoother failed (unknown error)",
    501: "the smoother plugin asked for does not exist",
    502: "the path smoother timed out",
    503: "the smoothed path is in collision",
    504: "the path smoother failed to smooth the path",
    505: "the path smoother was given an invalid path",
    700: "the spin recovery failed",
    701: "the spin recovery timed out",
    702: "the spin recovery could not transform the robot's pose (TF error)",
    703: "the spin recovery stopped: collision ahead",
    710: "the back-up recovery failed",
    711: "the back-up recovery timed out",
    712: "the back-up recovery could not transform the robot's pose (TF error)",
    713: "the back-up recovery was given invalid input",
    714: "the back-up recovery stopped: collision ahead",
    720: "drive on heading failed",
    721: "drive on heading timed out",
    722: "drive on heading could not transform the robot's pose (TF error)",
    723: "drive on heading stopped: collision ahead",
    724: "drive on heading was given invalid input",
}


def nav2_error_words(code: int, message: str = "") -> str:
    """Nav2's error code (and its own message, when it gave one) as a sentence."""
    words = NAV2_ERRORS.get(code)
    if words is None:
        words = "navigation failed" if code == 0 else f"navigation failed (Nav2 error code {code})"
    else:
        words = f"{words} (Nav2 error code {code})"
    message = " ".join(message.split())
    return f"{words}: {message}" if message else words
