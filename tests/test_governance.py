"""Issue 8 behaviour through the agent: approvals, watchdog, checked outcomes, e-stop."""

from __future__ import annotations

import math
import threading

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


def hanging_skill(woken: threading.Event) -> Skill:
    def run(ctx, _args):
        ctx.drive(0.3, 0.0, 0.0)
        woken.wait(30)  # a bug: blocks without ticking while the robot walks
        ctx.tick()
        return "done"

    return Skill("test.hang", "moves, then hangs", NoArgs, run, timeout=60, moves=False)


def test_watchdog_zeroes_velocity_of_a_hung_skill():
    """The skill hangs until the robot is stopped (30 s at most): only the watchdog can stop
    it meanwhile, so a stop before the skill woke is the watchdog's, however slow the machine."""
    woken = threading.Event()
    registry = default_registry()
    registry.register(hanging_skill(woken))
    robot = SimRobot(time_scale=1.0)
    agent, _ = agent_with(robot, registry)
    stops = []
    real_stop = robot.stop

    def stop():
        stops.append("the robot stopped while the skill hung" if not woken.is_set() else "after")
        real_stop()
        woken.set()

    robot.stop = stop
    result = agent.run_plan([SkillCall("test.hang")])
    assert result.status is MissionStatus.STOPPED
    assert "watchdog: no control tick" in result.response
    assert stops and stops[0] == "the robot stopped while the skill hung"
    assert robot.get_state().vx == 0.0
    assert any("watchdog" in e for e in agent.get_diagnostics()["errors"])


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
