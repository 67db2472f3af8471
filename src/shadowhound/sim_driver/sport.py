"""SimSportMode: the Go2's sport-mode service as go2_ros2_sdk reaches it, over a SimRobot.

What the robot itself does with the commands the driver forwards (no ROS here; the simulated
driver in `shadowhound.sim_driver.driver` puts the topics around it):

- Move (1008) sets the walking velocity, which lapses after `move_timeout` seconds unless a
  new Move renews it; StopMove (1003) stops at once. Moves are obeyed only in a walking mode
  (BalanceStand or locomotion) and not while a posture changes or a trick runs.
- Posture commands (go2_api.POSTURE_CHANGES) run one at a time, in order, and take time; the
  mode changes when one starts (to a mode in which the robot walks only when it ends: it
  ignores Moves until then) and the body height moves to the new posture's meanwhile;
  `progress` is not raised by them (only tricks raise it). StandUp leaves the robot standing
  with its joints locked (`stand_up_mode`: JOINT_LOCK, or the mode another firmware reports,
  e.g. DAMPING), ignoring Moves until BalanceStand.
- Tricks run only while standing balanced; the "ai"-mode ones only after MOTION_SWITCH {"name":
  "ai"} on the motion switcher topic.

Ground truth (`truth()`) is the simulator's exact state plus what was received; it is kept
apart from anything the driver publishes, so tests judge by it.
"""

from __future__ import annotations

import logging
import math
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from typing import Any

from ..robot.base import RobotError
from ..robot.go2 import api as go2_api
from ..robot.go2.api import (
    BODY_HEIGHT,
    BODY_HEIGHT_TOLERANCE,
    POSTURE_CHANGES,
    WALKING_MODES,
    PostureChange,
    SportMode,
)
from ..robot.sim.robot import SimRobot
from ..state import Posture

Report = Callable[[bool, str], None]  # (accepted, note) once the robot acts on a request
_TRICKS_BY_ID = {t.api_id: t for t in go2_api.TRICKS.values()}
_TRICK_MODES = {
    1030: SportMode.FRONT_FLIP,
    1031: SportMode.FRONT_JUMP,
    1032: SportMode.FRONT_POUNCE,
}
_log = logging.getLogger(__name__)
_SETTLE_LIMIT = 10.0  # seconds a posture change waits for the body to come to rest
_START_MODES = {
    Posture.STANDING: SportMode.BALANCE_STAND,
    Posture.SITTING: SportMode.SIT,
    Posture.LYING: SportMode.LIE_DOWN,
}
_MODE_SHIFT = 0.3  # share of the posture time a mode change without a posture change takes
_HEIGHT_MARGIN = 1.25 * BODY_HEIGHT_TOLERANCE  # how far from its end a body height stays


@dataclass
class _Change:
    """A posture change under way: braking until `start` is set, then `seconds` long."""

    command: PostureChange
    height_from: float
    height_to: float
    start: float | None = None
    seconds: float = 0.0

    def done(self, now: float) -> bool:
        return self.start is not None and now - self.start >= self.seconds

    def height(self, now: float) -> float:
        """The body height on the way: it nears the new posture's height but enters its
        tolerance only when the change completes, so the reports never run ahead of it."""
        span = self.height_to - self.height_from
        if self.start is None or abs(span) <= _HEIGHT_MARGIN:
            return self.height_from
        part = min(1.0, (now - self.start) / self.seconds) if self.seconds > 0 else 1.0
        return self.height_from + (span - math.copysign(_HEIGHT_MARGIN, span)) * part


@dataclass(frozen=True)
class Truth:
    """The simulated robot as it really is (odom frame; velocities in the body frame)."""

    mono: float  # time.monotonic() when taken
    x: float
    y: float
    yaw: float
    vx: float
    vy: float
    wz: float
    posture: Posture  # the posture the body is in (the old one until a change completes)
    mode: int
    body_height: float
    changing: str  # name of the posture command under way, '' when none
    trick: str  # name of the trick under way, '' when none
    moving: bool
    moves: int  # Move commands received (from Twists and from webrtc_req)
    moves_ignored: int  # ... of which the robot ignored (not in a walking mode)
    moves_lapsed: int  # Moves that ran out without a renewal
    stop_moves: int  # StopMove commands received
    requests: int  # sport requests received (every api id, Move and StopMove included)
    ai_mode: bool
    battery: float  # percent drained from full by the simulator (the driver offsets it)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["posture"] = self.posture.value
        return out


class SimSportMode:
    """The robot's sport-mode service over `sim` (a real-time SimRobot)."""

    def __init__(
        self,
        sim: SimRobot,
        *,
        move_timeout: float = 1.0,
        posture_seconds: float = 1.5,
        start: Posture = Posture.STANDING,
        stand_up_mode: SportMode = SportMode.JOINT_LOCK,
    ) -> None:
        self.sim = sim
        self.move_timeout = move_timeout
        self.posture_seconds = posture_seconds
        stand_up = replace(POSTURE_CHANGES[go2_api.STAND_UP], mode=stand_up_mode)
        self._changes = {
            **POSTURE_CHANGES,
            go2_api.STAND_UP: replace(stand_up, mode_after=stand_up_mode),
        }
        self._cond = threading.Condition()
        self._mode = _START_MODES[start]  # a Go2 boots standing, balanced
        sim.set_posture(start, seconds=0.0)
        self._change: _Change | None = None
        self._trick = ""
        self._lapse_at: float | None = None
        self._counts = {
            "moves": 0,
            "moves_ignored": 0,
            "moves_lapsed": 0,
            "stop_moves": 0,
            "requests": 0,
        }
        self._ai_mode = False
        self._jobs: queue.Queue[tuple[int, Report] | None] = queue.Queue()
        self._closed = False
        self._threads = [
            threading.Thread(target=self._run_jobs, name="sport-postures", daemon=True),
            threading.Thread(target=self._run_lapses, name="sport-lapse", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        self._jobs.put(None)
        self.sim.stop()
        for thread in self._threads:
            thread.join(2.0)

    # -- commands --------------------------------------------------------------------------

    def request(
        self,
        api_id: int,
        parameter: Any,
        topic: str = go2_api.SPORT_TOPIC,
        report: Report = lambda _ok, _note: None,
    ) -> None:
        """One sport request as the robot receives it; `report` is called once, when the
        robot acts on it or ignores it (later for queued postures and tricks)."""
        with self._cond:
            self._counts["requests"] += 1
        if topic == go2_api.MOTION_SWITCHER_TOPIC and api_id == go2_api.MOTION_SWITCH:
            name = parameter.get("name") if isinstance(parameter, dict) else None
            if name not in ("ai", "normal"):
                report(False, f"ignored: motion mode {name!r} is not 'ai' or 'normal'")
                return
            with self._cond:
                self._ai_mode = name == "ai"
            report(True, "")
        elif topic != go2_api.SPORT_TOPIC:
            report(False, f"not simulated: topic {topic!r}")
        elif api_id == go2_api.STOP_MOVE:
            self.stop_move()
            report(True, "")
        elif api_id == go2_api.MOVE:
            try:
                x, y, z = (float(parameter[k]) for k in ("x", "y", "z"))
            except (TypeError, KeyError, ValueError) as exc:
                with self._cond:
                    self._counts["moves"] += 1
                    self._counts["moves_ignored"] += 1
                report(
                    False,
                    f"ignored: Move needs {{'x','y','z'}} numbers, got {parameter!r} ({exc!r})",
                )
                return
            note = self.move(x, y, z)
            report(not note, note)
        elif api_id in self._changes or api_id in _TRICKS_BY_ID:
            self._jobs.put((api_id, report))
        else:
            report(False, f"not simulated: api id {api_id}")

    def move(self, x: float, y: float, z: float) -> str:
        """Walk at (x, y, z) until the Move lapses; returns why it was ignored, or ''."""
        with self._cond:
            self._counts["moves"] += 1
            why = self._why_not_walking()
            if why:
                self._counts["moves_ignored"] += 1
                return f"ignored: {why}"
            try:
                self.sim.send_velocity(x, y, z)
            except Exception as exc:  # RobotError for non-finite values
                self._counts["moves_ignored"] += 1
                return f"ignored: {exc}"
            self._lapse_at = time.monotonic() + self.move_timeout
            self._cond.notify_all()
        return ""

    def stop_move(self) -> None:
        """StopMove: the walking velocity goes to zero at once (the body brakes)."""
        with self._cond:
            self._counts["stop_moves"] += 1
            self._lapse_at = None
            self.sim.stop()

    def fall(self) -> None:
        """The robot falls (fault injection): it brakes as it goes down, lies limp (Damping),
        and ignores Moves until StandUp (or RecoveryStand) gets it up."""
        with self._cond:
            self._lapse_at = None
            self._change = None
            self._trick = ""
            self._mode = SportMode.DAMPING  # from now on Moves are ignored
            self.sim.stop()
            self._cond.notify_all()
        self.sim.set_posture(Posture.LYING, seconds=0.0)  # once the body has come to rest

    def _why_not_walking(self) -> str:
        self._finish_due_change()
        if self._change is not None:
            return f"{self._change.command.name} is under way"
        if self._trick:
            return f"{self._trick} is under way"
        if self._mode not in WALKING_MODES:
            return f"mode {self._mode.name} does not walk (BalanceStand first)"
        return ""

    # -- what the robot reports ------------------------------------------------------------

    def truth(self) -> Truth:
        with self._cond:
            self._finish_due_change()
            st = self.sim.get_state()
            return Truth(
                mono=time.monotonic(),
                x=st.x,
                y=st.y,
                yaw=st.yaw,
                vx=st.vx,
                vy=st.vy,
                wz=st.wz,
                posture=st.posture,
                mode=int(self._current_mode(st.is_moving)),
                body_height=self._body_height(st.posture),
                changing=self._change.command.name if self._change else "",
                trick=self._trick,
                moving=st.is_moving,
                ai_mode=self._ai_mode,
                battery=st.battery if st.battery is not None else 0.0,
                **self._counts,
            )

    def _current_mode(self, moving: bool) -> SportMode:
        if self._change is not None:  # Moves are ignored until it ends: no walking mode yet
            mode = self._change.command.mode
            return self._mode if mode in WALKING_MODES else mode
        if self._trick:
            return _TRICK_MODES.get(go2_api.TRICKS[self._trick].api_id, self._mode)
        if self._mode in WALKING_MODES:
            return SportMode.LOCOMOTION if moving else SportMode.BALANCE_STAND
        return self._mode

    def _body_height(self, posture: Posture) -> float:
        if self._change is None:
            return BODY_HEIGHT[posture]
        return self._change.height(time.monotonic())

    def _finish_due_change(self) -> None:
        """End the posture change whose time is up (whoever looks first, with the lock held),
        so the truth, the mode and the body height all show the new posture at once."""
        change = self._change
        if change is None or not change.done(time.monotonic()):
            return
        self.sim.set_posture(change.command.target, seconds=0.0)
        self._mode = change.command.mode_after
        self._change = None
        self._cond.notify_all()

    # -- the robot's own loops -------------------------------------------------------------

    def _run_lapses(self) -> None:
        """A Move runs out `move_timeout` after the last one, as the firmware's does."""
        with self._cond:
            while not self._closed:
                if self._lapse_at is None:
                    self._cond.wait()
                    continue
                left = self._lapse_at - time.monotonic()
                if left > 0:
                    self._cond.wait(left)
                    continue
                self._lapse_at = None
                self._counts["moves_lapsed"] += 1
                self.sim.send_velocity(0.0, 0.0, 0.0)

    def _run_jobs(self) -> None:
        while (job := self._jobs.get()) is not None:
            api_id, report = job
            change = self._changes.get(api_id)
            if change is not None:
                self._change_posture(change, report)
            else:
                self._perform(api_id, report)

    def _change_posture(self, command: PostureChange, report: Report) -> None:
        posture = self.sim.get_state().posture
        if posture not in command.needs:
            needs = " or ".join(sorted(p.value for p in command.needs))
            report(False, f"ignored: {command.name} needs the robot {needs}, it is {posture.value}")
            return
        with self._cond:  # no more walking: brake, then change
            self._lapse_at = None
            self.sim.stop()
            self._change = _Change(command, BODY_HEIGHT[posture], BODY_HEIGHT[command.target])
        self._settle()
        if command.target is not posture:
            seconds = command.share * self.posture_seconds
        elif self._mode != command.mode_after:  # same posture, another mode: a short shift
            seconds = min(command.share, _MODE_SHIFT) * self.posture_seconds
        else:
            seconds = 0.0  # already there: the robot acknowledges and stays
        with self._cond:
            change = self._change
            change.start, change.seconds = time.monotonic(), seconds
        report(True, "")
        with self._cond:
            while self._change is change and not self._closed:
                self._finish_due_change()
                if self._change is change:
                    self._cond.wait(max(0.001, change.start + seconds - time.monotonic()))

    def _perform(self, api_id: int, report: Report) -> None:
        trick = _TRICKS_BY_ID[api_id]
        with self._cond:
            why = self._why_not_walking()
            if not why and api_id in go2_api.AI_MODE_TRICKS and not self._ai_mode:
                why = "needs the 'ai' motion mode (firmware permitting)"
            if why:
                report(False, f"ignored: {why}")
                return
            self._lapse_at = None
            self._trick = trick.name
        report(True, "")
        try:
            self.sim.perform(trick.name)
        except RobotError as exc:  # cannot happen in a walking mode; say so if it does
            _log.warning("the simulator refused %s: %s", trick.name, exc)
        finally:
            with self._cond:
                self._trick = ""

    def _settle(self) -> None:
        deadline = time.monotonic() + _SETTLE_LIMIT
        while self.sim.get_state().is_moving and time.monotonic() < deadline:
            self.sim.sleep(0.02)

    @property
    def progress(self) -> int:
        """`go2_states.progress`: 1 while a trick (a dance, a flip) runs; postures leave it 0."""
        with self._cond:
            return 1 if self._trick else 0
