"""Where a Go2 is *now*, from odometry that arrives late: a pure-Python dead-reckoning tracker.

go2_ros2_sdk's `odom` is the robot's own pose stream: pose only (its twist is never filled),
stamped when the driver publishes it, and late by a fraction of a second (seconds on a busy
link). A closed loop that steers on it overshoots by speed x delay. `MotionTracker` keeps:

- what was commanded (body-frame velocity, with StopMove as a step to zero), run through a
  model of the robot's response (acceleration-limited) into a dead-reckoned trace;
- the odometry samples, each taken to show the robot `latency` seconds before it arrived;
- starts that odometry showed later than the latency says (`held`): their first commands were
  held up on the way, evidence of a stall the odometry stream alone does not show;
- the latency itself: fixed by configuration, or measured: a first guess each time the robot
  starts from rest (time from the first command to the first sample that shows motion, less
  the time the model needs to show it and half a sample period), then, each time odometry
  shows the robot still again, the delay that best lines the last seconds of odometry up with
  the trace (least squares over a grid of delays); never from a motion whose odometry came in
  stalled (`disturbed`: a loaded machine's stall says nothing of the link's latency).

`pose()` is the last odometry pose moved forward by the trace's motion since that sample was
taken. `velocity()` is the larger of the model's and the odometry's (successive poses), so a
robot counts as still only once odometry has caught up and shows it still: a step reads its
result from a pose that no longer moves, not from a prediction.

No rclpy and no clock of its own: every call takes the time, so tests drive it exactly.

Long because: the model, the samples and the latency are one state that every output reads
(the pose now needs the latency, the latency the model and the samples); the stamp clock
already lives apart (stamps.py).
"""

from __future__ import annotations

import bisect
import math
import statistics
from collections import deque
from dataclasses import dataclass

from ... import robot_config
from ...state import compose, normalize_angle
from ..base import Stall

# Motion control for real odometry, used with robot go2 for every field the profile (or the
# environment) does not set: the simulator's defaults (2 mm, 0.001 degrees, 20 Hz) are exact
# only for the exact simulator; odometry over DDS arrives late and noisy.
GO2_MOTION = robot_config.GO2_MOTION  # the Go2's motion settings (the profile applies them)

_DT = 0.01  # seconds per model integration step
_TRACE_SECONDS = 10.0  # model history kept: more than a fit window plus the largest latency
MAX_LATENCY = 5.0  # seconds: the most odometry is believed to lag (a busy Wi-Fi link: 2-5 s)
_MOTION_EPS = 0.003  # metres (and the same in radians) that count as "it moved"
_STILL_WINDOW = 0.25  # seconds of odometry a velocity is measured over
_FIT_SECONDS = 3.0  # seconds of odometry the delay is fitted over
_BURST = 0.01  # seconds: samples closer together than this came in one burst
_HELD = 0.05  # seconds a start may come later than the latency says before it was held up


@dataclass(frozen=True)
class Sample:
    """One odometry pose and when it arrived (monotonic seconds)."""

    t: float
    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class _Point:
    t: float
    x: float  # dead-reckoned pose in the model's own frame
    y: float
    yaw: float
    vx: float  # model velocity, body frame
    vy: float
    wz: float


def relative(
    a: tuple[float, float, float], b: tuple[float, float, float]
) -> tuple[float, float, float]:
    """The motion from pose a to pose b, in a's frame."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    return dx * c + dy * s, -dx * s + dy * c, normalize_angle(b[2] - a[2])


class MotionTracker:
    """Commands, odometry and latency in; the predicted pose and an honest velocity out.

    `latency` None measures it (starting from `initial_latency`); a number fixes it.
    """

    def __init__(
        self,
        *,
        linear_accel: float = 1.0,
        angular_accel: float = 3.0,
        latency: float | None = None,
        initial_latency: float = 0.2,
    ) -> None:
        self.linear_accel = linear_accel
        self.angular_accel = angular_accel
        self.fixed_latency = latency
        self._latencies: deque[float] = deque(maxlen=5)
        self._initial = initial_latency if latency is None else latency
        self._command = (0.0, 0.0, 0.0)
        self._trace: deque[_Point] = deque()
        self._samples: deque[Sample] = deque(maxlen=400)
        self._start: tuple[float, Sample] | None = None  # (first command from rest, rest pose)
        self._fitted: float | None = None  # the latest least-squares latency
        self._segment: Sample | None = None  # the odometry at rest before the last start
        self._moved = False  # the model moved since the last fit
        # The most the latency can be in this motion: from its first command to the first
        # sample that showed it (odometry cannot show motion before it happens).
        self._cap: float | None = None
        self._disturbed = False  # a stall was seen in this motion's odometry (`disturbed`)
        self._held: deque[Stall] = deque(maxlen=50)  # starts that came late (`held`)

    # -- inputs ------------------------------------------------------------------------

    def command(self, t: float, vx: float, vy: float, wz: float) -> None:
        """The robot was told to move at this body-frame velocity from time t (0 = stop)."""
        self._advance(t)
        moving = bool(vx or vy or wz)
        if moving and not self._model_moving():
            self._disturbed = False  # a new motion: its odometry may teach the latency
            at_rest = bool(self._samples) and _still(self.measured_velocity())
            self._segment = self._samples[-1] if at_rest else None  # the rest it starts from
            self._cap = None
            if at_rest and self.fixed_latency is None:
                self._start = (t, self._samples[-1])
        self._command = (vx, vy, wz)

    def odometry(self, t: float, x: float, y: float, yaw: float) -> None:
        """An odometry pose arrived at time t."""
        self._advance(t)
        sample = Sample(t, x, y, normalize_angle(yaw))
        self._samples.append(sample)
        if self.fixed_latency is not None:
            return
        if self._start is not None:
            self._measure_latency(sample)
        if self._model_moving():
            self._moved = True
        elif self._moved and _still(self.measured_velocity()):
            self._moved = False
            self._fit_latency()

    # -- outputs -----------------------------------------------------------------------

    @property
    def latency(self) -> float:
        """Seconds between the robot's motion and odometry showing it (command to pose)."""
        if self.fixed_latency is not None:
            return self.fixed_latency
        if self._fitted is not None:
            return self._fitted
        return statistics.median(self._latencies) if self._latencies else self._initial

    @property
    def latency_bound(self) -> float:
        """The most odometry may lag now: the latency once configured or measured, else
        `MAX_LATENCY` (a first start waits that long for odometry to show it)."""
        known = self.fixed_latency is not None or self._fitted is not None or self._latencies
        return self.latency if known else MAX_LATENCY

    @property
    def showing(self) -> bool:
        """Motion started from rest that odometry has not shown yet: until it does, where the
        robot is comes from the commands alone, and it may still be moving."""
        return self._start is not None and self._model_started()

    def last_sample(self) -> Sample | None:
        return self._samples[-1] if self._samples else None

    @property
    def commanding(self) -> bool:
        """Motion is commanded now (the last command was not a stop)."""
        return any(self._command)

    def idle_since(self, t: float) -> float:
        """Seconds since the model last moved (0 while it moves or is commanded)."""
        self._advance(t)
        for p in reversed(self._trace):
            if p.vx or p.vy or p.wz:
                return max(0.0, t - p.t)
        return math.inf if not any(self._command) else 0.0

    def model_motion(self, t0: float, t1: float) -> tuple[float, float]:
        """How far (metres, radians) the model moved between what odometry taken at t0 and at
        t1 should show: the trace between t0 and t1, both less the latency."""
        self._advance(t1)
        a = self._trace_at(t0 - self.latency)
        b = self._trace_at(t1 - self.latency)
        return math.hypot(b[0] - a[0], b[1] - a[1]), abs(b[2] - a[2])

    def held(self, since: float) -> tuple[Stall, ...]:
        """Starts from rest that odometry showed later than the latency says since `since`:
        the commands that began them were held up on the way (a loaded machine, a late link),
        from the first command until odometry's lateness says it acted."""
        return tuple(s for s in self._held if s.end >= since)

    def disturbed(self) -> None:
        """Odometry of the motion under way came in stalled (a loaded machine, a late link):
        its timing says more of the stall than of the latency, which it does not teach."""
        self._disturbed = True

    def restart(self) -> None:
        """Forget the odometry samples (not the latency): the next sample starts a new frame,
        as after a relocalization. What the model predicts from commands stays."""
        self._samples.clear()
        self._start = None
        self._segment = None
        self._moved = False

    def pose(self, t: float) -> tuple[float, float, float]:
        """The pose now: the last odometry pose plus the model's motion since it was taken.

        Once stopped, a robot that odometry never showed leaving its rest did not move: the
        model's motion was a ghost (commands ignored or lost), and the pose is odometry's."""
        self._advance(t)
        last = self._samples[-1] if self._samples else Sample(t, 0.0, 0.0, 0.0)
        if not any(self._command) and self._never_left_rest(last):
            return last.x, last.y, last.yaw
        # Odometry has not shown this start yet: all of the motion since is the commands'.
        start = self._start
        then = self._trace_at(start[0] if start and self.showing else last.t - self.latency)
        now = self._trace_at(t)
        return compose((last.x, last.y, last.yaw), relative(then, now))

    def velocity(self, t: float) -> tuple[float, float, float]:
        """Body-frame velocity: the model's or the odometry's, whichever is faster. It is zero
        only when the model has stopped and odometry shows the robot still."""
        self._advance(t)
        model = self._trace[-1] if self._trace else None
        modelled = (model.vx, model.vy, model.wz) if model else (0.0, 0.0, 0.0)
        if self.showing:  # the robot may still be moving as commanded: odometry cannot say
            modelled = max(
                ((p.vx, p.vy, p.wz) for p in self._trace if p.t >= self._start[0]),  # type: ignore[index]
                key=_speed,
                default=modelled,
            )
        measured = self.measured_velocity()
        return max(modelled, measured, key=_speed)

    def measured_velocity(self) -> tuple[float, float, float]:
        """Body-frame velocity from successive odometry poses over the last quarter second."""
        if len(self._samples) < 2:
            return (0.0, 0.0, 0.0)
        last = self._samples[-1]
        first = last
        for sample in reversed(self._samples):
            if last.t - sample.t > 2 * _STILL_WINDOW:
                break  # a gap in odometry: what happened across it is no velocity
            first = sample
            if last.t - sample.t >= _STILL_WINDOW:
                break
        # A burst after a pause (the driver stalled, then sent what it held) spans a few
        # milliseconds: a millimetre of noise across it would be a metre a second.
        span = max(last.t - first.t, _STILL_WINDOW / 2)
        dx, dy, dyaw = relative((first.x, first.y, first.yaw), (last.x, last.y, last.yaw))
        return dx / span, dy / span, dyaw / span

    def _never_left_rest(self, last: Sample) -> bool:
        rest = self._segment
        if rest is None:
            return False
        d = relative((rest.x, rest.y, rest.yaw), (last.x, last.y, last.yaw))
        return math.hypot(d[0], d[1]) < _MOTION_EPS and abs(d[2]) < _MOTION_EPS

    # -- model -------------------------------------------------------------------------

    def _model_started(self) -> bool:
        """The model has moved since the pending start (its first command may be a hair)."""
        assert self._start is not None
        started = self._start[0]
        return any(p.vx or p.vy or p.wz for p in reversed(self._trace) if p.t >= started)

    def _model_moving(self) -> bool:
        p = self._trace[-1] if self._trace else None
        return bool(any(self._command) or (p and (p.vx or p.vy or p.wz)))

    def _advance(self, t: float) -> None:
        """Integrate the model up to time t and forget history older than the trace keeps."""
        if not self._trace:
            self._trace.append(_Point(t, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
            return
        p = self._trace[-1]
        tx, ty, tw = self._command
        if not (tx or ty or tw or p.vx or p.vy or p.wz):
            if t > p.t:  # at rest: nothing to integrate, however long the pause
                self._trace.append(_Point(t, p.x, p.y, p.yaw, 0.0, 0.0, 0.0))
            p = self._trace[-1]
        while p.t < t:
            dt = min(_DT, t - p.t)
            vx = _approach(p.vx, tx, self.linear_accel * dt)
            vy = _approach(p.vy, ty, self.linear_accel * dt)
            wz = _approach(p.wz, tw, self.angular_accel * dt)
            mvx, mvy, mwz = (p.vx + vx) / 2, (p.vy + vy) / 2, (p.wz + wz) / 2
            mid = p.yaw + mwz * dt / 2
            c, s = math.cos(mid), math.sin(mid)
            p = _Point(
                p.t + dt,
                p.x + (mvx * c - mvy * s) * dt,
                p.y + (mvx * s + mvy * c) * dt,
                p.yaw + mwz * dt,
                vx,
                vy,
                wz,
            )  # yaw unwrapped inside the trace
            self._trace.append(p)
        while len(self._trace) > 2 and self._trace[1].t < t - _TRACE_SECONDS:
            self._trace.popleft()

    def _trace_at(self, t: float) -> tuple[float, float, float]:
        """The dead-reckoned pose at time t (clamped to the trace, interpolated)."""
        trace = self._trace
        if t <= trace[0].t:
            p = trace[0]
            return p.x, p.y, p.yaw
        if t >= trace[-1].t:
            p = trace[-1]
            return p.x, p.y, p.yaw
        i = bisect.bisect_left(trace, t, key=lambda q: q.t)
        a, b = trace[i - 1], trace[i]
        f = (t - a.t) / (b.t - a.t) if b.t > a.t else 1.0
        return a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.yaw + (b.yaw - a.yaw) * f

    def _measure_latency(self, sample: Sample) -> None:
        assert self._start is not None
        started, rest = self._start
        moved = relative((rest.x, rest.y, rest.yaw), (sample.x, sample.y, sample.yaw))
        if math.hypot(moved[0], moved[1]) < _MOTION_EPS and abs(moved[2]) < _MOTION_EPS:
            if sample.t - started > MAX_LATENCY + 1.0:
                self._start = None  # the robot did not move (ignored, or sitting): no measure
            return
        self._start = None
        if sample.t <= started:  # sent before the command: it was not at rest (odometry came
            return  # late, held up in a stalled process), so this start tells no latency
        self._cap = sample.t - started + self._sample_period()
        base = self._trace_at(started)
        shown = started
        for p in self._trace:  # when the model had moved as far as odometry can first show
            if p.t < started:
                continue
            d = relative(base, (p.x, p.y, p.yaw))
            shown = p.t
            if math.hypot(d[0], d[1]) >= _MOTION_EPS or abs(d[2]) >= _MOTION_EPS:
                break
        latency = sample.t - shown - self._sample_period() / 2
        late = latency - self.latency  # later than usual: its first commands were held up
        if late > max(_HELD, self._sample_period()) and not self._disturbed:  # (not its odometry)
            self._held.append(Stall(started - 1e-3, started + late))  # its first command on
        if not self._disturbed:
            self._latencies.append(min(MAX_LATENCY, max(0.0, latency)))

    def _fit_latency(self) -> None:
        """The delay that best lines odometry up with the trace over the motion that just
        ended (from the rest before it; at most the last few seconds). Kept only when it
        explains what odometry saw: commands the robot never obeyed (a dropped link) must not
        teach a delay."""
        segment, end = self._segment, self._samples[-1].t
        if segment is None or self._disturbed:
            return
        # The trace reaches back _FIT_SECONDS + MAX_LATENCY (it keeps _TRACE_SECONDS).
        recent = [s for s in self._samples if s.t >= max(segment.t, end - _FIT_SECONDS)]
        # Of samples that came in a burst only the last is as late as the latency: the ones
        # before it were held back on the link longer, yet arrived (and are timed) with it.
        window = [s for s, after in zip(recent, recent[1:], strict=False) if after.t - s.t > _BURST]
        window += recent[-1:]
        if len(window) < 5:
            return
        first = window[0]
        seen = [relative((first.x, first.y, first.yaw), (s.x, s.y, s.yaw)) for s in window]
        if max(math.hypot(d[0], d[1]) + abs(d[2]) for d in seen) < 10 * _MOTION_EPS:
            return  # too little motion to tell one delay from another

        def cost(latency: float) -> float:
            base = self._trace_at(first.t - latency)
            total = 0.0
            for s, d in zip(window, seen, strict=True):
                m = relative(base, self._trace_at(s.t - latency))
                total += (m[0] - d[0]) ** 2 + (m[1] - d[1]) ** 2 + (m[2] - d[2]) ** 2
            return total

        # Only delays this motion allows: a larger one would line odometry up with an earlier
        # motion of the model (a turn before this one), not with this.
        top = self._cap if self._cap is not None else 2 * self.latency + 0.5
        top = min(MAX_LATENCY, top)
        coarse = min((i * 0.05 for i in range(int(top / 0.05) + 1)), key=cost)
        fine = [coarse + i * 0.005 for i in range(-10, 11) if coarse + i * 0.005 >= 0]
        best = min(fine, key=cost)
        scale = sum(d[0] ** 2 + d[1] ** 2 + d[2] ** 2 for d in seen)
        if cost(best) <= 0.05 * scale:  # the model, so delayed, explains the odometry
            self._fitted = best

    def _sample_period(self) -> float:
        times = [s.t for s in self._samples]
        gaps = [b - a for a, b in zip(times[-21:], times[-20:], strict=False) if b > a]
        return statistics.median(gaps) if gaps else 0.0


def _speed(v: tuple[float, float, float]) -> float:
    return math.hypot(v[0], v[1]) + abs(v[2])


def _still(v: tuple[float, float, float]) -> bool:
    return math.hypot(v[0], v[1]) < 0.01 and abs(v[2]) < 0.02


def _approach(value: float, target: float, step: float) -> float:
    if value < target:
        return min(target, value + step)
    return max(target, value - step)
