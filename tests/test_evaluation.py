"""The planner must generalise: held-out sentences of the public kinds, never seen by the code."""

import json
from pathlib import Path

import pytest

from shadowhound.config import ShadowHoundConfig
from shadowhound.evaluation import load_cases, run_case

DATA = Path(__file__).parent / "data"
HELD_OUT = load_cases(DATA / "missions_heldout.yaml")
WORLD = load_cases(DATA / "missions_world.yaml")
WATCHES = load_cases(DATA / "missions_watches.yaml")


@pytest.mark.parametrize("case", HELD_OUT, ids=[c.mission[:50] for c in HELD_OUT])
def test_held_out_case(case):
    outcome = run_case(case, ShadowHoundConfig())
    assert outcome.passed, f"{outcome.failures} -> {outcome.response}"


@pytest.mark.parametrize("case", WORLD, ids=[c.mission[:50] for c in WORLD])
def test_world_case(case):
    """Going to things, places and points, names it cannot recognise, facing, travel."""
    outcome = run_case(case, ShadowHoundConfig())
    assert outcome.passed, f"{outcome.failures} -> {outcome.response}"


@pytest.mark.parametrize("case", WATCHES, ids=[c.mission[:50] for c in WATCHES])
def test_watch_case(case):
    """Until, unless, stop if: what fired and what it refused, in the default scene."""
    outcome = run_case(case, ShadowHoundConfig())
    assert outcome.passed, f"{outcome.failures} -> {outcome.response}"


def test_travel_questions_are_answered_from_the_odometer_without_moving():
    from shadowhound import RobotAgent

    agent = RobotAgent(ShadowHoundConfig())
    assert agent.execute_mission("walk forward 1 meter and turn left 90 degrees").success
    before = agent.robot.get_state()
    for question in ("how far have you walked?", "how long have you been walking?"):
        answer = agent.chat(question)
        assert "I have walked 1.00 m and turned 90 degrees since I started" in answer, answer
        assert "moving for" in answer
        reply = agent.execute_mission(question)
        assert reply.success and "travelled 1.00 m in total" in reply.response, reply.response
        assert "turned 90 degrees and moving for" in reply.response
    after = agent.robot.get_state()
    assert (after.x, after.y, after.yaw) == (before.x, before.y, before.yaw)


# -- several planners side by side ---------------------------------------------------------------

CASES = (
    '- mission: "walk forward 1 meter"\n  expect: {success: true, x: 1.0}\n'
    '- mission: "go sniff around the garden"\n  expect: {success: false, moved: false}\n'
)


def _model(request):
    """Plans the walk; for anything else says it cannot (no steps)."""
    from tests.llm_server import json_plan, text

    if request["messages"][-1]["content"] == "walk forward 1 meter":
        return json_plan([{"skill": "nav.move", "args": {"distance": 1.0}}])
    return text('{"steps": [], "answer": "I cannot sniff."}')


def test_eval_compares_planners_in_one_table(tmp_path):
    from tests.llm_server import ScriptedLLM, dynamic
    from tests.test_cli import shadowhound

    cases = tmp_path / "cases.yaml"
    cases.write_text(CASES)
    with ScriptedLLM(models=("m",)) as srv:
        srv.script(*[dynamic(_model) for _ in range(4)])
        common = ["--base-url", srv.url, "--model", "m", str(cases)]
        proc = shadowhound(
            "eval",
            "--backend",
            "offline",
            "--backend",
            "llamacpp",
            "--backend",
            "llamacpp:llm",
            *common,
        )
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert len(srv.requests) == 3  # hybrid asked once (the garden), llm twice
        json_proc = shadowhound(
            "eval", "--json", "--backend", "offline", "--backend", "llamacpp", *common
        )
    rows = {
        line.split(" | ")[0].strip("| "): line.split(" | ")
        for line in proc.stdout.splitlines()
        if line.startswith("| ")
    }
    # planner | passed | model calls/mission | planned offline | prompt | completion | ...
    assert rows["offline"][1:4] == ["2/2 (100%)", "0.00", "1/2"]
    assert rows["llamacpp"][1:4] == ["2/2 (100%)", "0.50", "1/2"]
    assert rows["llamacpp:llm"][1:4] == ["2/2 (100%)", "1.00", "0/2"]
    assert rows["llamacpp:llm"][4:6] == ["100", "20"]  # the scripted usage, 50 + 10 a call
    report = json.loads(json_proc.stdout)
    cards = {p["scorecard"]["planner"]: p["scorecard"] for p in report["planners"]}
    assert cards["llamacpp"]["model_calls"] == 1 and cards["offline"]["model_calls"] == 0
    assert [c["planned_by"] for c in report["planners"][1]["cases"]] == ["offline", ""]


def test_invalid_plans_before_repair_are_counted():
    from shadowhound import load_config
    from shadowhound.evaluation import MissionCase, run_cases, scorecard
    from tests.llm_server import ScriptedLLM, json_plan

    with ScriptedLLM(models=("m",)) as srv:
        srv.script(
            json_plan([{"skill": "nav.move", "args": {"distance": 1.0, "meters": 1}}]),
            json_plan([{"skill": "nav.move", "args": {"distance": 1.0}}]),
        )
        settings = load_config(
            "llamacpp", {"llm": {"base_url": srv.url, "model": "m", "hybrid": False}}, environ={}
        )
        outcomes = run_cases([MissionCase("walk forward 1 meter", {"x": 1.0})], settings)
    card = scorecard("llm", outcomes)
    assert (card.passed, card.model_calls, card.invalid_plans) == (1, 2, 1)
    assert outcomes[0].usage.invalid_plans == 1


def test_an_unknown_planner_option_is_a_usage_error(tmp_path):
    from tests.test_cli import shadowhound

    cases = tmp_path / "cases.yaml"
    cases.write_text(CASES)
    proc = shadowhound("eval", "--backend", "offline", "--backend", "llamacpp:fast", str(cases))
    assert proc.returncode == 2 and "unknown planner option 'fast'" in proc.stderr
    assert proc.stdout == ""  # checked before any case ran
