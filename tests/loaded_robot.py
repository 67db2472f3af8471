"""LoadedRobot: the late-odometry Go2 of test_go2_closed_loop on a loaded machine, exactly.

A machine that runs SLAM, Nav2 and a detector beside ShadowHound (or a CI runner with test
workers) stalls every process now and then: for a fraction of a second a thread gets no CPU.
`Stall`s say who stalls, when and for how long (robot seconds), so a test is the same every
run; between them everything runs on time. Who:

- "controller": ShadowHound's control loop (a sleep ends only once the stall is over);
- "receiver": ShadowHound's ROS thread: odometry that arrives meanwhile waits in DDS's queue
  and comes in one burst when it ends, each sample with its own stamp;
- "process": all of ShadowHound (both): the control loop wakes first, before the burst;
- "driver": the driver's process: commands that reach it meanwhile act when it ends, in order;
  it takes no pose meanwhile (one when it ends) and publishes none (stamped when published);
- "commands": only the driver's command path (its executor busy with a detector's work, say):
  commands act when it ends, while its odometry thread goes on as ever.

Commands act as go2_ros2_sdk's do: a velocity as soon as the driver has it, StopMove at its
10 Hz request loop's next turn. As on the Go2 robot, odometry older than `pose_timeout` while
motion is commanded makes `get_state` raise ("no odometry ...") and `send_velocity` refuse.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

from shadowhound.errors import RobotError
from shadowhound.state import Posture, RobotState
from tests.test_go2_closed_loop import LateRobot

WHO = ("controller", "receiver", "process", "driver", "commands")
_REQUEST_LOOP = 0.1  # seconds between the driver's turns of its request queue
_AFTER = 1e-3  # the ROS thread wakes this much after the control loop from a process stall


@dataclass(frozen=True)
class Stall:
    """`who` gets no CPU from `at` for `seconds` (robot clock)."""

    who: str
    at: float
    seconds: float

    def __post_init__(self) -> None:
        if self.who not in WHO:
            raise ValueError(f"who must be one of {WHO}, got {self.who!r}")


class LoadedRobot(LateRobot):
    """LateRobot whose controller, ROS thread and driver stall as `stalls` say (times from the
    robot's start, after its first odometry has come in)."""

    def __init__(
        self,
        stalls: list[Stall],
        rate: float = 20.0,
        delay: float = 0.2,
        pose_timeout: float = 0.5,
    ) -> None:
        self.schedule = list(stalls)
        self.pose_timeout = pose_timeout
        self._commands: deque[tuple[float, tuple[float, float, float] | None]] = deque()
        self._acted = 0.0  # when the last command acts: commands act in order
        self._arrived = 0.0  # when the last sample arrived: DDS keeps them in order
        self._received: float | None = None  # when odometry last came in
        # Stalls count from the end of LateRobot's start-up wait (odometry has come in), which
        # samples taken before it are published after: they see the stalls too.
        self._origin = 1.0 + delay + 1.0 / rate
        super().__init__(rate, delay)
        assert abs(self.sim.now() - self._origin) < 1e-6, (self.sim.now(), self._origin)

    # -- who is stalled when -----------------------------------------------------------

    def free(self, who: str, t: float) -> float:
        """The first moment at or after `t` at which `who` runs."""
        moved = True
        while moved:
            moved = False
            for s in self.schedule:
                hit = s.who == who or (
                    (s.who, who) in (("process", "controller"), ("process", "receiver"))
                    or (s.who, who) == ("driver", "commands")
                )
                start = self._origin + s.at
                end = (
                    start + s.seconds + (_AFTER if s.who == "process" and who == "receiver" else 0)
                )
                if hit and start <= t < end:
                    t, moved = end, True
        return t

    # -- the Robot protocol ------------------------------------------------------------

    def get_state(self) -> RobotState:
        state = super().get_state()
        if self._moving and not state.connected:
            raise RobotError(self._stale())
        return state

    def last_state(self) -> RobotState:
        state = super().last_state()
        now = self.sim.now()
        fresh = self._received is not None and now - self._received <= self.pose_timeout
        return state if fresh else _disconnected(state)

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        if (vx or vy or wz) and not self.last_state().connected:
            raise RobotError(self._stale() + " Not moving without odometry.")
        super().send_velocity(vx, vy, wz)

    def _walk(self, vx: float, vy: float, wz: float) -> None:
        self._acted = max(self._acted, self.free("commands", self.sim.now()))
        self._commands.append((self._acted, (vx, vy, wz)))

    def stop(self) -> None:
        now = self.sim.now()
        loop = math.ceil(self.free("commands", now) / _REQUEST_LOOP - 1e-9) * _REQUEST_LOOP
        self._acted = max(self._acted, self.free("commands", loop))
        self._commands.append((self._acted, None))
        self._moving = False
        self.intake.command(now, 0.0, 0.0, 0.0)

    def sleep(self, seconds: float) -> None:
        end = self.free("controller", self.sim.now() + seconds)
        while True:
            now = self.sim.now()
            take = self.free("driver", self._next)
            due = [end, take]
            if self._commands:
                due.append(self._commands[0][0])
            if self._pending:
                due.append(self._pending[0][0])
            t = min(due)
            if t > now:
                self.sim.sleep(t - now)
            now = self.sim.now()
            while self._commands and self._commands[0][0] <= now + 1e-9:
                command = self._commands.popleft()[1]
                if command is None:
                    self.sim.stop()
                else:
                    self.sim.send_velocity(*command)
            if take <= now + 1e-9:
                self._take(take)
            while self._pending and self._pending[0][0] <= now + 1e-9:
                arrival, pose, stamp = self._pending.popleft()
                self._received = arrival
                fault = self.intake.receive(arrival, stamp, *pose)
                if fault is not None:
                    self.faults.append(fault.kind)
                    if self._moving:
                        self.stop()
            if now >= end - 1e-9:
                return

    def _take(self, take: float) -> None:
        """The driver takes the true pose at `take` and publishes it `delay` later (stamped
        then); it arrives once ShadowHound's ROS thread runs."""
        s = self.sim.get_state()
        self.truths.append(s)
        fired = self.lying.fired
        shown, shift = self.lying.publish((s.x, s.y, s.yaw))  # as the driver's faults say
        if self.lying.fired and not fired and self.lying.faults.fall:
            self.sim.stop()  # it falls where it is, and lies there
            self.sim.set_posture(Posture.LYING, seconds=0.0)
        published = self.free("driver", take + self.delay)
        self._arrived = max(self._arrived, self.free("receiver", published))
        pose = shown if shown is not None else (math.nan,) * 3
        self._pending.append((self._arrived, pose, published + shift))
        while self._next <= take + 1e-9:
            self._next += self.period

    def _stale(self) -> str:
        age = self.sim.now() - (self._received or 0.0)
        return (
            f"no odometry on odom for {age:.1f} s: is go2_ros2_sdk running and the robot connected?"
        )


def _disconnected(state: RobotState) -> RobotState:
    return replace(state, connected=False)
