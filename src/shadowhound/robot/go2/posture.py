"""A Go2's posture as `go2_states` shows it, and waiting for a posture command to finish.

go2_ros2_sdk copies the robot's sport-mode state: `mode` and `body_height` tell the posture
(through go2_api's one table), while `progress` stays 0 during postures and says nothing about
their end. So a posture command is done when go2_states shows the posture it leads to (and,
after BalanceStand, a mode in which the robot walks). A posture counts once every report for
`SETTLE` seconds shows it: go2_states may flap (a single report of "sitting" 0.07 s into a
1.5 s Sit is no sitting robot). Firmware differ in the mode they report after StandUp (JointLock
6; Damping 7 on some), so before BalanceStand standing is judged by the body height alone, and
for `STAND_UP_BOUND` seconds at most (`stood_up`). No rclpy here: the robot hands in each
report and a check for the e-stop.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TypeVar

from ...state import Posture
from ..base import RobotError
from . import api as go2_api

_T = TypeVar("_T")
_POLL = 0.02  # seconds between looks at go2_states while a posture runs
SETTLE = 0.25  # seconds every report must show a posture before it counts
# Seconds after StandUp (or RiseSit) that BalanceStand waits for go2_states to show the body
# standing: a StandUp takes 1-2 s; after this BalanceStand goes anyway (the robot queues
# posture commands, as go2_ros2_sdk's joystick, which sends both back to back, relies on).
STAND_UP_BOUND = 3.0
# Modes of a robot that fell (motors limp, or getting up after a fall): it does not stand.
# Damping at standing height may also be a robot standing after StandUp (some firmware): it
# still counts as fallen here (the robot's state says lying until BalanceStand), while the
# posture read (go2_api.posture_of) and `stood_up` see it standing, so standing up from there
# sends BalanceStand only.
FALL_MODES = frozenset({go2_api.SportMode.DAMPING, go2_api.SportMode.RECOVERY_STAND})

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
        self._reports: deque[Report] = deque(maxlen=64)
        self.commanded = False  # a posture command or trick of ours is under way

    def update(self, mode: int, body_height: float) -> Posture | None:
        """A go2_states message arrived; returns the posture it shows once settled (None in
        between, or while the reports disagree)."""
        report = Report(time.monotonic(), mode, body_height)
        with self._lock:
            self._report = report
            self._reports.append(report)
            return self._settled(lambda r: r.posture)

    def observe(self, mode: int, body_height: float) -> Posture | None:
        """`update`, with a fallen robot (limp, or getting up after a fall) lying: it does
        not stand."""
        posture = self.update(mode, body_height)
        return Posture.LYING if self.fallen() else posture

    def fallen(self) -> bool:
        """The last reports (two or more, over `SETTLE`) show a mode of a fallen robot."""
        with self._lock:
            return self._settled(lambda r: r.mode in FALL_MODES) is True

    def _settled(self, view: Callable[[Report], _T]) -> _T | None:
        """What `view` shows of the latest report, if every report of the last `SETTLE`
        seconds, and the one before them, show the same (else None). Lock held."""
        if not self._reports:
            return None
        latest = self._reports[-1]
        seen = view(latest)
        for report in reversed(self._reports):
            if view(report) != seen:
                return None
            if latest.receipt - report.receipt >= SETTLE:
                return seen
        return None

    def fresh(self) -> Report | None:
        """The latest report, if recent and settled (its posture shown for `SETTLE` s)."""
        with self._lock:
            report = self._report
            settled = self._settled(lambda r: (r.posture, r.balanced)) is not None
        recent = report is not None and time.monotonic() - report.receipt <= self.stale
        return report if recent and settled else None

    def balanced(self) -> bool:
        report = self.fresh()
        return report is not None and report.balanced

    def describe(self) -> str:
        """The latest report in words (for messages)."""
        with self._lock:
            report = self._report
        if report is None:
            return "no messages"
        recent = time.monotonic() - report.receipt <= self.stale
        return report.describe() if recent else "no recent messages"

    def current(self) -> Posture:
        """The robot's posture, waiting (bounded) for a report that shows one."""
        deadline = time.monotonic() + self.timeout
        while True:
            report = self.fresh()
            if report is not None and report.posture is not None:
                return report.posture
            if time.monotonic() > deadline:
                raise RobotError(
                    f"cannot tell the robot's posture: {self.topic} shows {self.describe()} after "
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
                    f"{self.timeout:.0f} s: {self.topic} shows {self.describe()}; check that "
                    "nothing else (the phone app, a joystick) holds the robot and that it has "
                    "room"
                )
            time.sleep(_POLL)

    def stood_up(self, what: str, bound: float = STAND_UP_BOUND) -> bool:
        """Wait until go2_states shows the body at standing height (settled), whatever the
        mode; False once `bound` seconds (at most `timeout`) pass without it."""
        deadline = time.monotonic() + min(bound, self.timeout)
        while True:
            with self._lock:
                report = self._report
                standing = self._settled(
                    lambda r: go2_api.at_height(Posture.STANDING, r.body_height)
                )
            if standing and report is not None and time.monotonic() - report.receipt <= self.stale:
                return True
            self._check_estop(f"waiting for {what}")
            if time.monotonic() > deadline:
                return False
            time.sleep(_POLL)

    def pause(self, seconds: float, what: str) -> None:
        """Let `seconds` pass (a trick runs), ending early when the e-stop is pressed."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self._check_estop(f"waiting for {what}")
            time.sleep(min(_POLL * 5, max(0.0, end - time.monotonic())))


# The sport requests a posture change sends, by name (for messages).
STEP_NAMES = {
    go2_api.STAND_UP: "StandUp",
    go2_api.BALANCE_STAND: "BalanceStand",
    go2_api.RISE_SIT: "RiseSit",
    go2_api.SIT: "Sit",
    go2_api.STAND_DOWN: "StandDown",
}


def plan(current: Posture, posture: Posture) -> list[tuple[Posture, tuple[int, ...]]]:
    """The postures from `current` to `posture` (sitting <-> lying goes through standing), each
    with the sport api ids that lead to it. Standing with locked joints (after a StandUp from
    elsewhere) only needs balancing."""
    path = [current, posture]
    if Posture.STANDING not in path:
        path = [current, Posture.STANDING, posture]
    steps = (
        [(go2_api.BALANCE_STAND,)]
        if current is posture
        else [STEPS[(a, b)] for a, b in zip(path, path[1:], strict=False)]
    )
    return list(zip(path[1:], steps, strict=True))


class SportBody:
    """Posture changes and tricks through the sport API, as both Go2 backends run them.

    `watch` is the robot's PostureWatch; `request(api_id)` sends one sport request; `halt()`
    stops the robot if it moves. `estopped` is the e-stop latch, read and written under the
    robot's `lock`. `driven_until` (monotonic) is when the body may stop moving without a
    velocity command, after a posture or trick of ours (`settle` seconds after its end).
    """

    def __init__(
        self,
        watch: PostureWatch,
        request: Callable[[int], None],
        halt: Callable[[], None],
        lock: threading.Lock,
        settle: float,
    ) -> None:
        self.watch, self._request, self._halt = watch, request, halt
        self._lock, self._settle = lock, settle
        self.estopped = False
        self.driven_until = 0.0

    def latch(self, latched: bool) -> None:
        """Latch the e-stop (True) or release it (False)."""
        with self._lock:
            self.estopped = latched

    def check_estop(self, doing: str) -> None:
        """RobotError while the e-stop is latched (`doing` says what it refuses)."""
        with self._lock:
            estopped = self.estopped
        if estopped:
            raise RobotError(f"e-stop is latched; release it before {doing}")

    @contextlib.contextmanager
    def commanded(self) -> Iterator[None]:
        """A posture or trick of ours runs: its posture changes are no fall, and the body may
        move without a velocity command (for a while after, too)."""
        self.watch.commanded = True
        try:
            yield
        finally:
            self.watch.commanded = False
            self.driven_until = time.monotonic() + self._settle

    def set_posture(
        self, posture: Posture, late_stand: Callable[[str], None] | None = None
    ) -> None:
        """Go to `posture` through standing, one sport request at a time, each done when the
        state shows the posture it leads to; nothing is sent when already there. After StandUp
        (or RiseSit), BalanceStand waits for the body to stand (`watch.stood_up`), and
        `late_stand(what)` hears when that wait ran out."""
        posture = Posture(posture)
        self.check_estop("changing posture")
        watch = self.watch
        current = watch.current()
        if current is posture and (posture is not Posture.STANDING or watch.balanced()):
            return
        self._halt()  # the robot must be still before it changes posture
        with self.commanded():
            for target, api_ids in plan(current, posture):
                for api_id, then in zip(api_ids, (*api_ids[1:], None), strict=True):
                    balance = api_id == go2_api.BALANCE_STAND
                    if balance and watch.balanced():
                        continue  # RiseSit already ends balanced: no redundant command
                    self._request(api_id)
                    what = f"{STEP_NAMES[api_id]} (api id {api_id})"
                    if then == go2_api.BALANCE_STAND:
                        if not watch.stood_up(what) and late_stand is not None:
                            late_stand(what)
                    else:  # the posture shows (after BalanceStand: in a mode that walks)
                        watch.reach(target, what, balance)

    def perform(self, trick: str, before: Callable[[], None] | None = None) -> None:
        """Run the trick `trick` (go2_api.TRICKS, checked by the caller) from standing and wait
        until the robot stands again; `before()` runs first, inside the command."""
        info = go2_api.TRICKS[trick]
        self.check_estop(f"performing {trick}")
        posture = self.watch.current()
        if posture is not Posture.STANDING:
            raise RobotError(
                f"cannot perform {trick} while the robot is {posture.value}; stand up first"
            )
        with self.commanded():
            if before is not None:
                before()
            self._request(info.api_id)
            self.watch.pause(info.duration, f"{trick} (api id {info.api_id})")
            self.watch.reach(Posture.STANDING, trick)


def trick_info(trick: str) -> go2_api.Trick:
    """The trick's entry in go2_api.TRICKS; RobotError naming the known ones otherwise."""
    info = go2_api.TRICKS.get(trick)
    if info is None:
        raise RobotError(f"unknown trick {trick!r}; known: {', '.join(go2_api.TRICKS)}")
    return info


def finite_velocity(vx: float, vy: float, wz: float) -> tuple[float, float, float]:
    """A body-frame velocity as floats; RobotError unless all are finite."""
    values = (float(vx), float(vy), float(wz))
    if not all(math.isfinite(v) for v in values):
        raise RobotError(f"velocity must be finite numbers, got {values}")
    return values


def capped(
    values: tuple[float, float, float], max_linear: float, max_angular: float
) -> tuple[float, float, float]:
    """The velocity within the caps: the planar speed scaled down to `max_linear`, the turn
    rate clipped to `max_angular`."""
    norm = math.hypot(values[0], values[1])
    scale = max_linear / norm if norm > max_linear else 1.0
    return values[0] * scale, values[1] * scale, max(-max_angular, min(max_angular, values[2]))
