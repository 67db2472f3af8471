"""Limits that bind a mission as a whole hold in every planning mode (issue 12, defect 2).

A real `openai` client talks to a scripted model server on loopback; the robot is the
simulator, and every assertion reads its ground truth (its own odometer, true path, clock and
the tricks it performed), never the agent's account of what happened.
"""

from __future__ import annotations

import math
from collections import Counter

import pytest
from hypothesis import HealthCheck, event, given, note, settings
from hypothesis import strategies as st

from shadowhound import (
    RobotAgent,
    RobotAgentConfig,
    ShadowHoundConfig,
    SimRobot,
    SkillCall,
    default_registry,
    load_config,
)
from shadowhound import events as ev
from shadowhound.budget import MissionBudget
from shadowhound.robot.go2.api import TRICKS
from shadowhound.robot.sim.scene import World
from shadowhound.safety import Governor
from shadowhound.skills import NoArgs, PlanEnv, Skill
from tests.llm_server import Reply, ScriptedLLM, json_plan, model_settings, text, tool_calls
from tests.test_geofence import U_FENCE, orthogonal_polygons, ref_clearance

# How far the simulated body may end past a limit through control error alone: each motion
# stops within motion.position_tolerance (2 mm; a batch checked on predictions has at most 5
# steps here), and the body is never more than 1 cm from the last true-path point.
METRES_SLACK = 0.02
# Robot time a step can take beyond the mission's deadline: one posture command, which the robot
# does not interrupt (the longest, lying -> sitting, goes through standing: 1.5 s + 1.0 s), plus
# one control period (docs/safety.md: "within one control period, or one posture change").
SECONDS_SLACK = 2.6
RISKY = sorted(name for name, trick in TRICKS.items() if trick.risky)


@pytest.fixture
def srv():
    with ScriptedLLM(models=("test-model",)) as server:
        yield server


@pytest.fixture(scope="module")
def shared_srv():
    """One server for every example of a property test (each example clears its script)."""
    with ScriptedLLM(models=("test-model",)) as server:
        yield server


# The limits, not the furniture, are under test: the robot walks in an empty room.
EMPTY_ROOM = World(objects=())


def make_agent(srv, safety=None, **llm):
    settings = load_config(
        "llamacpp",
        {
            "llm": model_settings(srv, **llm),
            "safety": safety or {},
            "memory": {"enabled": False},
        },
        environ={},
    )
    robot = SimRobot(time_scale=0.0, world=EMPTY_ROOM)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    agent.initialize()
    return agent, robot


def move(distance):
    return {"skill": "nav.move", "args": {"distance": distance}}


def as_tool_calls(steps):
    return tool_calls(*[(s["skill"].replace(".", "_"), s["args"]) for s in steps])


# A step that fails when it runs (retrieval memory is off), so the planner is asked to re-plan.
FAILS = {"skill": "memory.note", "args": {"text": "the door is red"}}


# -- the defect, reproduced ----------------------------------------------------------------------


@pytest.mark.parametrize(("limit", "calls", "max_steps"), [(10, 8, 8), (None, 20, 20)])
def test_react_mission_distance_holds_across_steps(srv, limit, calls, max_steps):
    """8 calls of 4 m against a 10 m limit walked 32 m; 20 against the default 50 m, 80 m."""
    agent, robot = make_agent(
        srv,
        {"max_mission_distance": limit} if limit else {},
        mode="react",
        react_max_steps=max_steps,
    )
    limit = agent.settings.safety.max_mission_distance
    srv.script(
        *[tool_calls(("nav_move", {"distance": 4 if i % 2 == 0 else -4})) for i in range(calls)],
        text("I walked back and forth."),
    )
    result = agent.execute_mission("walk back and forth 4 metres, again and again")
    assert robot.true_odometer <= limit + METRES_SLACK
    assert robot.true_odometer > limit - 4  # it did walk until the limit stood in the way
    assert not result.success
    assert "safety.max_mission_distance" in result.response
    assert f"more than the limit of {limit:g} m" in result.refusals[0]
    tool_results = [m["content"] for m in srv.requests[-1]["messages"] if m["role"] == "tool"]
    assert "walked already" in tool_results[-1]  # the model is told why, and that it counts


@pytest.mark.parametrize("fmt", ["json_schema", "tools"])
def test_replan_is_checked_against_what_the_mission_already_walked(srv, fmt):
    agent, robot = make_agent(srv, {"max_mission_distance": 10}, plan_format=fmt)
    reply = json_plan if fmt == "json_schema" else as_tool_calls
    srv.script(reply([move(4), move(-4), FAILS]), reply([move(4)]))
    result = agent.execute_mission("walk 4 m and back, then note that the door is red")
    assert len(srv.requests) == 2  # it did re-plan
    assert robot.true_odometer <= 10 + METRES_SLACK
    assert robot.true_odometer == pytest.approx(8.0, abs=METRES_SLACK)
    assert not result.success
    assert "the new plan was refused" in result.response
    assert "12.0 m in all (8.0 m walked already)" in result.response


def test_react_mission_time_holds_across_steps(srv):
    agent, robot = make_agent(srv, {"max_mission_duration": 20}, mode="react")
    srv.script(*[tool_calls(("sys_wait", {"seconds": 6})) for _ in range(8)], text("waited"))
    t0 = robot.now()
    result = agent.execute_mission("wait 6 s eight times")
    assert robot.now() - t0 <= 20 + SECONDS_SLACK
    assert [s.status.value for s in result.steps[:4]] == ["succeeded"] * 3 + ["skipped"]
    assert "safety.max_mission_duration" in result.response


def test_a_step_that_runs_past_the_mission_time_is_stopped(srv):
    """Turns count as free in the plan check (a lower bound), so the robot's clock ends it."""
    agent, robot = make_agent(srv, {"max_mission_duration": 30})
    srv.script(json_plan([{"skill": "nav.rotate", "args": {"degrees": 3600}}]), json_plan([]))
    t0 = robot.now()
    result = agent.execute_mission("spin ten times")
    assert robot.now() - t0 <= 30 + SECONDS_SLACK
    assert not result.success and result.steps[0].status.value == "failed"
    assert "the mission's time is up" in result.steps[0].error
    assert "safety.max_mission_duration" in result.response


def test_mission_time_is_checked_before_anything_moves(srv):
    agent, robot = make_agent(srv, {"max_mission_duration": 100})
    srv.script(
        json_plan(
            [
                {"skill": "sys.wait", "args": {"seconds": 60}},
                move(1),
                {"skill": "sys.wait", "args": {"seconds": 60}},
            ]
        )
    )
    result = agent.execute_mission("wait a minute, step forward, wait a minute")
    assert not result.success and not robot.received_motion and robot.now() == 0.0
    assert "at least 122.0 s on the robot's clock, more than the limit of 100 s" in result.response


def test_react_honours_require_approval_for_every_step(srv):
    agent, robot = make_agent(srv, {"require_approval": True}, mode="react")
    srv.script(tool_calls(("nav_move", {"distance": 1})), text("I could not move."))
    result = agent.execute_mission("walk 1 m")  # nobody can approve: no interface attached
    assert not robot.received_motion and not result.success
    assert "safety.require_approval" in result.response


def test_an_approval_covers_the_call_shown_not_later_lookalikes(srv):
    agent, robot = make_agent(srv, mode="react")
    agent.enable_approvals()
    asked = []

    def approve_first_only(e):
        if e.kind == ev.APPROVAL_REQUIRED:
            asked.append(e.data["request"])
            (agent.approve if len(asked) == 1 else agent.reject)()

    agent.add_listener(approve_first_only)
    flip = ("body_sport", {"trick": "backflip"})
    srv.script(tool_calls(flip), tool_calls(flip), text("one flip"))
    result = agent.execute_mission("do two backflips")
    assert len(asked) == 2  # the second flip was asked about again
    assert [c.value for c in robot.commands if c.kind == "trick"] == ["backflip"]
    assert not result.success and "rejected" in result.response


def test_the_last_gate_refuses_a_risky_call_nobody_approved():
    """Whatever path a call takes to the robot, the step re-check wants this call approved."""
    settings = ShadowHoundConfig()
    robot = SimRobot(time_scale=0.0, world=EMPTY_ROOM)
    state = robot.get_state()
    env = PlanEnv(settings, state.pose, budget=MissionBudget.start(state, robot.now))
    governor, registry = Governor(settings.safety), default_registry()
    risky = registry.validate(SkillCall("body.sport", {"trick": "front_flip"}))
    assert "not approved: front_flip is a risky trick" in governor.check_step(risky, state, env)[0]
    env.budget.grant([risky])
    assert governor.check_step(risky, state, env) == []
    lookalike = registry.validate(SkillCall("body.sport", {"trick": "front_flip"}))
    assert governor.check_step(lookalike, state, env) != []
    # Checked on its own (no mission budget), a step is judged as before: approval is the plan's.
    assert governor.check_step(lookalike, state, PlanEnv(settings, state.pose)) == []


def test_a_skill_that_walks_further_than_it_predicts_is_stopped_at_the_mission_limit():
    """The plan check sees predictions; the control loop sees the odometer. A skill that
    predicts no path (or a real robot's detour) is stopped once the mission walked too far."""

    def wander(ctx, _args):
        while True:
            ctx.drive(0.4, 0.0, 0.0)
            ctx.tick()

    registry = default_registry()
    registry.register(Skill("test.wander", "walks on and on", NoArgs, wander, timeout=600))
    robot = SimRobot(time_scale=0.0, world=EMPTY_ROOM)
    settings = ShadowHoundConfig(safety={"max_mission_distance": 3, "geofence_radius": 100})
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings, registry=registry))
    result = agent.run_plan([SkillCall("test.wander")])
    assert not result.success
    assert "past the limit of 3 m (safety.max_mission_distance)" in result.response
    robot.sleep(2.0)  # let the body come to rest: braking from 0.4 m/s at 1 m/s^2 is 8 cm
    tick = 0.4 / settings.motion.control_rate_hz
    braking = 0.4**2 / (2 * robot.config.linear_accel)
    assert robot.true_odometer <= 3 + settings.safety.outcome_tolerance + tick + braking + 1e-6


# -- property tests: random plans and model replies against random limits and fences ------------

metres = st.one_of(st.floats(-2.5, 2.5), st.floats(-7, 7)).map(lambda v: round(v, 2))
walks = st.one_of(
    st.builds(lambda d: move(d), metres),
    st.builds(lambda x, y: {"skill": "nav.goto", "args": {"x": x, "y": y}}, metres, metres),
)
steps = st.one_of(
    walks,
    walks,
    walks,
    st.builds(lambda d: {"skill": "nav.strafe", "args": {"distance": d}}, metres),
    st.builds(
        lambda a: {"skill": "nav.rotate", "args": {"degrees": a}},
        st.sampled_from([-90, 45, 180, 720]),
    ),
    st.builds(lambda s: {"skill": "sys.wait", "args": {"seconds": s}}, st.sampled_from([1, 5, 20])),
    st.builds(
        lambda t: {"skill": "body.sport", "args": {"trick": t}},
        st.sampled_from(RISKY + ["hello", "stretch"]),
    ),
    st.sampled_from(
        [
            {"skill": "body.sit", "args": {}},
            {"skill": "body.lie_down", "args": {}},
            {"skill": "nav.patrol", "args": {"laps": 1}},
            FAILS,
            {"skill": "nav.fly", "args": {}},
        ]
    ),  # unknown: plan mode repairs it
)
plans = st.lists(steps, min_size=1, max_size=4)


@st.composite
def fences(draw):
    """A radius, and sometimes a polygon: convex around the origin, the U of issue 12 or a
    random orthogonal one with notches (the robot starts at the origin, inside or not)."""
    fence = {"geofence_radius": draw(st.sampled_from([2.0, 4.0, 6.0, 9.0, 12.0]))}
    kind = draw(st.sampled_from(["none", "convex", "u", "orthogonal"]))
    if kind == "convex":
        n, r = draw(st.integers(3, 7)), draw(st.floats(2.0, 8.0))
        turn = draw(st.floats(0, 2 * math.pi))
        fence["geofence_polygon"] = [
            (
                round(r * math.cos(turn + 2 * math.pi * k / n), 3),
                round(r * math.sin(turn + 2 * math.pi * k / n), 3),
            )
            for k in range(n)
        ]
    elif kind == "u":  # shifted so that the robot starts inside the left arm of the U
        fence["geofence_polygon"] = [(x - 0.5, y - 0.5) for x, y in U_FENCE]
        fence["geofence_margin"] = draw(st.sampled_from([0.0, 0.2]))
    elif kind == "orthogonal":
        fence["geofence_polygon"] = draw(orthogonal_polygons())
    return fence


limits = st.fixed_dictionaries(
    {
        "max_mission_distance": st.sampled_from([3.0, 6.0, 10.0, 20.0, 40.0]),
        "max_step_distance": st.sampled_from([1.5, 3.0, 6.0]),
        "max_mission_duration": st.sampled_from([10.0, 40.0, 120.0, 300.0]),
        "allow_risky_tricks": st.booleans(),
    }
)


def reply_for(plan, fmt):
    return json_plan(plan) if fmt == "json_schema" else as_tool_calls(plan)


def run_and_check(srv, script, limits_, fence, decisions, **llm):
    srv.clear()
    safety = {**limits_, **fence}
    agent, robot = make_agent(srv, safety, **llm)
    srv.script(*script)
    approved: Counter[str] = Counter()
    answers = iter(decisions)
    odometer_at: dict[int, float] = {}
    step_travel: list[tuple[str, float]] = []

    def on_event(e):
        if e.kind == ev.APPROVAL_REQUIRED:
            yes = next(answers, False)
            if yes:
                approved.update(
                    s["args"].get("trick")
                    for s in e.data["request"]["steps"]
                    if s["skill"] == "body.sport"
                )
            (agent.approve if yes else agent.reject)()
        elif e.kind == ev.STEP_STARTED:
            odometer_at[e.data["step"]["index"]] = robot.true_odometer
        elif e.kind == ev.STEP_FINISHED:
            step = e.data["step"]
            step_travel.append((step["skill"], robot.true_odometer - odometer_at[step["index"]]))

    if decisions:
        agent.enable_approvals()
    agent.add_listener(on_event)
    t0 = robot.now()
    result = agent.execute_mission("do as you are told")
    note(
        f"safety: {safety}\nsteps: {[s.to_dict() for s in result.steps]}\n"
        f"response: {result.response}"
    )
    event(f"{result.status.value}, moved" if robot.received_motion else result.status.value)
    if result.plan is not None and any("re-planned" in n for n in result.plan.notes):
        event("re-planned and ran the new plan")

    lim = agent.settings.safety
    assert robot.true_path_complete
    # The body: its centre keeps `geofence_margin` from every edge, or, when the robot started
    # closer than that (or outside), never comes closer to the edge than where it started.
    margin = lim.geofence_margin
    path = robot.true_path
    for _t, x, y in path:
        assert math.hypot(x, y) <= lim.geofence_radius - margin + METRES_SLACK, (x, y)
        if lim.geofence_polygon:
            start = min(margin, ref_clearance(path[0][1:], lim.geofence_polygon))
            clearance = ref_clearance((x, y), lim.geofence_polygon)
            assert clearance >= start - METRES_SLACK, (x, y, clearance)
    assert robot.true_odometer <= lim.max_mission_distance + METRES_SLACK
    for skill, walked in step_travel:
        legs = 4 if skill == "nav.patrol" else 1  # patrol: three route legs and the way back
        assert walked <= legs * lim.max_step_distance + METRES_SLACK, (skill, walked)
    assert robot.now() - t0 <= lim.max_mission_duration + SECONDS_SLACK
    performed = Counter(
        c.value
        for c in robot.commands
        if c.kind == "trick" and c.accepted and TRICKS[c.value].risky
    )
    if not lim.allow_risky_tricks:
        assert performed <= approved, (performed, approved)
    return result


MISSION_EXAMPLES = settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)


@MISSION_EXAMPLES
@given(
    plans,
    st.booleans(),
    st.booleans(),
    plans,
    st.sampled_from(["json_schema", "tools"]),
    limits,
    fences(),
    st.lists(st.booleans(), max_size=3),
)
def test_plan_mode_with_repairs_and_replans_never_exceeds_mission_limits(
    shared_srv, first, repair, fail, again, fmt, limits_, fence, decisions
):
    """A first reply to repair (an unknown skill) or not; a plan whose last step fails when
    it runs or not (then the model is asked to re-plan, and answers `again`)."""
    script = [reply_for([{"skill": "nav.fly", "args": {}}, *first], fmt)] if repair else []
    script += [reply_for([*first, FAILS] if fail else first, fmt), reply_for(again, fmt)]
    run_and_check(shared_srv, script, limits_, fence, decisions, plan_format=fmt)


@MISSION_EXAMPLES
@given(
    st.lists(st.tuples(plans, st.booleans()), min_size=1, max_size=8),
    limits,
    fences(),
    st.lists(st.booleans(), max_size=4),
)
def test_react_mode_never_exceeds_mission_limits(shared_srv, replies, limits_, fence, decisions):
    script: list[Reply] = [as_tool_calls(p) if tools else json_plan(p) for p, tools in replies]
    run_and_check(shared_srv, [*script, text("Done.")], limits_, fence, decisions, mode="react")
