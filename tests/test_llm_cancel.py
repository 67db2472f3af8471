"""Cancel and e-stop while the mission waits on a language model that never answers.

The real `openai` client against a real HTTP server on loopback that accepts requests and never
answers (`hang()`). Wherever the model is asked during a mission (plan, repair, re-plan, react,
a vision step), `cancel()` / `estop()` from another thread end the mission at once: stopped with
the reason, the robot never moved after the press (simulator ground truth), the request is
abandoned and no retry is ever sent.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config
from shadowhound.llm import backend
from shadowhound.memory import MissionHistory
from shadowhound.result import MissionResult
from tests.llm_server import (
    ScriptedLLM,
    drop,
    hang,
    json_plan,
    status,
    text,
    tool_calls,
)

MOVE_1 = [{"skill": "nav.move", "args": {"distance": 1.0}}]
# The model time-out, the longest llm.timeout allows: far beyond SAFETY, so a mission that ends
# while the server holds its request ended because of the press, never by waiting it out.
PATIENT = 600.0
SAFETY = 120.0  # seconds: bounds a hung test (a loaded machine is slow), never what is asserted


def until(check: Callable[[], Any], what: str) -> None:
    deadline = time.monotonic() + SAFETY
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


@pytest.fixture
def srv() -> Iterator[ScriptedLLM]:
    with ScriptedLLM(models=("test-model",)) as server:
        yield server


def make_agent(srv: ScriptedLLM, data_dir: Any = None, **llm: Any) -> tuple[RobotAgent, SimRobot]:
    memory = {"enabled": data_dir is not None, "data_dir": str(data_dir or "")}
    overrides = {
        "llm": {
            "base_url": srv.url,
            "model": "test-model",
            "max_retries": 2,
            "timeout": PATIENT,
            "hybrid": False,
            **llm,
        },  # the model plans all
        "memory": memory,
    }
    settings = load_config("llamacpp", overrides, environ={})
    robot = SimRobot(time_scale=0.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    agent.initialize()
    return agent, robot


def press_when(srv: ScriptedLLM, requests: int, press: Callable[[], None]) -> threading.Thread:
    """From another thread: once the server holds request number `requests` unanswered (the
    client is waiting on it), press."""

    def wait_then_press() -> None:
        until(
            lambda: len(srv.requests) >= requests and srv.holding() > 0,
            f"the server to hold request {requests}",
        )
        press()

    presser = threading.Thread(target=wait_then_press, daemon=True)
    presser.start()
    return presser


def finish(srv: ScriptedLLM, run: Callable[[], MissionResult]) -> MissionResult:
    """`run()` on a thread of its own, bounded by SAFETY: one still waiting then is waiting on
    the model (PATIENT is longer), which fails the test (and the held requests are let go)."""
    box: list[MissionResult] = []
    thread = threading.Thread(target=lambda: box.append(run()), daemon=True)
    thread.start()
    thread.join(SAFETY)
    if thread.is_alive():
        srv.release()
        pytest.fail(f"the mission still waited on the model {SAFETY:g} s after the press")
    return box[0]


def run_and_press(
    agent: RobotAgent,
    srv: ScriptedLLM,
    requests: int,
    press: str,
    mission: str = "walk forward 1 meter",
) -> MissionResult:
    """The mission, pressed while the server holds request number `requests`; it must have
    ended while the server still held that request."""
    presser = press_when(srv, requests, getattr(agent, press))
    result = finish(srv, lambda: agent.execute_mission(mission))
    assert srv.holding() == 1, "the mission ended only once the model's request had ended"
    presser.join(SAFETY)
    return result


def assert_no_retry(srv: ScriptedLLM, expected: int) -> None:
    """Nothing more reaches the server, also once the abandoned request has ended: the server
    lets go of it (the client sees the connection lost, which a client would retry) and every
    request thread has ended before the requests are counted."""
    srv.release()
    until(
        lambda: (
            srv.holding() == 0
            and not any(t.name == "shadowhound-llm-request" for t in threading.enumerate())
        ),
        "the abandoned request to end",
    )
    assert len(srv.requests) == expected


class Retrying(logging.Handler):
    """Set once the backend says it waits before a retry (the log line it writes then)."""

    def __init__(self) -> None:
        super().__init__()
        self.seen = threading.Event()

    def emit(self, record: logging.LogRecord) -> None:
        if "retrying in" in record.getMessage():
            self.seen.set()


@pytest.mark.parametrize(
    ("press", "reason"), [("cancel", "mission cancelled"), ("estop", "e-stop pressed")]
)
def test_press_while_planning_ends_the_mission_at_once(srv, press, reason):
    agent, robot = make_agent(srv)
    srv.script(hang(), hang(), hang())
    result = run_and_press(agent, srv, 1, press)
    assert result.status.value == "stopped" and not result.success
    assert reason in result.response and result.error
    assert not robot.received_motion
    assert agent.get_diagnostics()["status"] == "stopped"
    assert_no_retry(srv, 1)
    if press == "estop":
        agent.release_estop()
    agent.cleanup()


def test_press_during_the_backoff_before_a_retry_sends_nothing_more(srv, monkeypatch, caplog):
    """The server asks for an hour's wait (allowed here): only the press can end it."""
    monkeypatch.setattr(backend, "_MAX_RETRY_AFTER", 7200.0)
    caplog.set_level(logging.INFO, logger=backend.__name__)
    agent, robot = make_agent(srv)
    srv.script(status(503, retry_after_ms=3_600_000), json_plan(MOVE_1))
    retrying = Retrying()
    logging.getLogger(backend.__name__).addHandler(retrying)
    try:
        presser = threading.Thread(
            target=lambda: retrying.seen.wait(SAFETY) and agent.cancel(), daemon=True
        )
        presser.start()
        result = finish(srv, lambda: agent.execute_mission("walk forward 1 meter"))
    finally:
        logging.getLogger(backend.__name__).removeHandler(retrying)
    assert retrying.seen.is_set() and result.status.value == "stopped"
    assert len(srv.requests) == 1 and not robot.received_motion
    agent.cleanup()


def test_press_during_the_repair_round_trip(srv):
    agent, robot = make_agent(srv)
    srv.script(json_plan([{"skill": "nav.teleport", "args": {}}]), hang())
    result = run_and_press(agent, srv, 2, "cancel")
    assert result.status.value == "stopped"
    assert "mission cancelled" in result.response
    assert not robot.received_motion
    assert_no_retry(srv, 2)
    agent.cleanup()


def test_press_while_re_planning_after_a_failed_step(srv):
    agent, robot = make_agent(srv)
    robot.send_velocity = lambda *a: None  # motors dead: the move stalls and fails
    srv.script(json_plan(MOVE_1), hang())
    result = run_and_press(agent, srv, 2, "cancel")
    assert result.status.value == "stopped", result.response
    assert "mission cancelled" in result.response
    assert [s.status.value for s in result.steps] == ["failed"]
    assert robot.get_state().x == pytest.approx(0.0, abs=1e-6)
    assert_no_retry(srv, 2)
    agent.cleanup()


def test_press_while_react_waits_for_the_next_call(srv):
    agent, robot = make_agent(srv, mode="react")
    srv.script(tool_calls(("nav_move", {"distance": 0.5})), hang())
    result = run_and_press(agent, srv, 2, "estop")
    assert result.status.value == "stopped"
    assert "e-stop pressed" in result.response
    assert [s.status.value for s in result.steps] == ["succeeded"]
    assert robot.get_state().x == pytest.approx(0.5, abs=0.01)  # nothing after the press
    assert_no_retry(srv, 2)
    agent.release_estop()
    agent.cleanup()


def test_press_while_a_vision_step_asks_the_model(srv):
    agent, robot = make_agent(srv, vision=True)
    srv.script(
        json_plan([{"skill": "perception.describe", "args": {"question": "what?"}}, *MOVE_1]),
        hang(),
    )
    result = run_and_press(agent, srv, 2, "cancel", "what do you see, then walk")
    assert result.status.value == "stopped", result.response
    assert [s.status.value for s in result.steps] == ["cancelled", "skipped"]
    assert not robot.received_motion
    assert_no_retry(srv, 2)
    agent.cleanup()


def test_the_stopped_mission_is_in_the_history_and_the_next_one_runs(srv, tmp_path):
    agent, robot = make_agent(srv, data_dir=tmp_path)
    srv.script(hang(), json_plan(MOVE_1))
    stopped = run_and_press(agent, srv, 1, "cancel")
    after = agent.execute_mission("walk forward 1 meter")
    assert after.success, after.response
    assert robot.get_state().x == pytest.approx(1.0, abs=0.01)
    agent.cleanup()
    history = MissionHistory(tmp_path / "history.db")
    record = history.get(stopped.mission_id)
    assert record is not None and record["status"] == "stopped"
    assert "mission cancelled" in record["response"]
    history.close()


@pytest.mark.parametrize("press", ["cancel", "estop"])
def test_a_dry_run_after_a_press_still_asks_the_model(srv, press):
    agent, robot = make_agent(srv)
    srv.script(hang(), json_plan(MOVE_1))
    stopped = run_and_press(agent, srv, 1, press)
    assert stopped.status.value == "stopped"
    dry = agent.dry_run("walk forward 1 meter")  # allowed also while the e-stop is latched
    assert dry.success, dry.response
    assert len(srv.requests) == 2 and not robot.received_motion
    agent.release_estop()
    agent.cleanup()


# -- the retries LLMBackend does itself (so that a cancel can stop them) ---------------------


@pytest.mark.parametrize(
    ("replies", "requests", "success"),
    [
        ([status(401, "bad key"), json_plan(MOVE_1)], 1, False),  # retrying cannot help
        ([status(429, retry_after_ms=10), json_plan(MOVE_1)], 2, True),  # rate limited: wait
        ([status(503, retry_after_ms=61_000), json_plan(MOVE_1)], 1, False),  # too long a wait
        ([drop(), json_plan(MOVE_1)], 2, True),  # the connection was lost: try again
        ([status(500, retry_after_ms=10)] * 3 + [json_plan(MOVE_1)], 3, False),  # 1 + 2 retries
    ],
)
def test_which_failures_are_retried(srv, replies, requests, success):
    agent, robot = make_agent(srv)
    srv.script(*replies)
    result = agent.execute_mission("walk forward 1 meter")
    assert result.success is success, result.response
    assert len(srv.requests) == requests
    assert bool(robot.received_motion) is success
    agent.cleanup()


# -- the whole kind: whichever request the press lands on ------------------------------------

_PLAN_PREFIXES: dict[str, list[Any]] = {
    "plan": [],
    "repair": [json_plan([{"skill": "nav.teleport", "args": {}}])],
    "replan": [json_plan([{"skill": "nav.move", "args": {"distance": 0.5}}])],
}


@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    where=st.sampled_from(["plan", "repair", "replan", "react", "react_later", "vision"]),
    press=st.sampled_from(["cancel", "estop"]),
)
def test_any_press_on_any_model_request_stops_the_mission(srv, where, press):
    srv.clear()
    srv.requests.clear()
    mode = "react" if where.startswith("react") else "plan"
    agent, robot = make_agent(srv, mode=mode, vision=where == "vision")
    if where == "replan":
        robot.send_velocity = lambda *a: None
    prefix = {
        "react": [],
        "react_later": [tool_calls(("nav_move", {"distance": 0.3}))],
        "vision": [json_plan([{"skill": "perception.describe", "args": {}}, *MOVE_1])],
    }.get(where) or _PLAN_PREFIXES.get(where, [])
    srv.script(*prefix, hang(), text("never read"))
    pose: list[Any] = []
    presser = press_when(
        srv, len(prefix) + 1, lambda: (pose.append(robot.get_state()), getattr(agent, press)())
    )
    result = finish(srv, lambda: agent.execute_mission("walk forward 1 meter"))
    assert srv.holding() == 1  # it ended while the model still held the request
    presser.join(SAFETY)
    assert result.status.value == "stopped", (where, result.response)
    assert_no_retry(srv, len(prefix) + 1)  # nothing sent after the press
    end = robot.get_state()
    assert (end.x, end.y) == pytest.approx((pose[0].x, pose[0].y), abs=1e-6)
    agent.release_estop()
    agent.cleanup()
