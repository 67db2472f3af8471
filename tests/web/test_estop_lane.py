"""The e-stop is never queued behind the event fan-out, however many clients listen.

The app runs in-process under asyncio, spoken to through ASGI as uvicorn does (a request task is
created when its bytes arrive). Hundreds of event-stream clients are connected; the e-stop
request arrives while an event is being fanned out to them. The order of what happened (ground
truth from the simulated robot and each client's writes) shows whether the robot stopped
before or after the fan-out reached everybody.
"""

from __future__ import annotations

import asyncio
from typing import Any

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.web import create_app

CLIENTS = 300


class WatchedRobot(SimRobot):
    """The simulator, noting in a shared log when its hard stop is called."""

    def __init__(self, log: list[str], config: Any) -> None:
        super().__init__(config, time_scale=0.0)
        self.log = log

    def emergency_stop(self) -> None:
        super().emergency_stop()
        self.log.append("robot stopped")


def _scope(method: str, path: str) -> dict[str, Any]:
    return {
        "type": "http",
        "asgi": {"version": "3.0"},
        "http_version": "1.1",
        "method": method,
        "path": path,
        "raw_path": path.encode(),
        "root_path": "",
        "query_string": b"",
        "scheme": "http",
        "server": ("127.0.0.1", 80),
        "client": ("127.0.0.1", 40000),
        "headers": [(b"host", b"127.0.0.1"), (b"content-length", b"0")],
    }


def test_estop_reaches_the_robot_before_an_event_reaches_hundreds_of_clients() -> None:
    log: list[str] = []
    settings = ShadowHoundConfig()
    agent = RobotAgent(RobotAgentConfig(robot=WatchedRobot(log, settings.sim), settings=settings))
    app = create_app(agent)
    feed = app.state.web.feed
    answers: list[dict[str, Any]] = []

    async def run() -> None:
        loop = asyncio.get_running_loop()
        gone = asyncio.Event()
        snapshots: list[dict[str, Any]] = []
        estop_tasks: list[asyncio.Task[None]] = []

        async def receive_nothing() -> dict[str, Any]:
            await gone.wait()
            return {"type": "http.disconnect"}

        async def receive_empty() -> dict[str, Any]:
            return {"type": "http.request", "body": b"", "more_body": False}

        async def answer(message: dict[str, Any]) -> None:
            answers.append(message)

        async def client_send(message: dict[str, Any]) -> None:
            if message["type"] == "http.response.body" and b'"kind":"snapshot"' in message.get(
                "body", b""
            ):
                snapshots.append(message)
            if message["type"] == "http.response.body" and b'"kind":"step"' in message.get(
                "body", b""
            ):
                log.append("client got the event")
                if not estop_tasks:  # the e-stop's bytes arrive during the fan-out
                    estop_tasks.append(
                        loop.create_task(app(_scope("POST", "/api/estop"), receive_empty, answer))
                    )

        clients = [
            loop.create_task(app(_scope("GET", "/api/events"), receive_nothing, client_send))
            for _ in range(CLIENTS)
        ]
        while len(snapshots) < CLIENTS:  # every client has written its snapshot and waits
            await asyncio.sleep(0.01)
        feed.publish("step", {"n": 1})
        while log.count("client got the event") < CLIENTS or not answers:
            await asyncio.sleep(0.01)
        gone.set()
        await asyncio.gather(*clients, *estop_tasks, return_exceptions=True)

    try:
        asyncio.run(asyncio.wait_for(run(), 60))
    finally:
        agent.cleanup()
    assert answers[0]["status"] == 200
    assert agent.get_robot_state().estopped
    served_first = log.index("robot stopped")
    # The fan-out goes on after the stop (every client still gets the event), but the stop
    # waited for at most a couple of slices of clients, not for all of them.
    assert log.count("client got the event") == CLIENTS
    assert served_first < CLIENTS // 4, f"the e-stop waited for {served_first} clients"
