"""The teleop limiter (issue 27): whatever the stick and wherever the robot, what it commands
keeps to the speed caps and can always brake before the geofence (with the body's margin) and
before anything on the map. Issue 32: it obeys the governor's rules as missions do, and a
request that arrives late (behind a newer one, the release included) never moves the robot.
The pad end to end, judged by the simulator's truth, is in tests/web/test_teleop_api.py and
tests/web/test_browser_teleop.py."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import ShadowHoundConfig
from shadowhound.plan import SkillCall
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.skills import PlanEnv
from shadowhound.skills.bounds import room_ahead
from shadowhound.state import Posture, RobotState
from shadowhound.teleop import MARGIN, Command, Teleop
from shadowhound.world import check_leg


class PlacedRobot(SimRobot):
    """The simulator's room and map, the robot reported at a chosen pose."""

    placed = RobotState()

    def last_state(self) -> RobotState:
        return self.placed


def agent_on(robot: SimRobot) -> RobotAgent:
    """A real agent (its governor, its skills) on `robot`; no memory on disk."""
    config = ShadowHoundConfig()
    config.memory.enabled = False
    return RobotAgent(RobotAgentConfig(robot=robot, settings=config))


ROBOT = PlacedRobot(time_scale=0)
PLACED = agent_on(ROBOT)
PLACED.settings.safety.geofence_radius = 4.0
unit = st.floats(-1.0, 1.0)
PERIOD = 1.0 / ShadowHoundConfig().motion.control_rate_hz


@settings(max_examples=400, deadline=None)
@given(
    x=st.floats(-4.5, 4.5),
    y=st.floats(-4.5, 4.5),
    yaw=st.floats(-math.pi, math.pi),
    stick=st.tuples(unit, unit, unit),
    before=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-1.0, 1.0)),
)
def test_whatever_the_stick_the_robot_can_brake_before_the_fence_and_the_map(
    x: float,
    y: float,
    yaw: float,
    stick: tuple[float, float, float],
    before: tuple[float, float, float],
) -> None:
    lim = PLACED.settings.safety
    ROBOT.placed = RobotState(x=x, y=y, yaw=yaw)
    teleop = Teleop(PLACED)
    teleop._sent = Command(*before)  # noqa: SLF001 (what it sent the tick before)
    command = teleop._limit(stick, PERIOD)  # noqa: SLF001
    speed = math.hypot(command.vx, command.vy)
    assert speed <= lim.max_linear_speed + 1e-9
    assert abs(command.wz) <= lim.max_angular_speed + 1e-9
    # Speeding up ramps at the acceleration caps; slowing down is at once.
    assert speed <= max(math.hypot(*before[:2]), 0) + lim.max_linear_accel * PERIOD + 1e-9
    if speed < 1e-9:
        return
    heading = yaw + math.atan2(command.vy, command.vx)
    braking = speed * speed / (2 * lim.max_linear_accel) + speed * PERIOD
    fence, _ = room_ahead(lim, ROBOT.placed.pose, heading, braking + 1.0)
    assert braking <= fence - MARGIN + 1e-6, (braking, fence)
    end = (x + (braking + 1e-3) * math.cos(heading), y + (braking + 1e-3) * math.sin(heading))
    belief = ROBOT.belief()
    assert belief is not None
    if belief.inflated.is_blocked(belief.grid.cell_of(x, y)):
        return  # it starts within an obstacle's clearance: check_leg's rule for leaving it holds
    leg = check_leg(belief, (x, y), end)
    assert leg.clear or leg.distance >= braking - 0.03, (leg, braking)  # a half cell's step


def test_off_it_takes_nothing_and_on_it_refuses_a_robot_that_is_not_standing() -> None:
    teleop = Teleop(PLACED)
    try:
        teleop.drive(1.0, 0.0, 0.0, seq=1)
    except RuntimeError as exc:
        assert "switch it on first" in str(exc)
    else:
        raise AssertionError("drove while off")
    sitting = SimRobot(time_scale=0)
    sitting.set_posture(Posture.SITTING)
    assert "stand it up first" in (Teleop(agent_on(sitting)).start() or "")
    latched = agent_on(SimRobot(time_scale=0))
    latched.estop()
    assert "e-stop is latched" in (Teleop(latched).start() or "")


# -- the governor's rules (issue 32) -------------------------------------------------------

PATTERNS = ["nav.*", "nav.move", "nav.strafe", "nav.rotate", "nav.r*", "body.*", "*", "sys.*"]


@settings(max_examples=150, deadline=None)
@given(
    deny=st.lists(st.sampled_from(PATTERNS), max_size=3),
    allow=st.none() | st.lists(st.sampled_from(PATTERNS), max_size=3),
    battery=st.floats(0.0, 100.0),
    floor=st.floats(0.0, 100.0),
    stick=st.tuples(unit, unit, unit).filter(lambda s: all(abs(v) > 0.05 for v in s)),
)
def test_the_pad_moves_an_axis_only_when_a_mission_step_of_its_skill_would_run(
    deny: list[str],
    allow: list[str] | None,
    battery: float,
    floor: float,
    stick: tuple[float, float, float],
) -> None:
    """Forward and back are nav.move, sideways nav.strafe, turning nav.rotate: an axis moves
    exactly when the governor would let a mission step of that skill run from here (the allow
    and deny lists, the battery floor), and switching on is refused when none would."""
    robot = SimRobot(time_scale=0)
    robot.set_battery(battery)
    agent = agent_on(robot)
    lim = agent.settings.safety
    lim.deny_skills, lim.allow_skills, lim.battery_floor = deny, allow, floor
    state, env = robot.get_state(), PlanEnv(agent.settings)
    steps = {"nav.move": {"distance": 0.5}, "nav.strafe": {"distance": 0.5}}
    runs = [
        not agent.governor.check_step(
            agent.registry.validate(SkillCall(name, steps.get(name, {"degrees": 30.0}))),
            state,
            env,
        )
        for name in ("nav.move", "nav.strafe", "nav.rotate")  # the pad's axes, in order
    ]
    teleop = Teleop(agent)
    refused = teleop.start(thread=False)
    if not any(runs):
        assert refused and "no motion may run" in refused
        return
    assert refused is None
    assert teleop.drive(*stick, seq=1) == ""
    assert teleop.tick(PERIOD)
    sent = teleop.last
    assert [sent.vx != 0.0, sent.vy != 0.0, sent.wz != 0.0] == runs, (sent, runs)
    teleop.stop()


def test_a_battery_that_falls_below_the_floor_while_driving_stops_the_walk() -> None:
    robot = SimRobot(time_scale=0)
    agent = agent_on(robot)
    teleop = Teleop(agent)
    assert teleop.start(thread=False) is None
    assert teleop.drive(0.0, 0.0, 0.0, seq=1) == ""
    robot.set_battery(5.0)
    teleop.drive(1.0, 0.0, 0.6, seq=2)
    for _ in range(20):
        assert teleop.tick(PERIOD)
        robot.sleep(PERIOD)
    assert robot.true_odometer == 0.0 and robot.get_state().yaw == 0.0  # truth: it stood
    assert "below the floor of 15%" in teleop.last.limited


# -- late requests (issue 32) ---------------------------------------------------------------


@st.composite
def a_drive(draw: st.DrawFn) -> tuple[list[tuple[int, tuple[float, float, float]]], list[int]]:
    """What a page sends (numbered 1.., the release last) and the order it arrives in."""
    sticks = draw(st.lists(st.tuples(unit, unit, unit), min_size=1, max_size=6))
    sent = [(i + 1, s) for i, s in enumerate(sticks)] + [(len(sticks) + 1, (0.0, 0.0, 0.0))]
    return sent, draw(st.permutations(range(len(sent))))


@settings(max_examples=120, deadline=None)
@given(page=a_drive(), ticks=st.lists(st.integers(0, 4), min_size=7, max_size=7))
def test_after_the_release_no_late_request_moves_the_robot(
    page: tuple[list[tuple[int, tuple[float, float, float]]], list[int]], ticks: list[int]
) -> None:
    """Whatever order the page's requests arrive in, and however many control ticks pass
    between them: once the release is taken, the robot is sent no motion and only slows
    (truth), to a standstill."""
    sent, order = page
    release = sent[-1][0]
    robot = SimRobot(time_scale=0)
    teleop = Teleop(agent_on(robot))
    assert teleop.start(thread=False) is None
    released_at: int | None = None  # commands the robot had when the release was taken
    speeds: list[tuple[float, float]] = []
    for i, n in enumerate(order):
        seq, stick = sent[n]
        teleop.drive(*stick, seq=seq)
        if seq == release:
            released_at = len(robot.commands)
        for _ in range(ticks[i] + (15 if i == len(order) - 1 else 0)):
            teleop.tick(PERIOD)
            robot.sleep(PERIOD)
            s = robot.get_state()
            if released_at is not None:
                speeds.append((math.hypot(s.vx, s.vy), abs(s.wz)))
    assert released_at is not None
    late = [
        c
        for c in robot.commands[released_at:]
        if c.kind == "velocity" and c.accepted and any(c.value)
    ]
    assert not late, late
    for (v0, w0), (v1, w1) in zip(speeds, speeds[1:], strict=False):
        assert v1 <= v0 + 1e-12 and w1 <= w0 + 1e-12  # only braking, never driven again
    assert robot.get_state().vx == robot.get_state().vy == robot.get_state().wz == 0.0
    teleop.stop()


def test_nobody_driving_switches_it_off() -> None:
    robot = SimRobot(time_scale=0)
    agent = agent_on(robot)
    agent.settings.teleop.idle_timeout = 0.2
    teleop = Teleop(agent)
    assert teleop.start(thread=False) is None
    assert teleop.drive(0.0, 0.0, 0.0, seq=1) == ""  # a zero is nobody driving
    while teleop.tick(PERIOD):
        robot.sleep(PERIOD)
    assert not teleop.on
    assert "nobody drove for 0.2 s (teleop.idle_timeout)" in teleop.ended
