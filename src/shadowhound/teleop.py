"""Teleoperation: a person drives the robot with the dashboard's pad or keys, through the same
limits as missions.

`Teleop` (one per agent, reached through `MissionWorker.teleop`) is off until a person switches
it on; `start` is refused while a mission runs or waits and while the e-stop is latched, and
while it is on the worker takes no mission. The page sends the stick's deflection
(`drive(forward, left, turn)`, each -1..1) about ten times a second; a control thread at the
motion control rate commands the robot:

- speed: the deflection times the profile's speed caps (`safety.max_linear_speed`,
  `safety.max_angular_speed`), a diagonal no faster than straight ahead; speeding up ramps at
  `safety.max_linear_accel` / `max_angular_accel`; slowing down and stopping are immediate;
- room: the direction of travel is looked along, from the robot's pose, for the geofence (the
  body's margin kept, `skills/bounds.room_ahead`) and, with a map, anything on it
  (`world.check_leg`); the speed is cut so the robot can always brake, at
  `safety.max_linear_accel`, 5 cm short of either. Turning in place is always allowed;
- dead-man: a deflection older than `HEARTBEAT` (0.35 s: the page went away, its connection
  dropped) is zero, and the robot stops; letting go sends zero, which stops the robot at once
  (`drive` calls its stop, not waiting for the next tick);
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
from .skills.bounds import room_ahead
from .state import Posture, position_unknown
from .world import check_leg

if TYPE_CHECKING:
    from .agent import RobotAgent
    from .robot.base import Robot

log = logging.getLogger(__name__)

# Seconds a deflection counts without a new one. The page sends every 0.1 s, so a page that
# goes away has the robot stopped within this and one control tick: 0.4 s, inside the 0.5 s
# a lost page is allowed.
HEARTBEAT = 0.35
MARGIN = 0.05  # metres kept short of a fence or an obstacle when braking


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
        self._stick = (0.0, 0.0, 0.0)
        self._stamp = 0.0
        self._sent = Command()
        self._thread: threading.Thread | None = None
        self._stopped = threading.Event()

    @property
    def on(self) -> bool:
        return self._on

    @property
    def last(self) -> Command:
        return self._sent

    def start(self) -> str | None:
        """Switch teleoperation on; None, or why not. The caller (the worker) has checked
        that no mission runs or waits."""
        agent = self._agent
        if agent.estop_latched:
            return "the e-stop is latched: a person must release it first"
        try:
            state = agent.robot.get_state()
        except RobotError as exc:  # a robot that cannot say where it is is not driven blind
            return f"the robot cannot report its state: {exc}"
        if state.posture is not Posture.STANDING:
            return f"the robot is {state.posture.value}: stand it up first ('stand up')"
        with self._lock:
            if self._on:
                return None
            self._on, self._stick, self._stamp = True, (0.0, 0.0, 0.0), time.monotonic()
            self._stopped.clear()
            self._thread = threading.Thread(target=self._run, name="shadowhound-teleop")
            self._thread.daemon = True
            self._thread.start()
        return None

    def drive(self, forward: float, left: float, turn: float) -> Command:
        """The stick's deflection (-1..1 each; outside is clipped); answers what was sent last.
        Raises RuntimeError when teleoperation is off."""
        if not self._on:
            raise RuntimeError("teleoperation is off: switch it on first")
        stick = tuple(max(-1.0, min(1.0, float(v))) for v in (forward, left, turn))
        with self._lock:  # between two ticks: none sends an older stick after this
            self._stick, self._stamp = stick, time.monotonic()  # type: ignore[assignment]
            if stick == (0.0, 0.0, 0.0):
                self._halt()  # let go: stop now, not at the next tick
        return self._sent

    def stop(self) -> None:
        """Switch teleoperation off; the robot stops."""
        with self._lock:
            was_on, self._on = self._on, False
            thread = self._thread
            if was_on:
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
        agent = self._agent
        robot = agent.robot
        period = 1.0 / agent.settings.motion.control_rate_hz
        try:
            while self._on:
                if agent.estop_latched:
                    self._on = False
                    break
                # One tick under the lock: a stick let go (or switched off) meanwhile is seen
                # before anything is sent, never overtaken by the tick's older command.
                with self._lock:
                    if not self._on:
                        break
                    stick = self._stick
                    if time.monotonic() - self._stamp > HEARTBEAT:
                        stick = (0.0, 0.0, 0.0)  # the page went quiet: dead-man
                    self._tick(robot, stick, period)
                robot.sleep(period)
                if not robot.realtime:  # a simulator on its own clock: paced by the wall's
                    time.sleep(period)
        finally:
            self._halt()
            self._stopped.set()

    def _tick(self, robot: Robot, stick: tuple[float, float, float], period: float) -> None:
        command = self._limit(stick, period)
        try:
            if (command.vx, command.vy, command.wz) != (0.0, 0.0, 0.0):
                robot.send_velocity(command.vx, command.vy, command.wz)
            elif self._sent != Command():
                robot.stop()
        except RobotError as exc:
            log.warning("teleop: %s", exc)
            command = Command(limited=str(exc))
        self._sent = command

    def _limit(self, stick: tuple[float, float, float], period: float) -> Command:
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
        state = self._agent.robot.last_state()
        pose = state.pose
        if position_unknown(pose):
            return Command(0.0, 0.0, wz, "the robot's position is unknown: turning only")
        heading = pose.yaw + math.atan2(vy, vx)
        reach = speed * speed / (2 * lim.max_linear_accel) + speed * period + 0.5
        room, why = room_ahead(lim, pose, heading, reach)
        belief = self._agent.robot.belief()
        if belief is not None:
            end = (pose.x + reach * math.cos(heading), pose.y + reach * math.sin(heading))
            leg = check_leg(belief, (pose.x, pose.y), end)
            if not leg.clear and leg.distance < room:
                room, why = leg.distance, f"{leg.obstacle} ahead"
        # The fastest speed that still brakes within the room left.
        a = lim.max_linear_accel
        usable = max(0.0, room - MARGIN)
        allowed = max(0.0, -a * period + math.sqrt((a * period) ** 2 + 2 * a * usable))
        if allowed < speed:
            scale = allowed / speed
            return Command(vx * scale, vy * scale, wz, f"slowed for {why}" if why else "")
        return Command(vx, vy, wz)
