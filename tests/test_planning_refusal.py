"""The model may refuse a request instead of planning it ("blorp the zanzibar"): the refusal is
in the plan schema of every dialect, the prompt offers it, and the planner fails the mission
with the model's reason, cleaned and short, and runs nothing of that reply."""

from __future__ import annotations

import json
from typing import Any

import jsonschema
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config
from shadowhound.planning import prompts, schema
from shadowhound.planning.parse import parse_reply
from shadowhound.skills import default_registry
from tests.llm_server import ScriptedLLM, json_plan, model_settings, text, tool_calls

REGISTRY = default_registry()
DIALECTS = ("openai", "json_schema", "llamacpp")
MOVE = {"skill": "nav.move", "args": {"distance": 1}}
REASON = "I do not know what 'blorp' or 'zanzibar' mean."


def refusal(reason: Any = REASON) -> dict[str, Any]:
    return {"skill": "refuse", "args": {"reason": reason}}


def valid(instance: Any, dialect: str, style: str = "strict") -> bool:
    root = schema.plan_schema(REGISTRY, dialect, style)  # type: ignore[arg-type]
    return jsonschema.Draft202012Validator(root).is_valid(instance)


@pytest.fixture
def srv():
    with ScriptedLLM(models=("test-model",)) as server:
        yield server


def make_agent(srv, **llm):
    settings = load_config("llamacpp", {"llm": model_settings(srv, **llm)}, environ={})
    robot = SimRobot(time_scale=0.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    agent.initialize()
    return agent, robot


# -- the schema and the prompt offer it ----------------------------------------------------


@pytest.mark.parametrize("dialect", DIALECTS)
def test_every_dialect_admits_a_refusal_with_a_reason_and_nothing_else(dialect):
    assert valid({"steps": [refusal()], "answer": "", "conditions": []}, dialect)
    assert not valid(
        {"steps": [{"skill": "refuse", "args": {}}], "answer": "", "conditions": []}, dialect
    )
    assert not valid({"steps": [refusal(3)], "answer": "", "conditions": []}, dialect)
    extra = {"skill": "refuse", "args": {"reason": "no", "distance": 1.0}}
    assert not valid({"steps": [extra], "answer": "", "conditions": []}, dialect)


@pytest.mark.parametrize("dialect", DIALECTS)
def test_the_compact_schema_admits_a_refusal_with_a_reason(dialect):
    args = schema.plan_schema(REGISTRY, dialect, "compact")["properties"]["steps"]["items"]
    nulls = dict.fromkeys(args["properties"]["args"]["properties"]) if dialect == "openai" else {}
    assert "refuse" in args["properties"]["skill"]["enum"]
    step = {"skill": "refuse", "args": {**nulls, "reason": REASON}}
    assert valid({"steps": [step], "answer": "", "conditions": []}, dialect, "compact")
    step = {"skill": "refuse", "args": {**nulls, "reason": 3}}
    assert not valid({"steps": [step], "answer": "", "conditions": []}, dialect, "compact")


@pytest.mark.parametrize("dialect", ["json_schema", "llamacpp"])
def test_a_reason_is_never_empty_and_short_where_the_grammar_can_hold_it(dialect):
    assert not valid({"steps": [refusal("")], "answer": "", "conditions": []}, dialect)
    too_long = {
        "steps": [refusal("x" * (schema.ANSWER_MAX_CHARS + 1))],
        "answer": "",
        "conditions": [],
    }
    assert valid(too_long, dialect) is (dialect == "llamacpp")  # llama.cpp: cut when read


def test_refuse_can_never_be_a_skills_name():
    assert "." not in schema.REFUSE and schema.REFUSE not in REGISTRY.names
    assert all("." in name for name in REGISTRY.names)


@pytest.mark.parametrize("style", ["plan", "tools", "react"])
def test_the_prompt_offers_the_refusal_in_every_style(style):
    prefix = prompts.stable_prefix(REGISTRY, style=style)
    assert "request no skill fits" in prefix
    if style == "plan":
        assert '{"skill":"refuse","args":{"reason":"why"}}' in prefix


# -- the parser reads it, in every form a model sends ----------------------------------------


@pytest.mark.parametrize(
    "message",
    [
        {"content": json.dumps({"steps": [refusal()], "answer": "", "conditions": []})},
        {"content": json.dumps({"steps": [MOVE, refusal()]})},
        {"content": "```json\n" + json.dumps({"refusal": REASON}) + "\n```"},
        {"content": json.dumps({"refusal": REASON, "steps": [MOVE]})},
        {"content": None, "refusal": REASON},  # OpenAI's own refusal
        {"content": "", "tool_calls": [
            {"id": "c1", "type": "function", "function": {"name": "nav_move", "arguments": "{}"}},
            {"id": "c2", "type": "function",
             "function": {"name": "refuse", "arguments": json.dumps({"reason": REASON})}},
        ]},
    ],
)  # fmt: skip
def test_a_refusal_in_any_form_is_its_reason_and_no_steps(message):
    reply = parse_reply({"role": "assistant", **message})
    assert reply.refusal == REASON and reply.calls == [] and reply.problems == []


def test_a_refusal_without_a_reason_says_so():
    for args in ({}, {"reason": ""}, {"reason": 7}, None):
        content = json.dumps({"steps": [{"skill": "refuse", "args": args}]})
        assert parse_reply({"content": content}).refusal == "no reason given"


@settings(max_examples=300, deadline=None)
@given(reason=st.text(min_size=1, max_size=2000))
def test_a_reason_is_one_short_clean_line(reason):
    reply = parse_reply(
        {"content": json.dumps({"steps": [refusal(reason)], "answer": "", "conditions": []})}
    )
    assert reply.refusal and reply.calls == []
    assert len(reply.refusal) <= schema.ANSWER_MAX_CHARS
    assert not any(ord(c) < 32 or 0x7F <= ord(c) <= 0x9F for c in reply.refusal)
    assert not any(c in reply.refusal for c in "\u200b\u200e\u200f\u202a\u202e\u2066\u2069")
    assert reply.refusal == reply.refusal.strip()


# -- the planner fails the mission with it, and nothing moves --------------------------------


def test_blorp_the_zanzibar_is_refused_with_the_models_reason(srv):
    agent, robot = make_agent(srv)
    srv.script(json_plan([refusal()]))
    result = agent.execute_mission("blorp the zanzibar")
    assert not result.success
    assert result.response == f"The model refused to plan this request: {REASON}"
    assert result.usage.round_trips == 1 and result.usage.invalid_plans == 0  # not repaired
    assert not robot.received_motion


def test_a_refusal_among_steps_runs_none_of_them(srv):
    agent, robot = make_agent(srv)
    srv.script(
        json_plan([{"skill": "body.stand", "args": {}}, refusal("too vague to walk anywhere")])
    )
    result = agent.execute_mission("go over there and do the thing")
    assert not result.success and result.response.endswith("too vague to walk anywhere")
    assert result.steps == [] and not robot.received_motion


def test_react_mode_ends_on_a_refusal(srv):
    agent, robot = make_agent(srv, mode="react")
    srv.script(text(json.dumps({"refusal": "\x1b[31mI cannot blorp.\x1b[0m"})))
    result = agent.execute_mission("blorp the zanzibar")
    assert not result.success
    assert result.response == "The model refused to plan this request: [31mI cannot blorp. [0m"
    assert not robot.received_motion and len(srv.requests) == 1


def test_tools_mode_reads_a_refusal_the_model_calls(srv):
    agent, robot = make_agent(srv, plan_format="tools")
    srv.script(tool_calls(("refuse", {"reason": REASON})))
    result = agent.execute_mission("blorp the zanzibar")
    assert not result.success and result.response.endswith(REASON)
    assert not robot.received_motion
