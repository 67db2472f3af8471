"""MotionTracker: the Go2's pose now from late odometry. The truth is a SimRobot (on its own
virtual clock) whose poses reach the tracker through a delay line, as the driver's do."""

from __future__ import annotations

import math
from collections import deque

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.robot.go2.motion import MotionTracker, compose, relative
from shadowhound.robot.go2.stamps import StampClock
from shadowhound.robot.sim.robot import SimRobot


class DelayedOdometry:
    """A SimRobot seen through odometry at `rate` Hz that arrives `delay` seconds late."""

    def __init__(self, tracker: MotionTracker, rate: float, delay: float) -> None:
        self.sim = SimRobot(time_scale=0)
        self.tracker, self.period, self.delay = tracker, 1.0 / rate, delay
        self.pending: deque[tuple[float, tuple[float, float, float]]] = deque()
        self.next_sample = 0.0

    def command(self, vx: float, vy: float, wz: float) -> None:
        self.sim.send_velocity(vx, vy, wz)
        self.tracker.command(self.sim.now(), vx, vy, wz)

    def run(self, seconds: float, step: float = 0.005) -> None:
        end = self.sim.now() + seconds
        while self.sim.now() < end - 1e-9:
            self.sim.sleep(step)
            now = self.sim.now()
            while self.next_sample <= now + 1e-9:
                s = self.sim.get_state()
                self.pending.append((self.next_sample + self.delay, (s.x, s.y, s.yaw)))
                self.next_sample += self.period
            while self.pending and self.pending[0][0] <= now + 1e-9:
                t, pose = self.pending.popleft()
                self.tracker.odometry(t, *pose)

    def error(self) -> tuple[float, float]:
        """Metres and radians between the tracker's pose and the truth, now."""
        s = self.sim.get_state()
        x, y, yaw = self.tracker.pose(self.sim.now())
        return math.hypot(x - s.x, y - s.y), abs(math.remainder(yaw - s.yaw, 2 * math.pi))


def test_pose_math_round_trips() -> None:
    a, b = (1.0, 2.0, 0.5), (-0.3, 4.0, -2.9)
    back = compose(a, relative(a, b))
    assert all(math.isclose(u, v, abs_tol=1e-9) for u, v in zip(back, b, strict=True))


@settings(max_examples=25, deadline=None)
@given(
    delay=st.floats(0.0, 0.6),
    rate=st.sampled_from([10.0, 20.0, 50.0]),
    vx=st.floats(-0.6, 0.6),
    wz=st.floats(-1.0, 1.0),
)
def test_latency_is_measured_and_the_pose_predicted_while_moving(
    delay: float, rate: float, vx: float, wz: float
) -> None:
    tracker = MotionTracker(linear_accel=1.0, angular_accel=3.0)
    robot = DelayedOdometry(tracker, rate, delay)
    robot.run(1.0)
    if abs(vx) < 0.05 and abs(wz) <= 0.1:  # as the last check reads "turning": |wz| > 0.1
        vx = 0.3
    robot.command(vx, 0.0, wz)
    robot.run(1.5)
    assert abs(tracker.latency - delay) <= 1.0 / rate / 2 + 0.02
    # Moving: the prediction is as good as the latency measure (half a sample period).
    metres, radians = robot.error()
    assert metres < 0.6 * (1.0 / rate) + 0.005 and radians < 1.0 * (1.0 / rate) + 0.005
    assert math.hypot(*tracker.velocity(robot.sim.now())[:2]) > 0.01 or abs(wz) > 0.1


def test_velocity_is_zero_only_once_odometry_shows_the_robot_still() -> None:
    tracker = MotionTracker()
    robot = DelayedOdometry(tracker, 10.0, 0.5)
    robot.run(0.5)
    robot.command(0.4, 0.0, 0.0)
    robot.run(2.0)
    robot.command(0.0, 0.0, 0.0)  # StopMove
    robot.run(0.6)  # the robot has stopped (0.4 s of braking), odometry not yet
    assert not robot.sim.get_state().is_moving
    assert tracker.velocity(robot.sim.now())[0] > 0.05
    robot.run(0.8)
    assert tracker.velocity(robot.sim.now()) == (0.0, 0.0, 0.0)
    # Settled: the pose is odometry's own, and it is the truth.
    last = tracker.last_sample()
    assert last is not None and tracker.pose(robot.sim.now()) == (last.x, last.y, last.yaw)
    assert robot.error()[0] < 1e-9


def test_a_fixed_latency_is_used_as_given() -> None:
    tracker = MotionTracker(latency=0.3)
    robot = DelayedOdometry(tracker, 20.0, 0.1)
    robot.run(0.5)
    robot.command(0.4, 0.0, 0.0)
    robot.run(1.0)
    assert tracker.latency == 0.3


def test_a_robot_that_ignores_commands_is_not_predicted_far() -> None:
    """Prediction covers only the latency window: a dead link shows up as no progress."""
    tracker = MotionTracker(latency=0.3)
    tracker.odometry(0.0, 0.0, 0.0, 0.0)
    tracker.command(0.0, 0.5, 0.0, 0.0)
    for i in range(1, 50):
        tracker.odometry(i * 0.1, 0.0, 0.0, 0.0)  # odometry says: not moving at all
    x, _, _ = tracker.pose(5.0)
    assert x <= 0.5 * (0.3 + 0.1) + 1e-6  # latency plus the time since the last sample


def test_the_delay_is_fitted_once_odometry_shows_the_robot_still_again() -> None:
    """A creeping start fools the first guess; the fit over the stop gets the delay right."""
    tracker = MotionTracker()
    robot = DelayedOdometry(tracker, 10.0, 0.8)
    robot.run(1.5)
    robot.command(0.004, 0.0, 0.0)  # slower than odometry can call moving
    robot.run(2.0)
    robot.command(0.4, 0.0, 0.3)
    robot.run(2.0)
    robot.command(0.0, 0.0, 0.0)
    robot.run(2.0)
    assert abs(tracker.latency - 0.8) <= 0.01
    assert robot.error()[0] < 1e-6


def test_commands_the_robot_never_obeyed_teach_no_delay() -> None:
    """A dropped link: the model moved, odometry did not. The delay measured before stays."""
    tracker = MotionTracker()
    robot = DelayedOdometry(tracker, 20.0, 0.3)
    robot.run(1.0)
    robot.command(0.4, 0.0, 0.0)
    robot.run(1.5)
    robot.command(0.0, 0.0, 0.0)
    robot.run(1.5)
    assert abs(tracker.latency - 0.3) <= 0.01
    robot.sim.emergency_stop()  # from now on the robot ignores every velocity command
    robot.command(0.4, 0.0, 0.3)
    robot.run(3.0)
    robot.command(0.0, 0.0, 0.0)
    robot.run(1.5)
    robot.sim.release_estop()
    robot.command(0.0, 0.0, -0.3)  # a turn the robot obeys, right after the ignored walk
    robot.run(1.0)
    robot.command(0.0, 0.0, 0.0)
    robot.run(1.5)
    assert abs(tracker.latency - 0.3) <= 0.01


def test_a_robot_that_never_left_its_rest_is_where_odometry_says_once_stopped() -> None:
    """Commands lost on the way (a dropped link): the model walked, the robot did not. Once
    stopped, the pose is odometry's at once, not odometry plus a ghost of the model's walk
    (the next step would start from a pose the robot never had)."""
    tracker = MotionTracker(latency=0.5)
    for i in range(10):
        tracker.odometry(i * 0.1, 2.0, 1.0, 0.5)
    tracker.command(1.0, 0.4, 0.0, 0.0)
    for i in range(11, 30):
        tracker.odometry(i * 0.1, 2.0, 1.0, 0.5)  # odometry: the robot stays put
    tracker.command(3.0, 0.0, 0.0, 0.0)  # the stall is detected: stop
    assert tracker.pose(3.01) == (2.0, 1.0, 0.5)


def test_a_gap_in_odometry_is_no_velocity() -> None:
    """Odometry stopped for seconds while the robot moved, then came back: the jump across
    the gap is not a speed the robot has now."""
    tracker = MotionTracker(latency=0.2)
    tracker.odometry(0.0, 0.0, 0.0, 0.0)
    tracker.odometry(0.05, 0.0, 0.0, 0.0)
    tracker.odometry(3.0, 0.5, 0.0, 0.0)  # back after 3 s, half a metre further
    tracker.odometry(3.05, 0.5, 0.0, 0.0)
    assert tracker.measured_velocity() == (0.0, 0.0, 0.0)
    assert tracker.velocity(3.06) == (0.0, 0.0, 0.0)


# -- StampClock: when a pose was sent, on our clock ---------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    offset=st.floats(-50.0, 2e9),
    base=st.floats(0.01, 0.5),
    lates=st.lists(st.floats(0.0, 0.4), min_size=5, max_size=60),
)
def test_stamp_clock_removes_the_jitter_of_arrival_whatever_the_clocks(
    offset: float, base: float, lates: list[float]
) -> None:
    """Poses sent every 50 ms arrive `base` + a random lateness later, on a sender clock
    `offset` away from ours: once the fastest one has arrived, each maps to its send time plus
    the steady delay, so the jitter is gone; times never go backwards."""
    clock = StampClock()
    lates = [0.0, *lates]  # the first crosses as fast as the link can
    out, arrival = [], 0.0
    for i, late in enumerate(lates):
        sent = 100.0 + 0.05 * i
        arrival = max(arrival, sent + base + late)  # in order
        out.append(clock.local_time(sent + offset, arrival))
    for i, t in enumerate(out):
        assert t == pytest.approx(100.0 + 0.05 * i + base, abs=1e-3)
    assert out == sorted(out)


def test_stamp_clock_without_stamps_uses_arrival_and_starts_over_when_the_sender_jumps() -> None:
    clock = StampClock()
    assert clock.local_time(0.0, 5.0) == 5.0  # no stamp: arrival
    assert clock.local_time(1000.0, 5.1) == pytest.approx(5.1)
    assert clock.local_time(1000.05, 5.3) == pytest.approx(5.15)  # 0.15 s late: placed right
    # The sender's clock is set an hour ahead: the old offset is forgotten, not applied.
    assert clock.local_time(4600.0, 5.4) == pytest.approx(5.4)
    assert clock.local_time(4600.05, 5.6) == pytest.approx(5.45)
    assert clock.local_time(0.0, 5.5) == pytest.approx(5.5)  # never backwards


def test_a_pose_sent_before_the_command_teaches_no_latency_and_breaks_nothing() -> None:
    """ShadowHound's process stalled: the last pose it had showed the robot still, but the ones
    held in its queue, sent before the next command, show the robot still moving. The first of
    them, read as the start of the new motion, made the latency negative and the fit at rest
    raised ValueError in the ROS callback (seen on a loaded machine)."""
    tracker = MotionTracker()
    t = 0.0
    for _ in range(40):  # at rest
        t += 0.05
        tracker.odometry(t, 0.0, 0.0, 0.0)
    tracker.command(t + 0.3, 0.3, 0.0, 0.0)  # it looked at rest: a start
    for i in range(1, 4):  # held in the queue, sent before the command: still coasting
        tracker.odometry(t + 0.05 * i, 0.002 * i, 0.0, 0.0)
    t += 0.3
    x = 0.006
    for _ in range(40):  # the new motion, then a stop and rest: the fit runs
        t += 0.05
        x += 0.3 * 0.05
        tracker.odometry(t, x, 0.0, 0.0)
    tracker.command(t, 0.0, 0.0, 0.0)
    for _ in range(40):
        t += 0.05
        tracker.odometry(t, x, 0.0, 0.0)
    assert 0.0 <= tracker.latency < 1.0, tracker.latency


def test_a_motion_whose_odometry_came_in_stalled_teaches_no_latency() -> None:
    """The tracker keeps its latency when told the motion's odometry came in stalled."""
    tracker = MotionTracker(initial_latency=0.2)
    odometry = DelayedOdometry(tracker, 20.0, 0.2)
    odometry.run(0.5)
    odometry.command(0.3, 0.0, 0.0)
    tracker.disturbed()
    odometry.run(1.0)
    odometry.command(0.0, 0.0, 0.0)
    odometry.run(2.0)
    assert tracker.latency == 0.2
