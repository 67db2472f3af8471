"""Issue 8 behaviour through the agent: approvals, watchdog, checked outcomes, e-stop."""

from __future__ import annotations

import math
import threading
import time

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from shadowhound import (
    MissionStatus,
    Plan,
    RobotAgent,
    RobotAgentConfig,
    ShadowHoundConfig,
    SimRobot,
    SkillCall,
    default_registry,
)
from shadowhound import events as ev
from shadowhound.planning import FixedPlanner
from shadowhound.planning.parse import parse_reply
from shadowhound.skills import NoArgs, Skill
from shadowhound.state import Pose2D


def agent_with(robot=None, registry=None, **safety):
    settings = ShadowHoundConfig(safety=safety)
    robot = robot or SimRobot(time_scale=0.0)
    return RobotAgent(RobotAgentConfig(robot=robot, settings=settings, registry=registry)), robot


# -- approvals ----------------------------------------------------------------------------------


def approve_when_asked(agent, decision, after=0.05):
    def on_event(event):
        if event.kind == ev.APPROVAL_REQUIRED:
            request = event.data["request"]
            threading.Timer(after, lambda: decision(request)).start()

    agent.add_listener(on_event)


def test_risky_trick_runs_after_approval():
    agent, robot = agent_with()
    agent.enable_approvals()
    approve_when_asked(agent, lambda r: agent.approve(r["request_id"]))
    result = agent.execute_mission("do a backflip")
    assert result.success, result.response
    assert robot.counters["tricks"] == 1


def test_an_instant_answer_is_not_lost():
    agent, robot = agent_with(approval_timeout=5)
    agent.enable_approvals()
    agent.add_listener(lambda e: agent.approve() if e.kind == ev.APPROVAL_REQUIRED else None)
    assert agent.execute_mission("do a backflip").success


def test_rejection_and_time_out_refuse_without_moving():
    agent, robot = agent_with()  # the default time-out: the rejection comes well before it
    agent.enable_approvals()
    seen = []
    approve_when_asked(
        agent,
        lambda r: (
            seen.append(agent.pending_approval()) or agent.reject(r["mission_id"], "not indoors")
        ),
    )
    result = agent.execute_mission("do a backflip")
    assert not result.success and "rejected: not indoors" in result.response
    assert seen[0]["reasons"][0].startswith("step 1 (body.sport): backflip is a risky trick")
    agent2, robot2 = agent_with(approval_timeout=0.3)
    agent2.enable_approvals()
    result = agent2.execute_mission("do a backflip")
    assert "no approval within 0.3 s" in result.response
    assert robot.counters["tricks"] == robot2.counters["tricks"] == 0


def test_without_an_approver_risky_plans_are_refused():
    agent, robot = agent_with()
    result = agent.execute_mission("walk forward 1 meter and do a backflip")
    assert not result.success and "no interface that can ask a person" in result.response
    assert not robot.received_motion
    assert agent.get_diagnostics()["refusals"] == result.refusals


def test_require_approval_applies_to_every_plan():
    agent, robot = agent_with(require_approval=True)
    agent.enable_approvals()
    approve_when_asked(agent, lambda r: agent.approve())
    assert agent.execute_mission("walk forward 1 meter").success
    assert robot.get_state().x == pytest.approx(1.0, abs=0.003)


def test_estop_while_waiting_for_approval():
    agent, robot = agent_with()
    agent.enable_approvals()
    approve_when_asked(agent, lambda r: agent.estop())
    result = agent.execute_mission("do a front flip")
    assert result.status is MissionStatus.STOPPED and robot.counters["tricks"] == 0


# -- watchdog ---------------------------------------------------------------------------------


def hanging_skill() -> Skill:
    def run(ctx, _args):
        ctx.drive(0.3, 0.0, 0.0)
        ctx._cancelled.wait(30)  # a bug: blocks without ticking until the mission is stopped
        ctx.tick()
        return "done"

    return Skill("test.hang", "moves, then hangs", NoArgs, run, timeout=60, moves=False)


def test_watchdog_zeroes_velocity_of_a_hung_skill_and_stops_the_mission():
    """The skill hangs until its mission is stopped (30 s at most): the watchdog stops the
    robot first (after watchdog_timeout), then, the loop not back within watchdog_grace, the
    mission; however slow the machine, the order shows whose stops they were."""
    registry = default_registry()
    registry.register(hanging_skill())
    robot = SimRobot(time_scale=1.0)
    agent, _ = agent_with(robot, registry, watchdog_grace=0.5)
    stops = []
    real_stop = robot.stop

    def stop():
        stops.append("mission stopped" if agent._stop.cancelled.is_set() else "robot only")
        real_stop()

    robot.stop = stop
    result = agent.run_plan([SkillCall("test.hang")])
    assert result.status is MissionStatus.STOPPED
    assert "watchdog: no control tick" in result.response
    assert "safety.watchdog_grace" in result.response
    assert stops and stops[0] == "robot only", stops
    assert robot.get_state().vx == 0.0
    assert any("watchdog" in e for e in agent.get_diagnostics()["errors"])


class StallsOnce(SimRobot):
    """A simulated Go2 in real time whose control loop (the mission's thread) stalls once
    mid-walk, as on a loaded machine: the sleep goes on until the watchdog has stopped the
    robot (only the watchdog can meanwhile) and the robot has braked to rest."""

    def __init__(self, after: int = 0) -> None:
        super().__init__(time_scale=1.0)
        self.after = after  # moving ticks before the stall
        self.stopped = threading.Event()
        self.stalled = False
        self.speed_in_stall: float | None = None

    def stop(self) -> None:
        self.stopped.set()
        super().stop()

    def sleep(self, seconds: float) -> None:
        moving = self.get_state()
        if not self.stalled and (abs(moving.vx) > 0.2 or abs(moving.wz) > 0.2):
            self.after -= 1
        if not self.stalled and self.after < 0:
            self.stalled = True
            self.stopped.clear()
            assert self.stopped.wait(30), "the watchdog never stopped the robot"
            braking = time.monotonic() + 10  # the body brakes at its limit: till at rest
            while self.speed() > 0 and time.monotonic() < braking:
                time.sleep(0.01)
            self.speed_in_stall = self.speed()
        super().sleep(seconds)

    def speed(self) -> float:
        state = self.get_state()
        return abs(state.vx) + abs(state.vy) + abs(state.wz)


def test_a_control_loop_stalled_past_the_watchdog_goes_on_from_rest():
    """A stall (a loaded machine) is no hang: the watchdog stops the robot, the loop comes
    back within the grace and the walk goes on from rest, ending where it was asked in
    truth; the step says so. (Before issue 32 the mission stopped: the watchdog cried wolf.)"""
    robot = StallsOnce()
    agent, _ = agent_with(robot)
    start = robot.get_state()
    result = agent.execute_mission("walk forward 1 meter")
    assert robot.stalled and robot.speed_in_stall == 0.0
    assert result.success, result.response
    assert "stopped when its control loop stalled (the watchdog" in result.steps[0].output
    end = robot.get_state()
    tolerance = agent.settings.safety.outcome_tolerance
    assert math.hypot(end.x - start.x - 1.0, end.y - start.y) <= tolerance, (end, start)
    assert agent._watchdog is not None and agent._watchdog.trips == 1
    assert agent._watchdog.hangs == 0


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.sampled_from([("walk forward 0.8 meters", 0.8, 0.0), ("turn left 90 degrees", 0.0, 90.0)]),
    st.integers(0, 12),
)
def test_any_stall_of_the_control_loop_within_the_grace_ends_as_asked_in_truth(
    mission: tuple[str, float, float], after: int
) -> None:
    """The kind: wherever in a walk or a turn the control loop stalls past the watchdog (and
    comes back within the grace), the robot is stopped meanwhile and the step ends where it
    was asked, by the simulator's truth."""
    text, metres, degrees = mission
    robot = StallsOnce(after)
    agent, _ = agent_with(robot)
    start = robot.get_state()
    result = agent.execute_mission(text)
    trips = agent._watchdog.trips if agent._watchdog is not None else 0
    agent.cleanup()
    assert trips == 1
    assert robot.stalled and robot.speed_in_stall == 0.0
    assert result.success, result.response
    end = robot.get_state()
    lim = agent.settings.safety
    assert math.hypot(end.x - start.x - metres, end.y - start.y) <= lim.outcome_tolerance
    turned = math.degrees(end.yaw - start.yaw)
    assert abs(turned - degrees) <= lim.outcome_tolerance_deg, turned


def test_watchdog_leaves_healthy_real_time_missions_alone():
    agent, robot = agent_with(SimRobot(time_scale=1.0))
    result = agent.execute_mission("walk forward 0.3 meters")
    assert result.success, result.response
    watchdog = agent._watchdog
    assert watchdog is not None and watchdog._thread.is_alive()
    agent.cleanup()  # a long-lived process creating agents must not collect watchdog threads
    assert not watchdog._thread.is_alive()


# -- checked outcomes and acceleration caps -------------------------------------------------------


def test_a_step_that_claims_motion_that_never_happened_fails():
    registry = default_registry()
    registry.register(
        Skill(
            "test.fake_walk",
            "says it walked 1 m",
            NoArgs,
            lambda ctx, a: "walked 1 m",
            moves=True,
            predict=lambda p, a, env: [Pose2D(p.x + 1.0, p.y, p.yaw)],
        )
    )
    agent, robot = agent_with(registry=registry)
    result = agent.run_plan([SkillCall("test.fake_walk")])
    assert not result.success
    assert "outcome check failed: expected to end at (1.00, 0.00" in result.response


def test_velocity_commands_respect_acceleration_caps():
    agent, robot = agent_with(max_linear_accel=0.5)
    agent.execute_mission("walk forward 2 meters")
    speeds = [c.value[0] for c in robot.commands if c.kind == "velocity"]
    period = 1.0 / agent.settings.motion.control_rate_hz
    steps = [b - a for a, b in zip([0.0, *speeds], speeds, strict=False) if b != 0.0]
    assert max(steps) <= 0.5 * period + 1e-9
    assert robot.get_state().x == pytest.approx(2.0, abs=0.005)


# -- property tests: nothing outside the limits reaches the robot ------------------------------

LIMITS = {
    "max_linear_speed": 0.4,
    "max_angular_speed": 0.8,
    "geofence_radius": 3.0,
    "max_step_distance": 2.5,
}
numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=32),
    st.integers(-(10**6), 10**6),
    st.sampled_from(["1.5", "x", "", "-2", "1e9"]),
)
skill_names = st.sampled_from(default_registry().names + ["nav_move", "nav.fly", "", "body"])
arg_names = st.sampled_from(
    [
        "distance",
        "degrees",
        "x",
        "y",
        "speed",
        "seconds",
        "trick",
        "place",
        "laps",
        "heading_degrees",
        "bogus",
    ]
)
garbage_calls = st.builds(
    SkillCall,
    skill_names,
    st.dictionaries(
        arg_names,
        numbers | st.sampled_from(["kitchen", "start", "backflip", "hello", "garage"]),
        max_size=3,
    ),
)
metres, speeds = st.floats(-6, 6), st.none() | st.floats(0.05, 1.5)
well_formed_calls = st.one_of(
    st.builds(lambda d, v: SkillCall("nav.move", {"distance": d, "speed": v}), metres, speeds),
    st.builds(lambda d: SkillCall("nav.strafe", {"distance": d}), metres),
    st.builds(
        lambda a, v: SkillCall("nav.rotate", {"degrees": a, "speed": v}),
        st.floats(-720, 720),
        speeds,
    ),
    st.builds(lambda x, y: SkillCall("nav.goto", {"x": x, "y": y}), metres, metres),
    st.just(SkillCall("nav.patrol", {"laps": 1})),
    st.just(SkillCall("body.sit")),
)
calls = st.one_of(well_formed_calls, well_formed_calls, well_formed_calls, garbage_calls)


def assert_within_limits(robot, radius):
    for command in robot.commands:
        if command.kind == "velocity" and command.accepted:
            vx, vy, wz = command.value
            assert math.hypot(vx, vy) <= LIMITS["max_linear_speed"] + 1e-9
            assert abs(wz) <= LIMITS["max_angular_speed"] + 1e-9
    st_ = robot.get_state()
    assert math.hypot(st_.x, st_.y) <= radius + 0.05


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(calls, min_size=1, max_size=3))
def test_random_plans_never_exceed_limits_or_fence(plan):
    agent, robot = agent_with(**LIMITS)
    result = agent.run_plan(plan)
    event("moved" if robot.received_motion else "did not move")
    if not result.success and not result.steps:
        event("refused")
    assert_within_limits(robot, LIMITS["geofence_radius"])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.one_of(
        st.text(max_size=200),
        st.lists(
            st.fixed_dictionaries(
                {"skill": skill_names, "args": st.dictionaries(arg_names, numbers, max_size=3)}
            ),
            max_size=4,
        ).map(lambda steps: __import__("json").dumps({"steps": steps})),
    )
)
def test_random_model_answers_never_exceed_limits_or_fence(content):
    reply = parse_reply({"role": "assistant", "content": content})
    agent, robot = agent_with(**LIMITS)
    agent.config.planner = None
    agent._planner = FixedPlanner(Plan(reply.calls, text="model"))
    agent.execute_mission("model answer")
    assert_within_limits(robot, LIMITS["geofence_radius"])
