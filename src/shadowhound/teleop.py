"""Teleoperation: a person drives the robot with the dashboard's pad or keys, through the same
limits as missions.

`Teleop` (one per agent, reached through `MissionWorker.teleop`) is off until a person switches
it on; `start` is refused while a mission runs or waits, while the e-stop is latched, while the
robot is not standing and while the governor would refuse every motion, and while it is on the
worker takes no mission. The page sends the stick's deflection (`drive(forward, left, turn,
seq=...)`, each -1..1) about ten times a second; a control thread at the motion control rate
commands the robot:

- the governor's rules for a skill (`Governor.skill_rules`: `safety.allow_skills`,
  `deny_skills`, the battery floor): forward and back move as `nav.move`, sideways as
  `nav.strafe`, turning as `nav.rotate`, and what the governor would refuse that skill does not
  move (`deny_skills: ["nav.*"]` or a battery below the floor: nothing moves); nor does
  anything while the robot is not standing;
- speed: the deflection times the profile's speed caps (`safety.max_linear_speed`,
  `safety.max_angular_speed`), a diagonal no faster than straight ahead; speeding up ramps at
  `safety.max_linear_accel` / `max_angular_accel`; slowing down and stopping are immediate;
- room: the direction of travel is looked along, from the robot's pose, for the geofence (the
  body's margin kept) and, with a map, anything on it, by the rule a mission's legs are checked
  with (`skills/bounds.room_along`); the speed is cut so the robot can always brake, at
  `safety.max_linear_accel`, `STOP_SHORT` (5 cm) short of either. Turning in place is allowed;
- order: every deflection carries `seq`, a number that grows with every request of a page; one
  not above the last taken arrives late (behind a newer one, or behind the release) and is
  dropped: it neither moves the robot nor keeps it going;
- dead-man: a deflection older than `HEARTBEAT` (0.35 s: the page went away, its connection
  dropped) is zero, and the control tick after it (one period, 0.05 s at 20 Hz) sends the stop:
  `stop_after` (0.4 s) after the page's last word; the robot then brakes in its own time (the
  simulated Go2 at 1 m/s^2: half a second from 0.5 m/s). Letting go sends zero, which stops
  the robot at once (`drive` calls its stop, not waiting for the next tick);
- idle: with no deflection for `teleop.idle_timeout` (60 s) nobody is driving, and it switches
  itself off (`ended` says so), so missions are taken again;
- the e-stop ends teleoperation (the robot is already stopped) and so does `stop`.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .errors import RobotError
from .skills.bounds import STOP_SHORT, brake_speed, room_along
from .state import Posture, RobotState, position_unknown

if TYPE_CHECKING:
    from .agent import RobotAgent
    from .robot.base import Robot
    from .skills.registry import Skill

log = logging.getLogger(__name__)

# Seconds a deflection counts without a new one. The page sends every 0.1 s, so a page that
# goes away has the stop sent within this and one control tick (`stop_after`: 0.4 s), inside
# the 0.5 s a lost page is allowed.
HEARTBEAT = 0.35
MARGIN = STOP_SHORT  # metres kept short of a fence or an obstacle when braking
# The stick's axes, in the order of a deflection (forward, left, turn): each moves as the skill
# that declares it (`Skill.drives`), whose governor rules it keeps.
AXES = ("forward", "sideways", "turn")
_ZERO = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Command:
    """What the control thread sent last, and why it is less than asked (or "")."""

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0
    limited: str = ""


class Teleop:
    def __init__(self, agent: RobotAgent) -> None:
        self._agent = agent
        self._lock = threading.Lock()
        self._on = False
        self._stick = _ZERO
        self._stamp = 0.0  # when the stick was last told (monotonic)
        self._active = 0.0  # when a deflection other than zero last came (or it switched on)
        self._seq = 0  # the last request's number taken this session
        self._sent = Command()
        self._thread: threading.Thread | None = None
        self._stopped = threading.Event()
        self.ended = ""  # why it switched itself off last (idle, the e-stop); "" otherwise

    @property
    def on(self) -> bool:
        return self._on

    @property
    def last(self) -> Command:
        return self._sent

    @property
    def stop_after(self) -> float:
        """Seconds from a page's last word to the dead-man's stop command: the heartbeat and
        the control tick that notices it."""
        return HEARTBEAT + 1.0 / self._agent.settings.motion.control_rate_hz

    @property
    def idle_timeout(self) -> float:
        return self._agent.settings.teleop.idle_timeout

    def start(self, *, thread: bool = True) -> str | None:
        """Switch teleoperation on; None, or why not. The caller (the worker) has checked
        that no mission runs or waits. `thread=False`: the caller runs the control ticks
        (`tick`), as a test does."""
        agent = self._agent
        if agent.estop_latched:
            return "the e-stop is latched: a person must release it first"
        try:
            state = agent.robot.get_state()
        except RobotError as exc:  # a robot that cannot say where it is is not driven blind
            return f"the robot cannot report its state: {exc}"
        if state.posture is not Posture.STANDING:
            return f"the robot is {state.posture.value}: stand it up first ('stand up')"
        refused = self._refusals(state)
        if all(refused):
            why = "; ".join(dict.fromkeys(r for reasons in refused for r in reasons))
            return f"no motion may run ({', '.join(self._motions())}): {why}"
        with self._lock:
            if self._on:
                return None
            now = time.monotonic()
            self._on, self._stick, self._stamp, self._active = True, _ZERO, now, now
            self._seq, self.ended = 0, ""
            self._stopped.clear()
            self._thread = None
            if thread:
                self._thread = threading.Thread(target=self._run, name="shadowhound-teleop")
                self._thread.daemon = True
                self._thread.start()
        return None

    def drive(self, forward: float, left: float, turn: float, *, seq: int) -> str:
        """The stick's deflection (-1..1 each; outside is clipped), the page's `seq`-th word:
        "" when taken, else why it was dropped (a request no newer than the last taken).
        Raises RuntimeError when teleoperation is off."""
        stick = tuple(max(-1.0, min(1.0, float(v))) for v in (forward, left, turn))
        with self._lock:  # between two ticks: none sends an older stick after this
            if not self._on:
                raise RuntimeError("teleoperation is off: switch it on first")
            if seq <= self._seq:
                return (
                    f"request {seq} came after request {self._seq}: a late one, dropped "
                    "(it neither moves the robot nor keeps it going)"
                )
            now = time.monotonic()
            self._seq, self._stick, self._stamp = seq, stick, now  # type: ignore[assignment]
            if stick == _ZERO:
                self._halt()  # let go: stop now, not at the next tick
            else:
                self._active = now
        return ""

    def stop(self, why: str = "") -> None:
        """Switch teleoperation off; the robot stops. `why`: what switched it off, for `ended`
        ("" when a person did)."""
        with self._lock:
            was_on, self._on = self._on, False
            thread = self._thread
            if was_on:
                self.ended = why
                self._halt()
        if thread is not None and thread is not threading.current_thread():
            self._stopped.wait(2.0)

    def _halt(self) -> None:
        try:
            self._agent.robot.stop()
        except RobotError as exc:
            log.warning("teleop: the robot did not take the stop: %s", exc)
        self._sent = Command()

    # -- the control thread ------------------------------------------------------------------

    def _run(self) -> None:
        robot = self._agent.robot
        period = 1.0 / self._agent.settings.motion.control_rate_hz
        try:
            while self.tick(period):
                robot.sleep(period)
                if not robot.realtime:  # a simulator on its own clock: paced by the wall's
                    time.sleep(period)
        finally:
            self._halt()
            self._stopped.set()

    def tick(self, period: float) -> bool:
        """One control tick: the stick, through every limit, to the robot. False once
        teleoperation is off (switched off, the e-stop, nobody driving for the idle time)."""
        agent = self._agent
        # One tick under the lock: a stick let go (or switched off) meanwhile is seen before
        # anything is sent, never overtaken by the tick's older command.
        with self._lock:
            if not self._on:
                return False
            now = time.monotonic()
            if agent.estop_latched:
                self.ended = "the e-stop was pressed"
            elif now - self._active > self.idle_timeout:
                self.ended = f"nobody drove for {self.idle_timeout:g} s (teleop.idle_timeout)"
            else:
                stick = self._stick if now - self._stamp <= HEARTBEAT else _ZERO  # dead-man
                self._tick(agent.robot, stick, period)
                return True
            self._on = False
            self._halt()
            return False

    def _tick(self, robot: Robot, stick: tuple[float, float, float], period: float) -> None:
        command = self._limit(stick, period)
        try:
            if (command.vx, command.vy, command.wz) != _ZERO:
                robot.send_velocity(command.vx, command.vy, command.wz)
            elif (self._sent.vx, self._sent.vy, self._sent.wz) != _ZERO:
                robot.stop()
        except RobotError as exc:
            log.warning("teleop: %s", exc)
            command = Command(limited=str(exc))
        self._sent = command

    def _skills(self) -> list[Skill | None]:
        """Per axis (AXES), the skill whose motion it is (None: this agent has none)."""
        found = {s.drives: s for s in self._agent.registry if s.drives}
        return [found.get(axis) for axis in AXES]

    def _motions(self) -> list[str]:
        skills = zip(self._skills(), AXES, strict=True)
        return [s.name if s else f"no {axis} skill" for s, axis in skills]

    def _refusals(self, state: RobotState) -> list[list[str]]:
        """Per axis (AXES), why the governor would refuse its skill now ([] when not)."""
        governor = self._agent.governor
        return [
            governor.skill_rules(skill, state.battery)
            if skill is not None
            else [f"this agent has no skill that moves {axis}"]
            for skill, axis in zip(self._skills(), AXES, strict=True)
        ]

    def _limit(self, stick: tuple[float, float, float], period: float) -> Command:
        if stick == _ZERO:
            return Command()
        state = self._agent.robot.last_state()
        if state.posture is not Posture.STANDING:
            return Command(limited=f"the robot is {state.posture.value}: stand it up first")
        # An axis whose skill the governor refuses now does not move, saying why.
        refused = [
            reasons[0] if reasons and value else ""
            for value, reasons in zip(stick, self._refusals(state), strict=True)
        ]
        forward, left, turn = (0.0 if why else v for v, why in zip(stick, refused, strict=True))
        held = "; ".join(dict.fromkeys(why for why in refused if why))
        command = self._within_room(state, (forward, left, turn), period)
        if held:
            limited = "; ".join(filter(None, (held, command.limited)))
            return Command(command.vx, command.vy, command.wz, limited)
        return command

    def _within_room(
        self, state: RobotState, stick: tuple[float, float, float], period: float
    ) -> Command:
        lim = self._agent.settings.safety
        forward, left, turn = stick
        norm = math.hypot(forward, left)
        if norm > 1.0:
            forward, left = forward / norm, left / norm
        vx, vy = forward * lim.max_linear_speed, left * lim.max_linear_speed
        wz = turn * lim.max_angular_speed
        before = self._sent
        # Speeding up ramps; slowing down does not wait.
        step = lim.max_linear_accel * period
        speed, was = math.hypot(vx, vy), math.hypot(before.vx, before.vy)
        if speed > was + step:
            scale = (was + step) / speed
            vx, vy = vx * scale, vy * scale
        turn_step = lim.max_angular_accel * period
        if abs(wz) > abs(before.wz) + turn_step:
            wz = math.copysign(abs(before.wz) + turn_step, wz)
        speed = math.hypot(vx, vy)
        if speed < 1e-6:
            return Command(0.0, 0.0, wz)
        pose = state.pose
        if position_unknown(pose):
            return Command(0.0, 0.0, wz, "the robot's position is unknown: turning only")
        heading = pose.yaw + math.atan2(vy, vx)
        reach = speed * speed / (2 * lim.max_linear_accel) + speed * period + 0.5
        room, why = room_along(lim, self._agent.robot.belief(), pose, heading, reach)
        # The fastest speed that still brakes within the room left.
        allowed = brake_speed(room - MARGIN, lim.max_linear_accel, period)
        if allowed < speed:
            scale = allowed / speed
            return Command(vx * scale, vy * scale, wz, f"slowed for {why} ahead" if why else "")
        return Command(vx, vy, wz)
