"""The MCP desk shares the one mission worker with the other interfaces of its process: while
any interface's mission runs, an MCP mission or skill call is refused as busy, never queued."""

from __future__ import annotations

import math
import threading

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.checking import check_plan
from shadowhound.mcp.desk import BUSY, McpDesk, ToolInputError
from shadowhound.plan import Plan, SkillCall
from shadowhound.skills import PlanEnv
from shadowhound.skills.context import robot_belief
from shadowhound.worker import MissionJob, MissionWorker


def test_a_mission_from_another_interface_makes_mcp_busy():
    settings = ShadowHoundConfig()
    agent = RobotAgent(
        RobotAgentConfig(robot=SimRobot(settings.sim, time_scale=1.0), settings=settings)
    )
    agent.initialize()
    worker = MissionWorker(agent)  # e.g. the ROS node's
    desk = McpDesk(agent, worker=worker)
    # The ROS node's mission is held at its start until the MCP calls have been refused: it is
    # running then whatever the machine's speed (a short walk could otherwise end first).
    started, refused_both = threading.Event(), threading.Event()

    def hold(job: MissionJob) -> None:
        if job.source == "topic":
            started.set()
            assert refused_both.wait(60), "the MCP calls never came"

    worker.on("started", hold)
    try:
        ros_job = MissionJob("walk forward 0.3 meters", source="topic")
        assert worker.submit(ros_job) is None
        assert started.wait(60)
        with pytest.raises(ToolInputError) as refused:
            desk.start_mission("turn left 90 degrees")
        assert str(refused.value) == BUSY
        with pytest.raises(ToolInputError, match="^busy:"):
            desk.start_skill("nav_rotate", {"degrees": 90})
        refused_both.set()
        assert ros_job.done.wait(60) and ros_job.result is not None
        assert ros_job.result.success
        mcp_job = desk.start_skill("nav_rotate", {"degrees": 90})
        assert mcp_job.done.wait(60) and mcp_job.result is not None
        assert [s.skill for s in mcp_job.result.steps] == ["nav.rotate"]
        assert [r.mission for r in agent.history] == [
            "walk forward 0.3 meters",
            "nav.rotate(degrees=90.0)",
        ]
    finally:
        refused_both.set()
        desk.close()
        worker.stop()
        agent.cleanup()


# A skill tool call is a one-step plan: it runs exactly when checking that plan (validation,
# then the governor, with a person who says no) finds nothing against it, and a refused one
# never moves the robot. (A call that runs may still fail on the robot: a speed of 1e-300 m/s
# passes the checks and is then stopped by the no-progress watchdog.)
finite = st.floats(-50, 50, allow_nan=False)
calls = st.one_of(
    st.builds(lambda d: ("nav_move", {"distance": d}), st.one_of(finite, st.just(math.nan))),
    st.builds(
        lambda d, s: ("nav_move", {"distance": d, "speed": s}),
        finite,
        st.floats(-1, 5, allow_nan=False),
    ),
    st.builds(lambda d: ("nav_strafe", {"distance": d}), finite),
    st.builds(lambda a: ("nav_rotate", {"degrees": a}), st.floats(-720, 720)),
    st.builds(lambda x, y: ("nav_goto", {"x": x, "y": y}), finite, finite),
    st.builds(
        lambda t: ("body_sport", {"trick": t}),
        st.sampled_from(["hello", "front_flip", "backflip", "flop"]),
    ),
    st.builds(lambda s: ("sys_wait", {"seconds": s}), st.floats(-1, 400, allow_nan=False)),
)


@settings(max_examples=60, deadline=None)
@given(call=calls)
def test_a_skill_tool_runs_exactly_when_its_one_step_plan_passes_the_checks(call):
    tool, args = call
    config = ShadowHoundConfig(safety={"approval_timeout": 0.05})  # nobody answers: a no
    agent = RobotAgent(
        RobotAgentConfig(robot=SimRobot(config.sim, time_scale=0.0), settings=config)
    )
    agent.initialize()
    desk = McpDesk(agent)
    try:
        start = agent.get_robot_state()
        plan = Plan([SkillCall(tool, dict(args))], text="oracle", planner="explicit")
        env = PlanEnv(config, start.pose, belief=robot_belief(agent.robot))  # the map, too
        checked = check_plan(plan, agent.registry, agent.governor, config, env, start)
        allowed = not checked.problems and not checked.approvals
        try:
            job = desk.start_skill(tool, args)
        except ToolInputError:
            assert not allowed  # refused at the door: only calls that fail validation
            assert agent.get_robot_state().pose == start.pose
            return
        assert job.done.wait(60) and job.result is not None
        ran = job.result.steps[0].status.value != "skipped"
        assert ran == allowed, (job.result.response, checked)
        assert bool(job.result.refusals) == (not allowed)
        if not allowed:
            assert agent.get_robot_state().pose == start.pose
    finally:
        desk.close()
        agent.cleanup()


def test_get_state_is_strict_json_when_odometry_lies():
    """The text of a tool result is JSON for the client's model and tools: a NaN pose is null."""
    from shadowhound.mcp.server import _answer
    from tests.lying_odometry import LyingOdometry
    from tests.strict_json import strict_loads

    agent = RobotAgent(RobotAgentConfig(robot=LyingOdometry(x=math.nan, yaw=-math.inf)))
    agent.initialize()
    desk = McpDesk(agent)
    try:
        answer = _answer(desk.state())
    finally:
        desk.close()
        agent.cleanup()
    text = strict_loads(answer.content[0].text)  # type: ignore[union-attr]
    assert isinstance(text, dict)
    assert (text["robot"]["x"], text["robot"]["yaw"], text["robot"]["y"]) == (None, None, 0.0)
