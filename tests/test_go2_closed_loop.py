"""The motion skills on a robot whose odometry is late, as a Go2's is, judged by the truth.

`LateRobot` is a SimRobot (the truth, on its own virtual clock) seen only through odometry
samples that arrive `delay` seconds late at `rate` Hz, read through the Go2 robot's
OdometryIntake and MotionTracker: the closed loop gets what a Go2 on go2_ros2_sdk gives it, and
nothing more. Given `lies` (the sim-driver's fault messages, sim_faults.Faults) the samples
pass the sim-driver's LyingOdometry on the way, as over DDS; like the Go2 robot, it stops when
the intake finds a fault and `get_state` raises while odometry is not trusted.
Over DDS, tests/ros/test_go2_truth.py checks the same with the real driver and processes.
"""

from __future__ import annotations

import math
import random
from collections import deque
from collections.abc import Callable

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import ShadowHoundConfig
from shadowhound.errors import RobotError
from shadowhound.robot.base import Stall
from shadowhound.robot.go2.motion import GO2_MOTION, MotionTracker
from shadowhound.robot.go2.odometry import OdometryIntake
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.sim_driver.faults import Faults, LyingOdometry
from shadowhound.skills.bounds import leg_margin, turn_margin
from shadowhound.state import CameraFrame, Posture, RobotState, Sighting


class LateRobot:
    """The Robot protocol over a SimRobot whose pose is known only from late odometry."""

    name = "late-odometry"
    description = "simulated Go2 behind late odometry"

    def __init__(
        self,
        rate: float,
        delay: float,
        tracker: MotionTracker | None = None,
        sim: SimRobot | None = None,
        burst: int = 1,
        startup: Callable[[], float] | None = None,
    ) -> None:
        """`startup`: seconds a robot at rest takes to start walking once told to (its gait
        engaging), drawn per start; meanwhile the latest velocity waits, and a stop ends
        the wait."""
        self.sim = sim or SimRobot(time_scale=0)
        self.startup = startup
        self._starting: tuple[float, tuple[float, float, float]] | None = None  # (when, what)
        self.tricks = self.sim.tricks  # a simulated Go2: its tricks
        self.burst = burst  # samples that travel together: held back, then 1 ms apart
        self._group: list[tuple[tuple[float, float, float] | None, float]] = []
        self.tracker = tracker or MotionTracker()
        self.intake = OdometryIntake(self.tracker)
        self.lying = LyingOdometry()
        self.faults: list[str] = []  # what the intake found, in order
        self.truths: list[RobotState] = []  # the truth at each odometry sample's moment
        self.period, self.delay = 1.0 / rate, delay
        self._pending: deque[tuple[float, tuple[float, float, float] | None, float]] = deque()
        self._next = 0.0
        self._moving = False
        self.sleep(1.0 + delay + burst * self.period)  # odometry has come in, as a Go2 waits

    def lie(self, faults: Faults) -> None:
        """A fault message reaches the driver now (it fires as `faults` says)."""
        s = self.sim.get_state()
        self.lying.arm(faults, (s.x, s.y, s.yaw))

    def get_state(self) -> RobotState:
        now = self.sim.now()
        untrusted = self.intake.problem(now)
        if untrusted:
            raise RobotError(f"odometry is not trusted: {untrusted}")
        return self.last_state()

    def last_state(self) -> RobotState:
        now = self.sim.now()
        x, y, yaw = self.tracker.pose(now)
        vx, vy, wz = self.tracker.velocity(now)
        return RobotState(
            x=x,
            y=y,
            yaw=yaw,
            vx=vx,
            vy=vy,
            wz=wz,
            battery=None,
            posture=self.sim.get_state().posture,
            distance_travelled=self.intake.distance,
            angle_turned=self.intake.turned,
            time_moving=self.intake.moving,
            stamp=now,
        )

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        if not (vx or vy or wz):
            self.stop()
            return
        untrusted = self.intake.problem(self.sim.now())
        if untrusted:
            raise RobotError(f"odometry is not trusted: {untrusted}. Not moving.")
        self._walk(vx, vy, wz)
        self._moving = True
        walks = self.sim.get_state().posture is Posture.STANDING
        self.intake.command(self.sim.now(), *((vx, vy, wz) if walks else (0.0, 0.0, 0.0)))

    def _walk(self, vx: float, vy: float, wz: float) -> None:
        """Walk now, or once the robot has started (from rest, with a start-up time)."""
        if self.startup is None or (self._starting is None and self._moving):
            self.sim.send_velocity(vx, vy, wz)
            return
        when = self._starting[0] if self._starting else self.sim.now() + self.startup()
        self._starting = (when, (vx, vy, wz))

    def stop(self) -> None:
        self._starting = None
        self.sim.stop()
        self._moving = False
        self.intake.command(self.sim.now(), 0.0, 0.0, 0.0)

    def set_posture(self, posture: Posture) -> None:
        self.sim.set_posture(posture)

    def perform(self, trick: str) -> None:
        self.sim.perform(trick)

    def in_view(self) -> tuple[Sighting, ...]:
        return self.sim.in_view()  # its camera is not late: what the simulator shows now

    def now(self) -> float:
        return self.sim.now()

    def sleep(self, seconds: float) -> None:
        end = self.sim.now() + seconds
        while self.sim.now() < end - 1e-9:
            step = min(0.005, end - self.sim.now())
            if self._starting is not None:  # to the moment it starts walking
                step = max(1e-6, min(step, self._starting[0] - self.sim.now()))
            self.sim.sleep(step)
            now = self.sim.now()
            if self._starting is not None and self._starting[0] <= now + 1e-9:
                self.sim.send_velocity(*self._starting[1])
                self._starting = None
            while self._next <= now + 1e-9:
                s = self.sim.get_state()
                self.truths.append(s)
                fired = self.lying.fired
                shown, shift = self.lying.publish((s.x, s.y, s.yaw))
                if self.lying.fired and not fired and self.lying.faults.fall:
                    self.sim.stop()  # it falls where it is, and lies there
                    self.sim.set_posture(Posture.LYING, seconds=0.0)
                self._group.append((shown, shift))
                if len(self._group) == self.burst:  # the link delivers them together
                    arrival = self._next + self.delay
                    for i, (pose, late) in enumerate(self._group):
                        self._pending.append((arrival + 0.001 * i, pose, late))
                    self._group.clear()
                self._next += self.period
            while self._pending and self._pending[0][0] <= now + 1e-9:
                t, shown, shift = self._pending.popleft()
                x, y, yaw = shown if shown is not None else (math.nan,) * 3
                fault = self.intake.receive(t, t + shift, x, y, yaw)
                if fault is not None:
                    self.faults.append(fault.kind)
                    if self._moving:
                        self.stop()  # as the Go2 robot does

    def get_camera_frame(self) -> CameraFrame | None:
        return None

    def get_scan(self) -> None:
        return None

    def belief(self) -> None:
        return None

    @property
    def time_scale(self) -> float:  # its clock is the simulator's
        return self.sim.time_scale

    @property
    def realtime(self) -> bool:
        return self.sim.realtime

    def emergency_stop(self) -> None:
        self.sim.emergency_stop()
        self.tracker.command(self.sim.now(), 0.0, 0.0, 0.0)

    def release_estop(self) -> None:
        self.sim.release_estop()

    def watch_estop(self, listener: object) -> None:
        """No e-stop source of its own."""

    def look(self) -> None:
        self.sim.look()

    def say(self, text: str) -> None:
        self.sim.say(text)

    @property
    def latency(self) -> float:
        return self.tracker.latency_bound

    def stalls(self, since: float) -> tuple[Stall, ...]:
        return self.intake.stalls(since)

    def vocabulary(self) -> frozenset[str]:
        return self.sim.vocabulary()

    def bearings(self) -> tuple[()]:
        return ()

    def known_objects(self) -> tuple[()]:
        return ()

    def navigator(self) -> None:
        return None  # no Nav2: nav.goto walks the project's own path

    def close(self) -> None:
        self.sim.close()


@pytest.mark.parametrize(("rate", "delay"), [(20.0, 0.0), (20.0, 0.2), (10.0, 0.5)])
def test_walk_and_turn_end_on_target_in_truth_and_report_the_truth(
    rate: float, delay: float
) -> None:
    robot = LateRobot(rate, delay)
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    result = agent.execute_mission("walk forward 1 meter and turn left 90 degrees")
    assert result.success, result.response
    truth = robot.sim.get_state()
    assert math.hypot(truth.x - 1.0, truth.y) < 0.05, (truth.x, truth.y)
    assert abs(math.degrees(truth.yaw) - 90.0) < 3.0, math.degrees(truth.yaw)
    reported = result.robot
    assert math.hypot(reported.x - truth.x, reported.y - truth.y) < 0.05
    assert abs(math.degrees(math.remainder(reported.yaw - truth.yaw, math.tau))) < 3.0
    assert "battery level unknown" in result.response


def test_a_robot_without_a_battery_source_never_claims_a_level() -> None:
    agent = RobotAgent(RobotAgentConfig(robot=LateRobot(20.0, 0.2)))
    assert (
        agent.chat("how is your battery?")
        == "I cannot tell my battery level: this robot reports none."
    )
    assert agent.get_robot_status()["battery"] is None
    assert "battery unknown" in agent.execute_mission("report your status").response


def test_a_wrong_delay_is_corrected_at_rest_not_reported_as_done() -> None:
    """Odometry later than the robot believes (0.5 s, told 0.2 s, the first guess before any
    measure): the first approach stops off the goal, and a slow approach from rest, with its
    own stall clock, corrects it; the step is judged on the pose at rest."""
    robot = LateRobot(10.0, 0.5, tracker=MotionTracker(latency=0.2))
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    result = agent.execute_mission("walk forward 1 meter")
    assert result.success, result.response
    truth = robot.sim.get_state()
    assert math.hypot(truth.x - 1.0, truth.y) < 0.05, (truth.x, truth.y)


@pytest.mark.parametrize(("believed", "true"), [(0.4, 0.2), (0.0, 0.2), (0.1, 0.3), (0.5, 0.3)])
@pytest.mark.parametrize("mission", ["turn right 10 degrees", "turn left 90 degrees"])
def test_a_turn_on_a_wrong_latency_settles_instead_of_swinging(
    believed: float, true: float, mission: str
) -> None:
    """Odometry earlier or later than the robot believes (a latency measured under load, then
    the link changes): steering on the mispredicted pose swings about the goal (it used to swing
    +-5 degrees until the stall check failed a 10 degree turn). The approach stops at its second
    pass of the goal, judges at rest and comes back slowly."""
    robot = LateRobot(20.0, true, tracker=MotionTracker(latency=believed))
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    want = float(mission.split()[2]) * (-1 if "right" in mission else 1)
    result = agent.execute_mission(mission)
    assert result.success, result.response
    turned = math.degrees(robot.sim.get_state().yaw)
    assert abs(turned - want) < 3.0, turned


def test_the_late_odometry_robot_is_a_whole_robot() -> None:
    """Test robots implement the declared protocol too (the agent never probes for members)."""
    from shadowhound.robot.base import Robot

    assert isinstance(LateRobot(20.0, 0.2), Robot)


class JitteryRobot(LateRobot):
    """LateRobot over a link with jitter: some poses arrive up to `extra` seconds later than
    the rest, in order, each stamped when the driver sent it on a clock `clock_offset` seconds
    away from ours. The Go2 robot reads them as go2_ros.py does, through its OdometryIntake
    (a StampClock places them in time): jitter is never taken for a fault."""

    def __init__(
        self, rate: float, delay: float, extra: float, seed: int, clock_offset: float
    ) -> None:
        self.rng = random.Random(seed)
        self.extra, self.clock_offset = extra, clock_offset
        self._arrival = 0.0
        super().__init__(rate, delay)

    def sleep(self, seconds: float) -> None:
        end = self.sim.now() + seconds
        while self.sim.now() < end - 1e-9:
            step = min(0.005, end - self.sim.now())
            if self._starting is not None:  # to the moment it starts walking
                step = max(1e-6, min(step, self._starting[0] - self.sim.now()))
            self.sim.sleep(step)
            now = self.sim.now()
            if self._starting is not None and self._starting[0] <= now + 1e-9:
                self.sim.send_velocity(*self._starting[1])
                self._starting = None
            while self._next <= now + 1e-9:
                s = self.sim.get_state()
                sent = self._next + self.delay
                late = self.rng.uniform(0.0, self.extra) if self.rng.random() < 0.3 else 0.0
                self._arrival = max(self._arrival, sent + late)  # in order, as DDS keeps them
                self._pending.append((self._arrival, (s.x, s.y, s.yaw), sent))
                self._next += self.period
            while self._pending and self._pending[0][0] <= now + 1e-9:
                arrival, pose, sent = self._pending.popleft()
                assert self.intake.receive(arrival, sent + self.clock_offset, *pose) is None


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    extra=st.floats(0.05, 0.3),
    clock_offset=st.sampled_from([0.0, 1.7e9, 250.0]),
    turn=st.sampled_from([5, 15, 90]),
)
def test_odometry_jitter_does_not_throw_the_closed_loop_off_target(
    seed: int, extra: float, clock_offset: float, turn: int
) -> None:
    """Poses that arrive late by a random fraction of a second (a busy link or process) are
    placed in time by their stamps, so small and large turns and a walk still end on target
    in truth (found on CI: a 5 degree turn failed with "10 degrees to go" under load)."""
    robot = JitteryRobot(20.0, 0.2, extra, seed, clock_offset)
    config = ShadowHoundConfig(robot="go2")
    config.motion = config.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config))
    # The first motions teach the tracker the link's delay; the later ones steer on it.
    for mission, ahead, left in [
        ("walk forward 1 meter and turn left 90 degrees", 1.0, 90),
        (f"turn left {turn} degrees and walk forward 0.5 meters", 0.5, turn),
    ]:
        start = robot.sim.get_state()
        result = agent.execute_mission(mission)
        assert result.success, (mission, result.response)
        truth = robot.sim.get_state()
        turned = math.degrees(math.remainder(truth.yaw - start.yaw, math.tau))
        assert abs(turned - left) < 3.0, (mission, turned)
        # Walk first then turn, or turn first then walk: the goal is where the walk ends.
        heading = start.yaw + (math.radians(left) if mission.startswith("turn") else 0.0)
        goal = (start.x + ahead * math.cos(heading), start.y + ahead * math.sin(heading))
        assert math.hypot(truth.x - goal[0], truth.y - goal[1]) < 0.05, (mission, truth, goal)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    delay=st.floats(0.0, 3.2),
    burst=st.integers(1, 3),
    rate=st.sampled_from([17.0, 20.0]),
)
def test_odometry_seconds_late_in_bursts_still_ends_on_target(
    delay: float, burst: int, rate: float
) -> None:
    """go2_ros2_sdk #231: odometry 2-3 s late, several samples back to back then a gap, each
    stamped when sent. Slower, never wrong: the mission ends on target in truth."""
    robot = LateRobot(rate, delay, burst=burst)
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    result = agent.execute_mission("walk forward 1 meter and turn left 90 degrees")
    truth = robot.sim.get_state()
    assert result.success, result.response
    assert math.hypot(truth.x - 1.0, truth.y) < 0.05, (truth.x, truth.y)
    assert abs(math.degrees(truth.yaw) - 90.0) < 3.0, math.degrees(truth.yaw)
    assert robot.faults == []  # late is not lying: no fault was taken for it


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    slowest=st.sampled_from([0.05, 0.1, 0.15]),
    mission=st.sampled_from(["turn left", "turn right", "walk forward", "walk backward"]),
    amount=st.floats(0.0, 1.0),
)
def test_a_robot_slow_to_start_walking_still_succeeds_in_truth(
    seed: int, slowest: float, mission: str, amount: float
) -> None:
    """Each time it starts from rest the robot takes a moment (up to `slowest` seconds, a
    different one each start: its gait engaging, a command late on the link) before it
    moves, so its commands go further than it did; odometry is honest. That is no odometry
    that disagrees with the motion: every turn and walk succeeds, ends within the step's
    outcome tolerance in truth, and never goes beyond the step's margin (found on CI: a 90
    degree turn on the Go2 sim-driver, with its camera and detector busy, failed with its
    commands at 95 degrees against odometry's 90)."""
    rng = random.Random(seed)
    robot = LateRobot(20.0, 0.2, startup=lambda: rng.uniform(0.0, slowest))
    config = ShadowHoundConfig(robot="go2")
    config.motion = config.motion.model_copy(update=GO2_MOTION)
    config.memory.enabled = False
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config))
    lim = config.safety
    turning = mission.startswith("turn")
    size = round(30 + 150 * amount) if turning else round(0.3 + 1.7 * amount, 2)
    start = robot.sim.get_state()
    robot.truths.clear()
    result = agent.execute_mission(f"{mission} {size} {'degrees' if turning else 'meters'}")
    robot.sleep(2.0)  # whatever the robot still does after the mission, the truth shows
    assert result.success, (slowest, result.response)
    end = robot.sim.get_state()
    sign = -1.0 if mission.endswith(("right", "backward")) else 1.0
    if turning:
        turned = [math.degrees(t.yaw - start.yaw) * sign % 360.0 for t in robot.truths]
        last = math.degrees(end.yaw - start.yaw) * sign % 360.0
        assert abs(last - size) <= lim.outcome_tolerance_deg, (last, result.response)
        beyond = math.degrees(turn_margin(lim, math.radians(size)))
        assert max(t for t in turned if t < 270.0) <= size + beyond, result.response
    else:
        ahead = [(t.x - start.x) * sign for t in robot.truths]
        off = math.hypot(end.x - start.x - sign * size, end.y - start.y)
        assert off <= lim.outcome_tolerance, (off, result.response)
        assert max(ahead) <= size + leg_margin(lim, size), result.response
