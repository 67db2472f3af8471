"""On the web, a model reply nested 3,000 deep (a real model server stand-in, a real uvicorn
server) ends the mission failed with the reason, not `dropped` with no result; the history
database keeps it failed, and a fresh start finds no mission left running."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import httpx

from shadowhound.memory import MissionHistory
from shadowhound.web import WebServer
from tests.llm_server import ScriptedLLM, text
from tests.test_planner_crash import DEEP_PLAN, NESTS
from tests.web.conftest import finished, make_agent


def test_a_reply_nested_3000_deep_ends_the_web_mission_failed_with_the_reason(
    serve: Callable[..., WebServer], tmp_path: Path
) -> None:
    with ScriptedLLM(models=("test-model",)) as srv:
        agent = make_agent(
            backend="llamacpp",
            llm={
                "base_url": srv.url,
                "model": "test-model",
                "max_retries": 0,
                "check_on_start": False,
                "hybrid": False,
            },
            memory={"enabled": True, "data_dir": str(tmp_path)},
        )
        server = serve(agent)
        srv.script(text(DEEP_PLAN), text(DEEP_PLAN))  # the reply and the repair turn's
        with httpx.Client(base_url=server.url, timeout=10) as client:
            sent = client.post("/api/mission", json={"command": "walk forward 1 meter"})
            record = finished(client, sent.json()["mission_id"], timeout=30)
    assert record["state"] == "finished" and record["status"] == "failed", record
    assert record["success"] is False and NESTS in record["error"], record
    assert record["result"] is not None and NESTS in record["result"]["response"]
    assert agent.get_robot_state().distance_travelled == 0
    history = MissionHistory(tmp_path / "history.db")  # a fresh start of the same home
    try:
        assert history.interrupted == 0
        row = history.get(record["mission_id"])
        assert row is not None and row["status"] == "failed" and NESTS in row["response"]
    finally:
        history.close()
