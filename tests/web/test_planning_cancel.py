"""Against a real uvicorn server and a real model server that never answers: cancelling (or the
e-stop) on the web ends a mission that waits on the model at once, records it as stopped, and
the next queued mission runs."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest

from shadowhound.memory import MissionHistory
from shadowhound.web import WebServer
from tests.llm_server import ScriptedLLM, hang, json_plan
from tests.web.conftest import SAFETY, finished, make_agent, wait_for

Serve = Callable[..., WebServer]
MOVE_1 = [{"skill": "nav.move", "args": {"distance": 1.0}}]
# The model time-out, the longest llm.timeout allows (the defect waited it out, 3 tries): far
# beyond SAFETY, so a mission that ended while the server still held its request ended because
# of the press.
PATIENT = 600


@pytest.fixture
def srv() -> Iterator[ScriptedLLM]:
    with ScriptedLLM(models=("test-model",)) as server:
        yield server


def llm_agent(srv: ScriptedLLM, data_dir: Path):  # noqa: ANN201 - a RobotAgent
    return make_agent(
        backend="llamacpp",
        llm={
            "base_url": srv.url,
            "model": "test-model",
            "timeout": PATIENT,
            "max_retries": 2,
            "check_on_start": False,
            "hybrid": False,
        },
        memory={"enabled": True, "data_dir": str(data_dir)},
    )


def test_cancel_on_the_web_ends_planning_and_the_queue_moves_on(serve: Serve, srv, tmp_path):
    agent = llm_agent(srv, tmp_path)
    server = serve(agent)
    srv.script(hang(), json_plan(MOVE_1))
    with httpx.Client(base_url=server.url, timeout=SAFETY) as client:
        first = client.post("/api/mission", json={"command": "walk forward 2 meters"}).json()
        second = client.post("/api/mission", json={"command": "walk forward 1 meter"}).json()
        wait_for(lambda: srv.holding() == 1, what="the model to be asked")
        assert client.get("/api/status").json()["status"] == "planning"
        reader = MissionHistory(tmp_path / "history.db")  # on record from acceptance
        assert reader.get(first["mission_id"])["status"] == "running"
        assert reader.get(second["mission_id"])["status"] == "queued"
        reader.close()
        cancelled = client.post(f"/api/missions/{first['mission_id']}/cancel").json()
        assert cancelled["cancelled"] is True
        record = finished(client, first["mission_id"])
        assert srv.holding() == 1  # it ended while the model still held the request
        assert record["status"] == "stopped" and "mission cancelled" in record["response"]
        after = finished(client, second["mission_id"])
        assert after["status"] == "succeeded", after
        assert agent.get_robot_state().x == pytest.approx(1.0, abs=0.01)  # only the second
    assert_no_retry(srv, 2)
    history = MissionHistory(tmp_path / "history.db")
    assert history.get(first["mission_id"])["status"] == "stopped"
    assert history.get(second["mission_id"])["status"] == "succeeded"
    history.close()


def test_estop_on_the_web_ends_planning(serve: Serve, srv, tmp_path):
    agent = llm_agent(srv, tmp_path)
    server = serve(agent)
    srv.script(hang())
    with httpx.Client(base_url=server.url, timeout=SAFETY) as client:
        first = client.post("/api/mission", json={"command": "walk forward 2 meters"}).json()
        queued = client.post("/api/mission", json={"command": "walk forward 1 meter"}).json()
        wait_for(lambda: srv.holding() == 1, what="the model to be asked")
        assert client.post("/api/estop").json()["dropped"] == 1
        record = finished(client, first["mission_id"])
        assert srv.holding() == 1  # it ended while the model still held the request
        assert record["status"] == "stopped" and "e-stop" in record["response"]
        assert finished(client, queued["mission_id"])["state"] == "dropped"
        assert not agent.robot.received_motion
        client.post("/api/estop/release")
    assert_no_retry(srv, 1)


def assert_no_retry(srv: ScriptedLLM, expected: int) -> None:
    """Nothing more reaches the model once the abandoned request has ended: the server lets go
    of it (a lost connection, which a client would retry) and every request thread ends first."""
    srv.release()
    wait_for(
        lambda: (
            srv.holding() == 0
            and not any(t.name == "shadowhound-llm-request" for t in threading.enumerate())
        ),
        what="the abandoned request to end",
    )
    assert len(srv.requests) == expected
