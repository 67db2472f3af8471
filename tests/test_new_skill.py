"""A new skill is one file (issue 14): `tests/look_up_skill.py` defines `body.look_up`, registered
the ordinary way, and nothing else in the house is edited for it. A language model's JSON plan
names it, the governor checks it from its declarations, the simulated robot runs it, the result
says it, the history records it and retrieval memory keeps what it saw. A guard keeps facts
about skills from being keyed by their names outside the skills again."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import pytest

import shadowhound
from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, SkillCall, load_config
from shadowhound.config import SafetyConfig, ShadowHoundConfig
from shadowhound.result import StepStatus
from shadowhound.safety import Governor
from shadowhound.skills import PlanEnv, SkillRegistry, default_registry
from shadowhound.state import Posture, RobotState
from tests import look_up_skill
from tests.llm_server import ScriptedLLM, json_plan, model_settings
from tests.test_memory import needs_rag


def with_look_up(skill=look_up_skill.SKILL) -> SkillRegistry:
    registry = default_registry()
    registry.register(skill)
    return registry


def make_agent(srv, tmp_path, **memory) -> tuple[RobotAgent, SimRobot]:
    settings = load_config(
        "llamacpp",
        {
            "llm": model_settings(srv, model="m"),
            "memory": {"enabled": True, "data_dir": str(tmp_path), **memory},
        },
        environ={},
    )
    robot = SimRobot(time_scale=0.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings, registry=with_look_up()))
    agent.initialize()
    return agent, robot


def test_a_model_plans_it_the_robot_runs_it_the_result_says_it_the_history_keeps_it(tmp_path):
    with ScriptedLLM(models=("m",)) as srv:
        agent, robot = make_agent(srv, tmp_path)
        robot.set_posture(Posture.SITTING)
        srv.script(
            json_plan([{"skill": "body.look_up", "args": {"degrees": "20 deg", "hold": "2 s"}}])
        )
        result = agent.execute_mission("look up at the ceiling")
        request = srv.requests[0]
    # The model was offered it: in the prompt's skill list and the plan's schema.
    assert "body.look_up(" in request["messages"][0]["content"]
    offered = request["response_format"]["schema"]["properties"]["steps"]["items"]["properties"]
    assert "body.look_up" in offered["skill"]["enum"]
    assert offered["args"]["properties"]["hold"] == {"type": "number"}  # its own argument
    assert result.success, result.response
    [step] = result.steps
    assert (step.skill, step.args, step.status) == (
        "body.look_up",
        {"degrees": 20.0, "hold": 2.0},
        StepStatus.SUCCEEDED,
    )
    # It runs standing, so the sitting robot stood up first; it held the view 2 s (robot clock).
    assert robot.get_state().posture is Posture.STANDING
    assert step.output.startswith("stood up first (was sitting); looking up 20 degrees: ")
    assert step.robot_duration >= 2.0
    # It reports: its answer is a sentence of the response, not a "Done:" of actions.
    assert "Done:" not in result.response
    assert result.response.startswith("Stood up first (was sitting); looking up 20 degrees: ")
    assert "In view: " in result.response
    # The history holds the mission with its step.
    record = agent.memory.history.get(result.mission_id)
    assert record["status"] == "succeeded"
    assert [(s["skill"], s["output"]) for s in record["steps"]] == [("body.look_up", step.output)]
    agent.cleanup()


@needs_rag
def test_retrieval_memory_keeps_what_it_saw_as_an_observation(tmp_path):
    with ScriptedLLM(models=("m",)) as srv:
        agent, _robot = make_agent(srv, tmp_path, enable_rag=True)
        srv.script(
            json_plan([{"skill": "body.look_up", "args": {}}]),
            json_plan([{"skill": "body.stand", "args": {}}]),
        )
        looked = agent.execute_mission("look up")
        assert looked.success and agent.execute_mission("stand").success
    # Its output, and nothing of body.stand (which declares no memory), is an observation.
    kept = agent.memory.recall.search("looking up at the room", k=5, kind="observation")
    assert [(m.text, m.meta.get("mission")) for m in kept] == [
        (looked.steps[0].output, looked.mission_id)
    ]
    assert kept[0].text.startswith("looking up 30 degrees: ")
    agent.cleanup()


# -- the governor reads its declarations -----------------------------------------------------


def check(calls, registry=None, start=None, auto_stand=True, **limits):
    registry = registry or with_look_up()
    settings = ShadowHoundConfig(safety=SafetyConfig(**limits))
    start = start or RobotState()
    return Governor(settings.safety, auto_stand, registry).check_plan(
        [registry.validate(c) for c in calls], start, PlanEnv(settings, start.pose)
    )


def reasons(verdict) -> list[str]:
    return [str(r) for r in verdict.refusals]


def test_it_runs_standing_and_leaves_the_robot_standing():
    sitting = RobotState(posture=Posture.SITTING)
    look = SkillCall("body.look_up", {})
    assert (
        "will be sitting here; add body.stand"
        in reasons(check([look], start=sitting, auto_stand=False))[0]
    )
    # After it the robot stands, so a move needs no body.stand of its own.
    assert (
        check(
            [SkillCall("body.stand"), look, SkillCall("nav.move", {"distance": 1})],
            start=sitting,
            auto_stand=False,
        ).refusals
        == []
    )


def test_a_low_battery_refuses_it_unless_it_declares_otherwise():
    low = RobotState(battery=9.0)
    refused = reasons(check([SkillCall("body.look_up", {})], start=low))
    assert refused == [
        "step 1 (body.look_up): the battery is at 9%, below the floor of 15% "
        "(safety.battery_floor): only nav.stop, body.sit, body.lie_down, "
        "sys.status, voice.say are allowed"
    ]
    gentle = with_look_up(dataclasses.replace(look_up_skill.SKILL, low_battery=True))
    assert check([SkillCall("body.look_up", {})], gentle, start=low).refusals == []
    still = check([SkillCall("nav.move", {"distance": 1})], gentle, start=low)
    assert reasons(still)[0].endswith(
        "only nav.stop, body.sit, body.lie_down, sys.status, voice.say, body.look_up are allowed"
    )


def test_a_steep_look_needs_approval_and_its_hold_counts_toward_the_missions_time():
    steep = check([SkillCall("body.look_up", {"degrees": 50})])
    assert steep.refusals == []
    assert [str(a) for a in steep.approvals] == [
        "step 1 (body.look_up): looking up 50 degrees can tip the robot over backwards and "
        "needs approval, or safety.allow_risky_tricks: true"
    ]
    assert check([SkillCall("body.look_up", {"degrees": 40})]).approvals == []
    assert (
        check([SkillCall("body.look_up", {"degrees": 50})], allow_risky_tricks=True).approvals == []
    )
    long = check([SkillCall("body.look_up", {"hold": 20})], max_mission_duration=15)
    assert (
        "would take at least 20.0 s on the robot's clock, more than the limit of 15 s"
        in reasons(long)[0]
    )
    assert check([SkillCall("body.look_up", {"hold": 10})], max_mission_duration=15).refusals == []


def test_a_call_is_said_in_its_own_words():
    registry = with_look_up()
    call = registry.validate(SkillCall("body_look_up", {"degrees": 15}))
    assert call.skill.say(call.args) == "look up 15 degrees"
    nameless = dataclasses.replace(look_up_skill.SKILL, phrase=None)
    assert nameless.say(call.args) == "body.look_up"


# -- the guard -------------------------------------------------------------------------------

PACKAGE = Path(shadowhound.__file__).parent


def test_no_fact_about_a_skill_is_keyed_by_its_name_outside_the_skills():
    """A string that is exactly a skill's name may appear in skills/ (the declarations) and in
    the planners (planning/: which words mean which skill is language, not a fact about the
    skill), except in the offline planner's messages (`_errors.py`, which asks the skill)."""
    names = set(default_registry().names)
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        where = path.relative_to(PACKAGE)
        if where.parts[0] == "skills" or (
            where.parts[0] == "planning" and where.name != "_errors.py"
        ):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and node.value in names:
                found.append(f"{where}:{node.lineno}: {node.value!r}")
    assert found == [], "declare it on the Skill instead: " + "; ".join(found)


def test_a_skill_that_walks_cannot_be_declared_fit_for_a_low_battery():
    with pytest.raises(
        ValueError, match="'body.look_up' moves the robot, so it cannot be allowed on a low battery"
    ):
        dataclasses.replace(look_up_skill.SKILL, moves=True, low_battery=True)
