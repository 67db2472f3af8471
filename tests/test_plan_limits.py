"""What one plan may carry (agent.max_steps, max_watches_per_step, max_watches, max_args_chars):
a model that sends 10,000 watches is refused, naming the limit, before anything moves; the
work of checking a plan is bounded by the limits whatever its size; and a plan within them
runs its ticks without tripping the (real) watchdog."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot, load_config
from shadowhound.checking import check_plan
from shadowhound.plan import Plan, SkillCall, Watch
from shadowhound.planning import FixedPlanner
from shadowhound.safety import Governor
from shadowhound.skills import PlanEnv, SkillRegistry, ValidatedCall, default_registry
from shadowhound.state import RobotState, Scan, Sighting
from shadowhound.worker import MissionJob, MissionWorker
from tests.llm_server import ScriptedLLM, model_settings, text

LIMITS = ShadowHoundConfig().agent
UNSEEN = Watch("until", "seen", "white fridge", within=0.2)  # never holds in the default room


def watches_plan(count: int) -> str:
    """A model's JSON plan: one walk with `count` watches."""
    import json

    condition = {"step": 1, "when": "until", "kind": "seen", "name": "red ball"}
    return json.dumps(
        {
            "steps": [{"skill": "nav.move", "args": {"distance": 1}}],
            "conditions": [condition] * count,
        }
    )


def test_a_model_plan_with_10000_watches_is_refused_naming_the_limits() -> None:
    with ScriptedLLM(models=("test-model",)) as srv:
        settings_ = load_config("llamacpp", {"llm": model_settings(srv)}, environ={})
        robot = SimRobot(settings_.sim, time_scale=0.0)
        agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings_))
        agent.initialize()
        srv.script(text(watches_plan(10_000)), text(watches_plan(10_000)))  # and the repair's
        result = agent.execute_mission("walk forward until you see the red ball")
        agent.cleanup()
    assert result.status.value == "failed", result.response
    assert (
        "step 1 carries 10000 conditions; at most 8 are allowed (agent.max_watches_per_step)"
        in result.response
    )
    assert "the plan carries 10000 conditions; at most 64" in result.response
    assert robot.true_odometer == 0 and not robot.received_motion
    # The repair turn told the model the limit, not 10,000 lines about each watch.
    assert len(srv.requests[1]["messages"][-1]["content"]) < 1000


class CountingRegistry(SkillRegistry):
    """The real registry, counting the calls it validates."""

    def __init__(self) -> None:
        super().__init__(default_registry())
        self.validated = 0

    def validate(self, call: SkillCall) -> ValidatedCall:
        self.validated += 1
        return super().validate(call)


class CountingRobot(SimRobot):
    """The simulator, counting what checking a plan reads of it."""

    reads = 0

    def in_view(self) -> tuple[Sighting, ...]:
        self.reads += 1
        return super().in_view()

    def get_scan(self) -> Scan | None:
        self.reads += 1
        return super().get_scan()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    steps=st.integers(0, 5_000),
    watches=st.integers(0, 5_000),
    guarded=st.booleans(),
    chars=st.integers(0, 50_000),
)
def test_checking_a_plan_of_any_size_does_work_bounded_by_the_limits(
    steps: int, watches: int, guarded: bool, chars: int
) -> None:
    """Counted, not timed: validations and robot reads never pass the limits, and a plan
    beyond them is refused naming the limit before a single step is validated."""
    config = ShadowHoundConfig()
    robot = CountingRobot(config.sim, time_scale=0.0)
    registry = CountingRegistry()
    say = SkillCall(
        "voice.say",
        {"text": "x" * chars},
        watches=(UNSEEN,) * watches,
        guard=Watch("if", "battery_below", percent=50) if guarded else None,
    )
    plan = Plan([say] * steps)
    env = PlanEnv(config, belief=robot.belief(), vocabulary=robot.vocabulary())
    governor = Governor(config.safety, skills=registry)
    checked = check_plan(plan, registry, governor, config, env, RobotState(), robot=robot)
    per_step = watches + guarded
    over = {
        "agent.max_steps": steps > LIMITS.max_steps,
        "agent.max_watches_per_step": steps > 0 and per_step > LIMITS.max_watches_per_step,
        "agent.max_watches": steps * per_step > LIMITS.max_watches,
        "agent.max_args_chars": steps > 0 and chars + 5 > LIMITS.max_args_chars,
    }
    said = " ".join(checked.problems)
    if over["agent.max_steps"]:
        assert f"the plan has {steps} steps; at most 50" in said
    else:
        for limit, broken in over.items():
            assert (f"({limit})" in said) == broken, (limit, checked.problems)
    if any(over.values()):
        assert registry.validated == 0 and robot.reads == 0 and not checked.calls
    assert registry.validated <= LIMITS.max_steps
    assert robot.reads <= LIMITS.max_watches


def walk_with(count: int) -> Plan:
    """A short walk watching `count` conditions, none of which holds on the way."""
    kinds = [
        UNSEEN,
        Watch("unless", "in_the_way", within=0.3),
        Watch("until", "battery_below", percent=1),
    ]
    watches = tuple(kinds[i % len(kinds)] for i in range(count))
    return Plan([SkillCall("nav.move", {"distance": 0.3}, watches=watches)])


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(count=st.one_of(st.integers(0, LIMITS.max_watches_per_step), st.integers(9, 10_000)))
def test_a_plan_within_the_limits_walks_without_tripping_the_watchdog(count: int) -> None:
    """On a simulator in real time, with the agent's own watchdog armed (at the 1 s the
    loaded-machine tests use): a walk with up to the most watches a step may carry walks
    without a trip; one with more never starts."""
    config = ShadowHoundConfig(safety={"watchdog_timeout": 1.0})
    robot = SimRobot(config.sim, time_scale=1.0)
    plan = walk_with(count)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config, planner=FixedPlanner(plan)))
    agent.initialize()
    worker = MissionWorker(agent)
    try:
        job = MissionJob("walk forward", source="web")
        assert worker.submit(job) is None
        assert job.done.wait(60)
        result: Any = job.result
        assert agent._watchdog is not None and agent._watchdog.trips == 0, result.response
        if count > LIMITS.max_watches_per_step:
            assert result.status.value == "failed" and "max_watches_per_step" in result.response
            assert robot.true_odometer == 0
        else:
            assert result.success, result.response
            assert math.isclose(robot.get_state().x, 0.3, abs_tol=0.02)
    finally:
        worker.stop()
        agent.cleanup()


@pytest.mark.parametrize("where", ["args", "key"])
def test_a_step_whose_arguments_carry_a_megabyte_is_refused_naming_the_limit(where: str) -> None:
    config = ShadowHoundConfig()
    robot = SimRobot(config.sim, time_scale=0.0)
    big = "x" * 1_000_000
    args = {"text": big} if where == "args" else {big: 1}
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config))
    agent.initialize()
    result = agent.run_plan([SkillCall("voice.say", args)])
    agent.cleanup()
    assert result.status.value == "failed"
    assert "step 1: its arguments carry more than 2000 characters" in result.response
    assert len(result.response) < 1000 and not robot.received_motion
