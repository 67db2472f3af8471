"""Hybrid planning, the default with a model configured: what the offline rules understand whole
costs no model call; everything else is the model's, planned from the sentence as written."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config
from shadowhound.memory.history import MissionHistory
from shadowhound.planning import make_planner
from shadowhound.planning.hybrid import HybridPlanner
from shadowhound.planning.llm import LLMPlanner
from shadowhound.planning.rules import RulePlanner
from tests.llm_server import ScriptedLLM, json_plan, status, text


@pytest.fixture
def srv():
    with ScriptedLLM(models=("m",)) as server:
        yield server


def agent_for(srv, tmp_path=None, **llm):
    memory = {"enabled": True, "data_dir": str(tmp_path)} if tmp_path else {"enabled": False}
    settings = load_config(
        "llamacpp",
        {"llm": {"base_url": srv.url, "model": "m", "max_retries": 0, **llm}, "memory": memory},
        environ={},
    )
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=settings))
    agent.initialize()
    return agent


def test_hybrid_is_the_default_with_a_model_and_a_setting_turns_it_off(srv):
    def settings(**llm):
        return load_config("vllm", {"llm": {"base_url": srv.url, "model": "m", **llm}}, environ={})

    assert isinstance(make_planner(settings()), HybridPlanner)
    assert isinstance(make_planner(settings(hybrid=False)), LLMPlanner)
    assert isinstance(make_planner(settings(mode="react")), LLMPlanner)  # the model's own loop
    assert isinstance(make_planner(load_config("offline", environ={})), RulePlanner)
    env = load_config("vllm", environ={"SHADOWHOUND_LLM__HYBRID": "false"})
    assert env.llm.hybrid is False


@pytest.mark.parametrize(
    "mission",
    [
        "stand up and walk forward 1 meter",
        "turn right 45 degrees then sit down",
        "walk in a square of 1 meter",
        "go back to the start",
    ],
)
def test_sentences_the_rules_understand_cost_no_model_call(srv, mission):
    agent = agent_for(srv)
    result = agent.execute_mission(mission)
    assert result.success, result.response
    assert srv.requests == [] and result.usage.round_trips == 0
    assert (result.planner, result.plan.planned_by) == ("hybrid", "offline")
    record = result.to_dict()
    assert (record["planner"], record["planned_by"]) == ("hybrid", "offline")


def test_the_model_plans_what_the_rules_do_not_understand_from_the_sentence_as_written(srv):
    agent = agent_for(srv)
    # The rules understand the first clause only; the model gets the whole sentence and
    # nothing of the rules' partial reading.
    mission = "walk forward 1 meter and then fetch my slippers from the hallway"
    srv.script(
        json_plan(
            [
                {"skill": "nav.move", "args": {"distance": 1.0}},
                {"skill": "nav.goto", "args": {"place": "start"}},
            ]
        )
    )
    result = agent.execute_mission(mission)
    assert result.success, result.response
    assert len(srv.requests) == 1 and result.usage.round_trips == 1
    messages = srv.requests[0]["messages"]
    assert messages[-1] == {"role": "user", "content": mission}
    assert "I understood" not in json.dumps(messages) and "slippers" not in messages[0]["content"]
    assert (result.planner, result.plan.planned_by) == ("hybrid", "llm")


def test_a_model_failure_after_the_rules_gave_up_is_reported_not_hidden(srv):
    agent = agent_for(srv)
    srv.script(status(500, "model crashed"), status(500, "model crashed"))
    result = agent.execute_mission("fetch my slippers")
    assert not result.success and "HTTP 500" in result.response
    assert result.planner == "hybrid" and result.plan is None
    assert result.to_dict()["planned_by"] == ""


def test_hybrid_off_asks_the_model_even_for_simple_sentences(srv):
    agent = agent_for(srv, hybrid=False)
    srv.script(json_plan([{"skill": "body.stand", "args": {}}]))
    result = agent.execute_mission("stand up")
    assert result.success and result.usage.round_trips == 1
    assert (result.planner, result.plan.planned_by) == ("llm", "llm")


def test_the_mission_history_records_who_planned(srv, tmp_path):
    agent = agent_for(srv, tmp_path)
    srv.script(json_plan([{"skill": "sys.status", "args": {}}]))
    offline = agent.execute_mission("sit down")
    by_model = agent.execute_mission("fetch my slippers")
    assert by_model.success, by_model.response
    agent.cleanup()
    store = MissionHistory(tmp_path / "history.db")  # what a later process reads
    records = {r.mission_id: store.get(r.mission_id) for r in (offline, by_model)}
    assert records[offline.mission_id]["planned_by"] == "offline"
    assert records[by_model.mission_id]["planned_by"] == "llm"
    assert {r["planner"] for r in records.values()} == {"hybrid"}


def test_cli_run_reports_the_planner(srv):
    env = {**os.environ, "SHADOWHOUND_LLM__MAX_RETRIES": "0"}
    env.pop("SHADOWHOUND_CONFIG", None)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "shadowhound",
            "run",
            "--backend",
            "llamacpp",
            "--base-url",
            srv.url,
            "--model",
            "m",
            "--json",
            "walk forward 2 meters",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert (out["planner"], out["planned_by"], out["usage"]["round_trips"]) == (
        "hybrid",
        "offline",
        0,
    )
    assert srv.requests == []  # no completion asked: the start-up check lists models only


def test_planners_declare_what_the_agent_may_use_of_them(srv):
    """The agent chooses by declared protocol (never by probing): plan mode re-plans, react
    mode steps, the offline rules do neither."""
    from shadowhound.planning import Planner, ReplanningPlanner, StepwisePlanner

    def planner(**llm):
        return make_planner(
            load_config("vllm", {"llm": {"base_url": srv.url, "model": "m", **llm}}, environ={})
        )

    rules = make_planner(load_config("offline", environ={}))
    assert isinstance(rules, Planner) and not rules.needs_context
    assert not isinstance(rules, ReplanningPlanner) and not isinstance(rules, StepwisePlanner)
    for plan_mode in (planner(), planner(hybrid=False)):
        assert isinstance(plan_mode, ReplanningPlanner)
        assert not isinstance(plan_mode, StepwisePlanner)
    assert isinstance(planner(mode="react"), StepwisePlanner)


def test_one_backend_serves_the_planner_chat_and_vision_in_hybrid_mode(srv):
    """Vision through the hybrid planner once failed (its describe_image took no cancel
    event, so perception.describe crashed): now the agent's one backend answers it."""
    agent = agent_for(srv, vision=True)
    assert agent.backend is not None and agent.planner.model.backend is agent.backend
    srv.script(text("A red ball."), text("I am here."))
    result = agent.execute_mission("describe what you see")
    assert result.success, result.response
    assert result.plan.planned_by == "offline" and "A red ball." in result.response
    image = srv.requests[0]["messages"][0]["content"][1]
    assert image["image_url"]["url"].startswith("data:image/jpeg;base64,")
    assert agent.chat("where are you?") == "I am here."
    assert len(srv.requests) == 2
