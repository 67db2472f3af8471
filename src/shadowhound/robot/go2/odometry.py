"""Odometry as evidence, not truth: each Go2 pose is checked before it moves the robot's pose.

A Go2's odometry can be wrong while it still arrives: SLAM relocalizes (the pose jumps), two
SDKs publish on one network (go2_ros2_sdk #28), the driver's clock steps, the stream freezes
with fresh stamps, a value is NaN. Believed, any of these walks the robot, in truth, beyond
what the person allowed. `OdometryIntake` stands between the messages and `MotionTracker`:

- a pose that is not finite, or absurdly far (beyond `MAX_COORDINATE`), is refused;
- stamps going back (a clock step) reset the stamp clock;
- a pose change the robot cannot make in the time between the samples (at `max_speed`,
  `max_yaw_rate`, with slack for samples that arrive in bursts: a late sample is not a jump) is
  a jump: the tracker starts a new frame from it and the odometer does not count it;
- a pose that stops changing while motion is commanded, once odometry has shown this motion
  (so the latency is known and a late sample is not taken for a freeze), is a freeze;
- a pose that moves while nothing has been commanded for longer than the latency and a stop
  take is motion nobody here commanded (a joystick, another controller);
- outside problems (a second odometry publisher on the graph) are reported by the robot.

Each fault makes odometry untrusted until `recover` seconds of consistent samples have arrived
since the last bad one (and no outside problem remains); `receive` returns a fault only when
it begins, so the robot stops once.

It also keeps how late the stream ran (`stalls`): a sample that came in later than its stamp
says it was sent (this process or the link stalled), or a pause in the stamps beyond the
stream's usual rate (the driver stalled), and, near such a stall, a start it showed later than
the latency says (its commands were held up: MotionTracker.held). A loaded machine stalls the
commands going out as it stalls the poses coming in; a step allows for what was seen
(skills/bounds.py). Taken from when samples were sent and came in, and when odometry first
showed a start, never from how far a pose says the robot went. No rclpy and no clock of its
own: every call takes the time.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from ...state import normalize_angle
from ..base import MAX_STALL, Stall
from .motion import MotionTracker
from .stamps import StampClock

MAX_COORDINATE = 1.0e5  # metres: farther than any robot's odometry frame can honestly reach
_CHANGED = 0.001  # metres (and radians) a pose must change by to count as new
_SHOWN = 0.25  # ... or this share of what the commands moved it by since the sample before
_GOOD_SAMPLES = 5  # consistent samples (besides `recover` seconds) before trusting again
_STALLS_KEPT = 30.0  # seconds of stalls `stalled` can look back over
_DISTURBS = 0.05  # seconds of stall that make a motion's odometry no measure of the latency
_LOADED = 2.0  # seconds from a stall of the stream within which a late start was held up too


@dataclass(frozen=True)
class OdometryLimits:
    """What the robot can do, as far as checking its odometry goes."""

    max_speed: float = 1.25  # m/s: the Go2's command cap (1.0) and a margin
    max_yaw_rate: float = 2.5  # rad/s: the Go2's cap (2.0) and a margin
    burst: float = 0.5  # s: the most a burst of late samples may compress time
    noise: float = 0.03  # m (and rad) of noise allowed beyond the kinematic bound
    clock_step: float = 0.05  # s a stamp may go back before it is a clock step
    freeze_distance: float = 0.08  # m the model moved while odometry stood still: a freeze
    freeze_turn: float = 0.15  # rad, likewise for turning
    uncommanded_speed: float = 0.15  # m/s measured with nothing commanded: someone else drives
    uncommanded_yaw_rate: float = 0.3  # rad/s
    stop_seconds: float = 1.5  # s a stopped robot may still move (braking) beyond the latency
    recover: float = 1.0  # s of consistent odometry before it is trusted again


@dataclass(frozen=True)
class OdometryFault:
    """Why odometry is not believed: `kind` (non-finite, out-of-range, jump, clock, frozen,
    uncommanded, publishers), the message for a person, and when (monotonic seconds)."""

    kind: str
    message: str
    at: float


class OdometryIntake:
    """Checks odometry samples, feeds the good ones to `tracker`, keeps the odometer."""

    def __init__(
        self,
        tracker: MotionTracker,
        limits: OdometryLimits | None = None,
        clock: StampClock | None = None,
    ) -> None:
        self.tracker = tracker
        self.limits = limits or OdometryLimits()
        self.clock = clock or StampClock()
        self.distance = 0.0  # metres the odometer counted (consistent samples only)
        self.turned = 0.0  # radians
        self.moving = 0.0  # seconds between consecutive samples that showed motion
        self._fault: OdometryFault | None = None
        self._bad_at = -math.inf  # when the last bad sample arrived
        self._good = 0  # consistent samples since then
        self._outside: dict[str, OdometryFault] = {}  # problems reported by the robot
        self._last_stamp = 0.0
        self._times: deque[float] = deque(maxlen=40)  # recent sample times (for burst gaps)
        self._stalls: deque[Stall] = deque()  # the stream's stalls, in the order seen
        self._gaps: deque[float] = deque(maxlen=200)  # recent gaps between sample times
        self._changed_at: float | None = None  # when odometry last showed a new pose
        self._shown_motion = False  # odometry changed since motion was last commanded

    # -- inputs ------------------------------------------------------------------------

    def receive(
        self,
        arrival: float,
        stamp: float,
        x: float,
        y: float,
        yaw: float,
        *,
        driven_elsewhere: bool = False,
    ) -> OdometryFault | None:
        """One odometry message (arrival on our monotonic clock, its header stamp in seconds).
        Returns the fault it begins, if any. `driven_elsewhere`: something the robot knows of
        (Nav2) drives it, so motion without our command is expected."""
        pose = (x, y, yaw)
        if not all(math.isfinite(v) for v in pose):
            return self._bad(
                "non-finite",
                f"odometry sent a pose that is not a number (x={x}, y={y}, yaw={yaw})",
                arrival,
            )
        if abs(x) > MAX_COORDINATE or abs(y) > MAX_COORDINATE:
            return self._bad(
                "out-of-range",
                f"odometry sent a pose {max(abs(x), abs(y)):.3g} m from its origin (at most "
                f"{MAX_COORDINATE:g} m is believable)",
                arrival,
            )
        fault = None
        stamp = stamp if math.isfinite(stamp) else 0.0
        if stamp > 0 and self._last_stamp - stamp > self.limits.clock_step:
            back = self._last_stamp - stamp
            self.clock = StampClock(self.clock.window, self.clock.jump)  # learn it anew
            fault = self._bad(
                "clock",
                f"odometry stamps went back {back:.2f} s (the driver's clock was set back?)",
                arrival,
            )
        if stamp > 0:
            self._last_stamp = stamp
        t = self.clock.local_time(stamp, arrival)
        self._note_stall(arrival, t)
        last = self.tracker.last_sample()
        jump = self._jump(last.t, (last.x, last.y, last.yaw), t, pose) if last else ""
        if jump:
            self.tracker.restart()  # a new frame begins here
            self.tracker.odometry(t, x, y, yaw)
            self._changed_at = t
            return self._bad("jump", jump, arrival) or fault
        if last is not None:
            step = math.hypot(x - last.x, y - last.y)
            turn = abs(normalize_angle(yaw - last.yaw))
            self.distance += step
            self.turned += turn
            # A new pose: it moved, or as far as a slow command moves it between two samples
            # (a correction at 1 degree/s turns less than _CHANGED from one to the next).
            moved, turned = self.tracker.model_motion(last.t, t)
            if step > min(_CHANGED, _SHOWN * moved) or turn > min(_CHANGED, _SHOWN * turned):
                self.moving += min(max(0.0, t - last.t), self.limits.burst)  # not a gap's
                self._changed_at = t
                self._shown_motion = self._shown_motion or self.tracker.commanding
        elif self._changed_at is None:
            self._changed_at = t
        self.tracker.odometry(t, x, y, yaw)
        self._times.append(t)
        problem = self._frozen(t) or self._uncommanded(t, driven_elsewhere)
        if problem:
            return self._bad(problem[0], problem[1], arrival) or fault
        if fault is None:
            self._good += 1
        return fault

    def command(self, t: float, vx: float, vy: float, wz: float) -> None:
        """Velocity commanded from time t (0 = stop), as the tracker takes it."""
        if not any((vx, vy, wz)):
            self._shown_motion = False
        elif not self.tracker.commanding:
            self._shown_motion = False  # a new start from rest: odometry must show it anew
        self.tracker.command(t, vx, vy, wz)

    def report(self, kind: str, message: str | None, at: float) -> OdometryFault | None:
        """A problem the robot found outside the samples (`message` None: it is gone).
        Returns the fault when it begins."""
        if message is None:
            self._outside.pop(kind, None)
            return None
        new = kind not in self._outside
        self._outside[kind] = OdometryFault(kind, message, at)
        return self._outside[kind] if new else None

    # -- outputs -----------------------------------------------------------------------

    def stalls(self, since: float) -> tuple[Stall, ...]:
        """The stalls that ended since `since` (the clock of `arrival`): the stream's, and
        starts it showed later than the latency says (MotionTracker.held) on a loaded machine:
        within `_LOADED` seconds of a stall of the stream. On a quiet one a late start is the
        robot's own, or a lie's shape, and allowed nothing."""
        seen = [s for s in self._stalls if s.end >= since - _LOADED]
        held = [
            h
            for h in self.tracker.held(since)
            if any(s.start - _LOADED <= h.start <= s.end + _LOADED for s in seen)
        ]
        return (*(s for s in seen if s.end >= since), *held)

    def stalled(self, since: float) -> float:
        """Seconds: the longest of `stalls(since)`."""
        return max((s.seconds for s in self.stalls(since)), default=0.0)

    def problem(self, now: float) -> str | None:
        """Why odometry is not trusted now (None: it is)."""
        if self._outside:
            return "; ".join(f.message for f in self._outside.values())
        fault = self._fault
        if fault is None:
            return None
        if now - self._bad_at >= self.limits.recover and self._good >= _GOOD_SAMPLES:
            self._fault = None
            return None
        return (
            f"{fault.message} ({now - fault.at:.1f} s ago; trusted again after "
            f"{self.limits.recover:g} s of consistent odometry)"
        )

    # -- checks ------------------------------------------------------------------------

    def _bad(self, kind: str, message: str, arrival: float) -> OdometryFault | None:
        begins = self._fault is None
        self._bad_at = arrival
        self._good = 0
        if begins or self._fault is None or self._fault.kind != kind:
            self._fault = OdometryFault(kind, message, arrival)
        return self._fault if begins else None

    def _jump(
        self,
        t0: float,
        a: tuple[float, float, float],
        t1: float,
        b: tuple[float, float, float],
    ) -> str:
        """Why the change from a (at t0) to b (at t1) is more than the robot can do ('' if
        it is not)."""
        lim = self.limits
        dt = max(0.0, t1 - t0) + self._slack()
        moved = math.hypot(b[0] - a[0], b[1] - a[1])
        turned = abs(normalize_angle(b[2] - a[2]))
        can_move = lim.max_speed * dt + lim.noise
        can_turn = lim.max_yaw_rate * dt + lim.noise
        if moved > can_move:
            return (
                f"odometry jumped {moved:.2f} m from ({a[0]:.2f}, {a[1]:.2f}) to ({b[0]:.2f}, "
                f"{b[1]:.2f}) where the robot can move at most {can_move:.2f} m: a "
                "relocalization, a second odometry source or a driver fault"
            )
        if turned > can_turn:
            return (
                f"odometry's heading jumped {math.degrees(turned):.0f} degrees where the "
                f"robot can turn at most {math.degrees(can_turn):.0f}: a relocalization, a "
                "second odometry source or a driver fault"
            )
        return ""

    def _note_stall(self, arrival: float, t: float) -> None:
        """Keep how late the sample that arrived at `arrival`, sent at `t` (this clock), was:
        later than sent (this process or the link stalled), or after a pause in what was sent
        beyond the usual gap (the driver stalled)."""
        gaps = sorted(self._gaps)
        usual = gaps[len(gaps) * 9 // 10] if len(gaps) >= 10 else math.inf  # bursts are usual
        gap = t - self._times[-1] if self._times else 0.0
        self._gaps.append(gap)
        while self._stalls and self._stalls[0].end < arrival - _STALLS_KEPT:
            self._stalls.popleft()
        # Late: held from when it was sent. After a pause: the sender stalled at some moment
        # after the sample before (a stall is as long as it is beyond the usual gap).
        for stall, seconds in ((Stall(t, arrival), arrival - t), (Stall(t - gap, t), gap - usual)):
            if seconds > 1e-3:  # a millisecond is the link's and the scheduler's noise
                self._stalls.append(stall)
            if seconds > _DISTURBS:
                self.tracker.disturbed()

    def _slack(self) -> float:
        """Time a burst may have compressed: the longest recent gap between samples (a burst
        delivers what a gap held back), at least 0.1 s, at most `burst`."""
        times = list(self._times)
        gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
        return min(self.limits.burst, max([0.1, *gaps]))

    def _frozen(self, t: float) -> tuple[str, str] | None:
        """Odometry stands still while the model, which odometry has been following since
        this motion began, says the robot has moved on."""
        if not (self.tracker.commanding and self._shown_motion) or self._changed_at is None:
            return None
        # A stall seen meanwhile held the commands up as long (the driver's process, the link):
        # the robot only then went on as they say.
        held = min(MAX_STALL, self.stalled(self._changed_at))
        if self._changed_at + held >= t:
            return None
        moved, turned = self.tracker.model_motion(self._changed_at + held, t)
        lim = self.limits
        if moved < lim.freeze_distance and turned < lim.freeze_turn:
            return None
        return (
            "frozen",
            f"odometry has not changed for {t - self._changed_at:.1f} s while the robot was "
            f"commanded to move (about {moved:.2f} m, {math.degrees(turned):.0f} degrees): "
            "the odometry stream is frozen, or the robot is held",
        )

    def _uncommanded(self, t: float, driven_elsewhere: bool) -> tuple[str, str] | None:
        lim = self.limits
        if driven_elsewhere:
            return None
        # Odometry late by up to the latency (or, before it is measured, by the most it may
        # be) still shows motion that was commanded: that is no one else driving.
        if self.tracker.idle_since(t) < self.tracker.latency_bound + lim.stop_seconds:
            return None
        vx, vy, wz = self.tracker.measured_velocity()
        speed = math.hypot(vx, vy)
        if speed < lim.uncommanded_speed and abs(wz) < lim.uncommanded_yaw_rate:
            return None
        return (
            "uncommanded",
            f"odometry shows the robot moving ({speed:.2f} m/s, "
            f"{math.degrees(abs(wz)):.0f} degrees/s) with no command from ShadowHound: a "
            "joystick or another controller drives it",
        )
