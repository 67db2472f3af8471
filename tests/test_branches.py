"""A branch ("if ... otherwise ...") is decided once, when its first step is reached: exactly one
of its ways runs, whatever the first way does to what the condition reads. Judged by the
simulator's truth (its state is its ground truth: no odometry error)."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.plan import SkillCall, Watch
from shadowhound.planning.parse import parse_reply
from shadowhound.result import StepStatus
from shadowhound.state import normalize_angle

TURNS = "if the red ball is visible, turn right 90 degrees, otherwise turn left 90 degrees"


def agent_on(robot: SimRobot) -> RobotAgent:
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=ShadowHoundConfig()))
    agent.initialize()
    return agent


def turned(robot: SimRobot, start: float) -> float:
    """Degrees the body really turned from `start` (left positive)."""
    return math.degrees(normalize_angle(robot.get_state().yaw - start))


@pytest.mark.parametrize(("facing", "expected"), [(0.0, -90.0), (math.pi, 90.0)])
def test_if_the_red_ball_is_visible_turn_right_otherwise_left_turns_one_way(
    facing: float, expected: float
) -> None:
    """Facing the ball it turns right and stays turned (the "otherwise" is not decided again
    after the turn hid the ball); facing away it turns left."""
    robot = SimRobot(time_scale=0.0)
    robot.reset(yaw=facing)
    visible = any(s.name == "red ball" for s in robot.in_view())
    assert visible == (facing == 0.0)  # the scene as the test means it
    agent = agent_on(robot)
    result = agent.execute_mission(TURNS)
    agent.cleanup()
    assert result.success, result.response
    assert turned(robot, facing) == pytest.approx(expected, abs=1.0), result.response
    ran = [s.status for s in result.steps]
    if visible:
        assert ran == [StepStatus.SUCCEEDED, StepStatus.SKIPPED]
        assert "decided when the branch began" in result.steps[1].output
    else:
        assert ran == [StepStatus.SKIPPED, StepStatus.SUCCEEDED]


def test_the_dry_run_says_one_way_runs() -> None:
    agent = agent_on(SimRobot(time_scale=0.0))
    result = agent.dry_run(TURNS)
    agent.cleanup()
    assert result.success, result.response
    assert "would run" not in result.response  # it does not claim both steps run
    assert (
        "one way runs, decided when step 1 is reached: step 1 if the red ball is visible, "
        "otherwise step 2" in result.response
    )


def test_each_repeat_of_a_branch_is_decided_when_it_is_reached() -> None:
    """ "..., then repeat that": the first time the ball is in view (turn right), the second
    time it is not (turn left): back where it began, each time one way."""
    robot = SimRobot(time_scale=0.0)
    agent = agent_on(robot)
    result = agent.execute_mission(TURNS + ", then repeat that")
    agent.cleanup()
    assert result.success, result.response
    assert [s.status for s in result.steps] == [
        StepStatus.SUCCEEDED,
        StepStatus.SKIPPED,
        StepStatus.SKIPPED,
        StepStatus.SUCCEEDED,
    ]
    assert turned(robot, 0.0) == pytest.approx(0.0, abs=1.0)


def test_a_models_if_and_otherwise_are_one_branch() -> None:
    """A model's conditions name no branch: its "if" and "otherwise" on the same condition,
    next to each other, are one."""
    reply = parse_reply(
        {
            "content": '{"steps": [{"skill": "nav.rotate", "args": {"degrees": -90}}, '
            '{"skill": "nav.rotate", "args": {"degrees": 90}}], "conditions": ['
            '{"step": 1, "when": "if", "kind": "seen", "name": "red ball"}, '
            '{"step": 2, "when": "if_not", "kind": "seen", "name": "red ball"}]}'
        }
    )
    assert [c.guard.branch for c in reply.calls if c.guard is not None] == [1, 1]
    robot = SimRobot(time_scale=0.0)
    agent = agent_on(robot)
    result = agent.run_plan(reply.calls, TURNS)
    agent.cleanup()
    assert result.success, result.response
    assert turned(robot, 0.0) == pytest.approx(-90.0, abs=1.0)


def test_a_named_branch_that_tests_two_conditions_is_refused() -> None:
    ball = Watch("if", "seen", "red ball", branch=1)
    battery = Watch("if_not", "battery_below", percent=30, branch=1)
    robot = SimRobot(time_scale=0.0)
    agent = agent_on(robot)
    result = agent.run_plan(
        [
            SkillCall("nav.rotate", {"degrees": -90}, guard=ball),
            SkillCall("nav.rotate", {"degrees": 90}, guard=battery),
        ]
    )
    agent.cleanup()
    assert not result.success and not robot.received_motion
    assert "steps 1 and 2 are one branch (1) but test different conditions" in result.response


def test_branches_group_unnamed_guards_by_condition_and_keep_named_ones() -> None:
    from shadowhound.plan import branches

    seen = Watch("if", "seen", "red ball")
    other = Watch("if_not", "seen", "red ball", words="otherwise")
    low = Watch("if", "battery_below", percent=20)
    named = Watch("if", "seen", "red ball", branch=7)
    guards = [seen, other, None, seen, low, named, other, None]
    assert branches(guards) == [8, 8, 0, 9, 10, 7, 11, 0]


ARM = st.lists(st.integers(-180, 180).filter(lambda d: abs(d) >= 5), min_size=1, max_size=3)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    facing=st.sampled_from([0.0, math.pi / 2, math.pi]),
    taken=ARM,
    otherwise=st.one_of(st.just([]), ARM),
    named=st.booleans(),
)
def test_exactly_one_way_of_a_branch_runs(
    facing: float, taken: list[int], otherwise: list[int], named: bool
) -> None:
    """Any truth of the condition at the branch's start, any turns in each way (turns that
    hide the ball or bring it into view included), the branch named or not: the steps of one
    way all run and the other's are all skipped, and the body turned exactly that way's
    turns, in truth."""
    robot = SimRobot(time_scale=0.0)
    robot.reset(yaw=facing)
    visible = any(s.name == "red ball" for s in robot.in_view())
    branch = 1 if named else 0
    calls = [
        SkillCall(
            "nav.rotate", {"degrees": d}, guard=Watch("if", "seen", "red ball", branch=branch)
        )
        for d in taken
    ] + [
        SkillCall(
            "nav.rotate", {"degrees": d}, guard=Watch("if_not", "seen", "red ball", branch=branch)
        )
        for d in otherwise
    ]
    agent = agent_on(robot)
    result = agent.run_plan(calls, "if the red ball is visible ..., otherwise ...")
    agent.cleanup()
    assert result.success, result.response
    ran = [s.status is StepStatus.SUCCEEDED for s in result.steps]
    skipped = [s.status is StepStatus.SKIPPED for s in result.steps]
    way = [True] * len(taken) + [False] * len(otherwise)
    assert ran == [w == visible for w in way], result.response
    assert skipped == [w != visible for w in way], result.response
    expected = sum(taken) if visible else sum(otherwise)
    assert abs(normalize_angle(math.radians(turned(robot, facing) - expected))) < math.radians(1)
