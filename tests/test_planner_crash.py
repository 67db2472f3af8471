"""A planner that crashes ends the mission failed, with the reason, in every record: the result
each interface reads, and the history database (a real SQLite file), so that the next start
finds no mission `running` and reports no crash that did not happen. A model's reply nested
thousands deep is refused, saying how deep and what is allowed, before it is decoded."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.memory.history import MissionHistory
from shadowhound.plan import Plan, SkillCall, Usage
from shadowhound.worker import MissionJob, MissionWorker
from tests.llm_server import ScriptedLLM, text

DEPTH = 3000
# A plan whose one step's arguments nest DEPTH deep: Python's JSON decoder gives up on it.
DEEP_PLAN = (
    '{"steps": [{"skill": "nav.move", "args": '
    + '{"distance": ' * DEPTH
    + "1"
    + "}" * DEPTH
    + "}]}"
)
NESTS = f"nests {DEPTH + 3} deep; at most 16 (llm.max_reply_depth)"


def run_cli(*args: str, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    full = {**os.environ, **env}
    full.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=full,
    )


def test_cli_run_json_with_a_reply_nested_3000_deep_fails_and_the_history_says_so(
    tmp_path: Path,
) -> None:
    with ScriptedLLM(models=("m",)) as srv:
        srv.script(text(DEEP_PLAN), text(DEEP_PLAN))  # the reply, and the repair turn's reply
        env = {"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path), "SHADOWHOUND_LLM__HYBRID": "false"}
        done = run_cli(
            "run",
            "--json",
            "--backend",
            "llamacpp",
            "--base-url",
            srv.url,
            "--model",
            "m",
            "walk forward 1 meter",
            env=env,
        )
    answer = json.loads(done.stdout)
    assert done.returncode == 1, done.stderr
    assert answer["status"] == "failed" and answer["success"] is False, answer
    assert NESTS in answer["error"], answer
    assert (answer.get("robot") or {}).get("distance_travelled") == 0
    assert "Traceback" not in done.stderr
    with_history = MissionHistory(tmp_path / "history.db")
    try:
        assert with_history.interrupted == 0  # nothing was left running
        (row,) = with_history.recent(5)
        assert row["status"] == "failed" and NESTS in row["response"], row
    finally:
        with_history.close()
    # A fresh start of the command reports no crash.
    again = run_cli("run", "--json", "stand up", env=env)
    assert again.returncode == 0, again.stderr
    assert "interrupted" not in again.stderr and "crash" not in again.stderr, again.stderr


class CrashingPlanner:
    """A planner that raises `error` where it is asked: planning, re-planning or react."""

    name = "crashing"
    kind = "llm"
    needs_context = False

    def __init__(self, error: BaseException, first: Plan | None = None) -> None:
        self.error = error
        self.first = first  # a first plan to run (then re-planning after it fails raises)

    def plan(self, text: str, context: Any = None) -> Plan:
        if self.first is not None:
            return self.first
        raise self.error

    def replan(self, text: str, context: Any, done: list[str], failure: str) -> Plan:
        raise self.error


class CrashingReact(CrashingPlanner):
    def react(self, text: str, context: Any, run_step: Any) -> tuple[str, Usage, bool]:
        run_step(SkillCall("nav.rotate", {"degrees": 10}))  # the robot moved, then the crash
        raise self.error


class Oddity(Exception):
    """An exception class no part of ShadowHound knows."""


ERRORS = st.sampled_from(
    [RecursionError, MemoryError, ValueError, KeyError, TypeError, AttributeError, Oddity]
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    kind=ERRORS,
    said=st.text(max_size=300),
    where=st.sampled_from(["plan", "replan", "react"]),
)
def test_any_exception_a_planner_raises_ends_the_record_failed_never_running(
    tmp_path_factory: Any, kind: type[Exception], said: str, where: str
) -> None:
    data = tmp_path_factory.mktemp("history")
    config = ShadowHoundConfig(memory={"enabled": True, "data_dir": str(data)})
    robot = SimRobot(config.sim, time_scale=0.0)
    error = kind(said)
    if where == "replan":  # a first plan whose step fails, then re-planning crashes
        no_one = Plan([SkillCall("nav.follow", {"target": "person"})], planned_by="llm")
        planner: CrashingPlanner = CrashingPlanner(error, first=no_one)
    else:
        planner = CrashingReact(error) if where == "react" else CrashingPlanner(error)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config, planner=planner))
    agent.initialize()
    worker = MissionWorker(agent)
    try:
        job = MissionJob("walk forward 1 meter", source="web")
        assert worker.submit(job) is None
        assert job.done.wait(30)
        result = job.result
        assert job.dropped is None and result is not None
        assert result.status.value == "failed" and not result.success
        if where != "replan":  # re-planning's crash is added to why the step failed
            assert kind.__name__ in (result.error or ""), result.error
        row = agent.memory.history.get(job.mission_id)  # type: ignore[union-attr]
        assert row is not None and row["status"] == "failed", row
        assert robot.true_odometer < 1e-6  # nothing walked (react turned 10 degrees)
        state = robot.get_state()
        assert robot.counters["stops"] > 0  # left stopped, at rest but for the last braking
        assert max(abs(state.vx), abs(state.vy), abs(state.wz)) < 1e-3
    finally:
        worker.stop()
        agent.cleanup()
    fresh = MissionHistory(data / "history.db")
    try:
        assert fresh.interrupted == 0
    finally:
        fresh.close()


def test_deep_json_in_a_reply_is_measured_and_refused_never_decoded() -> None:
    from shadowhound.planning.parse import nesting, parse_reply

    assert nesting('{"a": "[[[[{{{{", "b": [1, {"c": []}]}') == 4  # brackets in strings skipped
    deep_args = "[" * DEPTH + "]" * DEPTH
    calls = [{"id": "c1", "function": {"name": "nav.move", "arguments": deep_args}}]
    tools = parse_reply({"tool_calls": calls})
    assert tools.problems == [
        f"tool call 1: the model's reply nests {DEPTH} deep; at most 16 (llm.max_reply_depth)"
    ]
    fenced = parse_reply({"content": "Here:\n```json\n" + DEEP_PLAN + "\n```"}, max_depth=20)
    assert fenced.calls == [] and fenced.problems == [
        f"the model's reply nests {DEPTH + 3} deep; at most 20 (llm.max_reply_depth)"
    ]
    plain = parse_reply({"content": '{"steps": [{"skill": "nav.move", "args": {"distance": 1}}]}'})
    assert [c.skill for c in plain.calls] == ["nav.move"] and not plain.problems


def test_a_mission_that_raises_past_its_run_still_ends_failed_in_the_worker(
    tmp_path: Path,
) -> None:
    """The worker's own net: an agent that started a mission (its record `running`) and then
    raised ends the job failed with the reason, in its result and its history row."""
    from shadowhound import events as ev

    class Breaking(RobotAgent):
        def execute_mission(self, text: str, mission_id: str | None = None) -> Any:
            self._events.emit(ev.MissionStarted(mission_id or "m", text))
            raise Oddity("a bug after the start")

    config = ShadowHoundConfig(memory={"enabled": True, "data_dir": str(tmp_path)})
    agent = Breaking(RobotAgentConfig(robot=SimRobot(config.sim, time_scale=0.0), settings=config))
    agent.initialize()
    worker = MissionWorker(agent)
    try:
        job = MissionJob("stand up", source="web")
        assert worker.submit(job) is None and job.done.wait(30)
        assert job.dropped is None and job.result is not None
        assert job.result.status.value == "failed" and "Oddity" in (job.result.error or "")
        row = agent.memory.history.get(job.mission_id)  # type: ignore[union-attr]
        assert row is not None and row["status"] == "failed" and "Oddity" in row["response"]
    finally:
        worker.stop()
        agent.cleanup()
