"""A Go2's posture as `go2_states` shows it, and waiting for a posture command to finish.

go2_ros2_sdk copies the robot's sport-mode state: `mode` and `body_height` tell the posture
(through go2_api's one table), while `progress` stays 0 during postures and says nothing about
their end. So a posture command is done when go2_states shows the posture it leads to (and,
after BalanceStand, a mode in which the robot walks). No rclpy here: the robot hands in each
report and a check for the e-stop.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from ..state import Posture
from . import go2_api
from .base import RobotError

_POLL = 0.02  # seconds between looks at go2_states while a posture runs

# Sport api ids that take the robot from one posture to the next (sitting is left with
# RiseSit); each is followed by a wait until go2_states shows the posture it leads to.
STEPS: dict[tuple[Posture, Posture], tuple[int, ...]] = {
    (Posture.LYING, Posture.STANDING): (go2_api.STAND_UP, go2_api.BALANCE_STAND),
    (Posture.SITTING, Posture.STANDING): (go2_api.RISE_SIT, go2_api.BALANCE_STAND),
    (Posture.STANDING, Posture.SITTING): (go2_api.SIT,),
    (Posture.STANDING, Posture.LYING): (go2_api.STAND_DOWN,),
}


@dataclass(frozen=True)
class Report:
    """One go2_states message: when it arrived (monotonic), the mode and the body height."""

    receipt: float
    mode: int
    body_height: float

    @property
    def posture(self) -> Posture | None:
        return go2_api.posture_of(self.mode, self.body_height)

    @property
    def balanced(self) -> bool:
        """Standing in a mode in which the robot obeys Moves."""
        return self.mode in go2_api.WALKING_MODES

    def describe(self) -> str:
        seen = self.posture.value if self.posture else "in between"
        return f"mode {self.mode} ({seen}), body height {self.body_height:.2f} m"


class PostureWatch:
    """The latest go2_states report, and bounded waits on it.

    `check_estop(doing)` raises when the e-stop is latched; `topic` names go2_states in
    messages; `timeout` bounds each wait; a report older than `stale` seconds does not count.
    """

    def __init__(
        self, check_estop: Callable[[str], None], topic: str, timeout: float, stale: float
    ) -> None:
        self._check_estop, self.topic, self.timeout, self.stale = (
            check_estop,
            topic,
            timeout,
            stale,
        )
        self._lock = threading.Lock()
        self._report: Report | None = None

    def update(self, mode: int, body_height: float) -> Posture | None:
        """A go2_states message arrived; returns the posture it shows (None in between)."""
        report = Report(time.monotonic(), mode, body_height)
        with self._lock:
            self._report = report
        return report.posture

    def fresh(self) -> Report | None:
        with self._lock:
            report = self._report
        return report if report and time.monotonic() - report.receipt <= self.stale else None

    def balanced(self) -> bool:
        report = self.fresh()
        return report is not None and report.balanced

    def _seen(self) -> str:
        with self._lock:
            report = self._report
        if report is None:
            return "no messages"
        return report.describe() if self.fresh() is not None else "no recent messages"

    def current(self) -> Posture:
        """The robot's posture, waiting (bounded) for a report that shows one."""
        deadline = time.monotonic() + self.timeout
        while True:
            report = self.fresh()
            if report is not None and report.posture is not None:
                return report.posture
            if time.monotonic() > deadline:
                raise RobotError(
                    f"cannot tell the robot's posture: {self.topic} shows {self._seen()} after "
                    f"{self.timeout:.0f} s; check that go2_ros2_sdk is running and connected "
                    "(`shadowhound doctor --go2`)"
                )
            self._check_estop("changing posture")
            time.sleep(_POLL)

    def reach(self, target: Posture, what: str, balanced: bool = False) -> None:
        """Wait until go2_states shows `target` (and a walking mode when `balanced`)."""
        deadline = time.monotonic() + self.timeout
        while True:
            report = self.fresh()
            if (
                report is not None
                and report.posture is target
                and (not balanced or report.balanced)
            ):
                return
            self._check_estop(f"waiting for {what}")
            if time.monotonic() > deadline:
                raise RobotError(
                    f"{what} sent, but the robot did not reach {target.value} within "
                    f"{self.timeout:.0f} s: {self.topic} shows {self._seen()}; check that "
                    "nothing else (the phone app, a joystick) holds the robot and that it has "
                    "room"
                )
            time.sleep(_POLL)

    def pause(self, seconds: float, what: str) -> None:
        """Let `seconds` pass (a trick runs), ending early when the e-stop is pressed."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self._check_estop(f"waiting for {what}")
            time.sleep(min(_POLL * 5, max(0.0, end - time.monotonic())))
