"""Prompts with a stable prefix: for one configuration, every mission's request starts with the
same bytes (intro, skills, rules, reply format); what changes comes last, so a server's prompt
cache evaluates only the tail."""

from __future__ import annotations

import os

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config
from shadowhound.planning import prompts
from shadowhound.skills import default_registry
from tests.llm_server import ScriptedLLM, json_plan, text, tool_calls


def common_prefix(a: str, b: str) -> str:
    return os.path.commonprefix([a, b])


@pytest.mark.parametrize("style", ["plan", "tools", "react"])
def test_the_prefix_is_everything_constant_and_nothing_that_changes(style):
    prefix = prompts.stable_prefix(default_registry(), style=style)
    assert prefix == prompts.stable_prefix(default_registry(), style=style)
    assert prefix.startswith("You plan actions for ShadowHound")
    assert "Rules:" in prefix and ("Reply with JSON only" in prefix if style == "plan" else True)
    assert ("nav.move(distance" in prefix) is (style != "tools")
    for changing in ("Robot now", "Places:", "Recent missions", "Relevant memories"):
        assert changing not in prefix


def _agent(srv, tmp_path, **llm):
    settings = load_config(
        "llamacpp",
        {
            "llm": {"base_url": srv.url, "model": "m", "max_retries": 0, "hybrid": False, **llm},
            "memory": {"enabled": True, "data_dir": str(tmp_path)},
        },
        environ={},
    )
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=settings))
    agent.initialize()
    return agent


@pytest.mark.parametrize(
    "style,fmt,mode",
    [("plan", "auto", "plan"), ("tools", "tools", "plan"), ("react", "auto", "react")],
)
def test_two_different_missions_share_the_prefix_byte_for_byte(tmp_path, style, fmt, mode):
    with ScriptedLLM(models=("m",)) as srv:
        agent = _agent(srv, tmp_path, plan_format=fmt, mode=mode)
        if style == "plan":
            srv.script(
                json_plan([{"skill": "nav.move", "args": {"distance": 1.5}}]),
                json_plan([{"skill": "body.sit", "args": {}}]),
            )
        else:
            srv.script(
                tool_calls(("nav_move", {"distance": 1.5})),
                text("done"),
                tool_calls(("body_sit", {})),
                text("done"),
            )
        agent.execute_mission("walk forward one and a half meters")
        agent.execute_mission("take a seat over there")  # robot moved; history grew
        firsts = [r for r in srv.requests if len(r["messages"]) == 2]
        assert len(firsts) == 2
        one, two = (r["messages"][0]["content"] for r in firsts)
    prefix = prompts.stable_prefix(default_registry(), style=style)
    assert one.startswith(prefix) and two.startswith(prefix)
    assert one != two
    # The first difference is after the whole constant part: places, history, memories, the
    # robot's state and the mission (the user message) are the tail.
    assert len(common_prefix(one, two)) >= len(prefix)
    assert "Robot now: standing at x=0.00" in one and "Robot now: standing at x=1.50" in two
    assert one.index("Robot now") > len(prefix) and two.index("Recent missions") > len(prefix)


def test_the_prefix_does_not_depend_on_the_places_or_state(tmp_path):
    registry = default_registry()
    a = prompts.system_prompt(
        registry,
        style="plan",
        places={"kitchen": (3, 2)},
        history=["succeeded: 'sit' -> Done."],
        history_size=5,
        memories=["the dock is behind the sofa"],
    )
    b = prompts.system_prompt(registry, style="plan")
    prefix = prompts.stable_prefix(registry, style="plan")
    assert a.startswith(prefix + "\n") and b.startswith(prefix + "\n")
    assert a.index("Places:") < a.index("Recent missions") < a.index("Relevant memories")
