"""The dashboard when odometry lies: one NaN in the robot's pose must not freeze the page.

The robot is a real SimRobot whose pose, as the agent reads it, has x = NaN and yaw = inf
(tests/lying_odometry.py). The page reads every message with JSON.parse, which refuses NaN;
these read them as strictly, from the API, the WebSocket and server-sent events.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig
from tests.lying_odometry import LyingOdometry
from tests.strict_json import strict_loads
from tests.web.conftest import SAFETY, TOKEN, wait_for


@pytest.fixture
def lying() -> Iterator[RobotAgent]:
    agent = RobotAgent(
        RobotAgentConfig(
            robot=LyingOdometry(x=math.nan, yaw=math.inf), settings=ShadowHoundConfig()
        )
    )
    agent.initialize()
    yield agent
    agent.cleanup()


def _robot_is_reported_unknown(robot: dict[str, Any]) -> None:
    assert robot["x"] is None and robot["yaw"] is None and robot["yaw_deg"] is None
    assert robot["y"] == 0.0 and robot["posture"] in ("standing", "sitting")  # still said


@pytest.mark.parametrize("path", ["/api/status", "/api/diagnostics", "/api/map"])
def test_the_api_answers_strict_json_with_null_for_what_is_not_finite(
    lying: RobotAgent, path: str
) -> None:
    from fastapi.testclient import TestClient

    from shadowhound.web import create_app

    with TestClient(create_app(lying), base_url="http://127.0.0.1") as client:
        reply = client.get(path)
    assert reply.status_code == 200, reply.text  # not a 500 from the JSON encoder
    answer = strict_loads(reply.content)
    assert isinstance(answer, dict)
    _robot_is_reported_unknown(answer["robot"])


def test_the_apps_own_json_answers_are_strict() -> None:
    """Refusals and error handlers answer with StrictJSON, the app's default response class:
    Starlette's JSONResponse would raise on NaN (a 500) where this writes null."""
    from starlette.responses import JSONResponse

    from shadowhound.web.responses import StrictJSON

    content = {"robot": {"x": math.nan, "y": 1.5}, "path": [(math.inf, 0.0)]}
    with pytest.raises(ValueError):
        JSONResponse(content)
    assert strict_loads(StrictJSON(content).body) == {
        "robot": {"x": None, "y": 1.5},
        "path": [[None, 0.0]],
    }


def test_estop_answers_strict_json_too(lying: RobotAgent) -> None:
    from fastapi.testclient import TestClient

    from shadowhound.web import create_app

    with TestClient(create_app(lying), base_url="http://127.0.0.1") as client:
        reply = client.post("/api/estop")
        assert reply.status_code == 200, reply.text
        answer = strict_loads(reply.content)
        assert isinstance(answer, dict) and answer["estop"] is True
        _robot_is_reported_unknown(answer["robot"])
        client.post("/api/estop/release")


def test_the_websocket_feed_stays_strict_json_through_a_mission(lying: RobotAgent) -> None:
    from fastapi.testclient import TestClient

    from shadowhound.web import create_app

    app = create_app(lying, token=TOKEN)
    headers = {"Authorization": f"Bearer {TOKEN}"}
    with (
        TestClient(app, base_url="http://127.0.0.1") as client,
        client.websocket_connect(
            "/ws/status", subprotocols=["shadowhound", f"bearer.{TOKEN}"]
        ) as ws,
    ):
        snapshot = strict_loads(ws.receive_text())
        assert isinstance(snapshot, dict) and snapshot["kind"] == "snapshot"
        _robot_is_reported_unknown(snapshot["status"]["robot"])
        reply = client.post("/api/mission", json={"command": "sit down"}, headers=headers)
        assert reply.status_code == 202, reply.text
        seen = []
        while not seen or seen[-1]["kind"] != "mission_record":
            message = strict_loads(ws.receive_text())
            assert isinstance(message, dict)
            seen.append(message)
    record = seen[-1]
    assert record["success"] is True, record
    _robot_is_reported_unknown(record["result"]["robot"])
    states = [m for m in seen if m["kind"] == "state"]
    for state in states:
        _robot_is_reported_unknown(state["robot"])


def test_server_sent_events_stay_strict_json(lying: RobotAgent, serve: Any) -> None:
    import httpx

    # A real server: Starlette's TestClient before 1.8 (what Python 3.10 gets) reads a whole
    # response before it returns, and an event stream never ends (the test hung there).
    with httpx.Client(base_url=serve(lying).url, timeout=SAFETY) as client:
        client.post("/api/mission", json={"command": "sit down"})

        def record() -> Any:
            missions = client.get("/api/missions").json()["missions"]
            return missions and missions[0]["state"] == "finished"

        wait_for(record, what="the mission to finish")
        with client.stream("GET", "/api/events?since=0") as stream:
            messages = []
            for line in stream.iter_lines():
                if line.startswith("data: "):
                    messages.append(strict_loads(line[6:]))
                    if messages[-1]["kind"] == "mission_record":  # type: ignore[index]
                        break
    assert messages[0]["kind"] == "snapshot"  # type: ignore[index]
    _robot_is_reported_unknown(messages[0]["status"]["robot"])  # type: ignore[index]
    _robot_is_reported_unknown(messages[-1]["result"]["robot"])  # type: ignore[index]
