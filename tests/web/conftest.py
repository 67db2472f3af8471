"""Fixtures for the web tests: agents on the simulated robot, the app in-process (TestClient)
and the app on a real uvicorn server on a free 127.0.0.1 port."""

from __future__ import annotations

import importlib.util
import math
import os
import time
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot

if TYPE_CHECKING:
    from fastapi.testclient import TestClient

    from shadowhound.web import WebServer

# Without the web extra these tests cannot run: skip the directory locally, fail in CI.
_MISSING = [
    m for m in ("fastapi", "uvicorn", "httpx", "websockets") if importlib.util.find_spec(m) is None
]
if _MISSING:
    if os.environ.get("CI"):
        raise ImportError(
            f"the web tests need {', '.join(_MISSING)} (pip install -e "
            "'.[web,dev]'); CI must run them"
        )
    collect_ignore_glob = ["test_*.py"]

TOKEN = "test-token-0123456789abcdef"
SAFETY = 60.0  # seconds: what a wait allows before it fails; it bounds a hung test, and a loaded
# machine is slow, so no wait asserts how soon something happens (bench/ measures that)


def make_agent(time_scale: float = 0.0, **settings: Any) -> RobotAgent:
    config = ShadowHoundConfig(**settings)
    agent = RobotAgent(
        RobotAgentConfig(robot=SimRobot(config.sim, time_scale=time_scale), settings=config)
    )
    agent.initialize()
    return agent


def wait_for(
    check: Callable[[], Any],
    timeout: float = SAFETY,
    what: str = "condition",
    detail: Callable[[], str] | None = None,
) -> Any:
    """Poll `check` until it returns something truthy; fail after `timeout` seconds (saying
    `detail()` too, when given: what the test could see then)."""
    deadline = time.monotonic() + timeout
    while True:
        value = check()
        if value:
            return value
        if time.monotonic() > deadline:
            seen = f": {detail()}" if detail else ""
            raise AssertionError(f"timed out after {timeout} s waiting for {what}{seen}")
        time.sleep(0.02)


@pytest.fixture
def agent() -> Iterator[RobotAgent]:
    a = make_agent()
    yield a
    a.cleanup()


@pytest.fixture
def client(agent: RobotAgent) -> Iterator[TestClient]:
    from fastapi.testclient import TestClient

    from shadowhound.web import create_app

    with TestClient(create_app(agent), base_url="http://127.0.0.1") as c:
        yield c


@pytest.fixture
def serve() -> Iterator[Callable[..., WebServer]]:
    """Start the app for an agent on a real server: `serve(agent, token=...) -> WebServer`."""
    from shadowhound.web import WebServer, create_app

    servers: list[WebServer] = []

    def start(agent: RobotAgent, **options: Any) -> WebServer:
        server = WebServer(create_app(agent, **options), "127.0.0.1", 0).start()
        servers.append(server)
        return server

    yield start
    for server in servers:
        server.stop()
        server.app.state.web.agent.cleanup()


def finished(client: Any, mission_id: str, timeout: float = SAFETY) -> dict[str, Any]:
    """The mission's record once it has finished (or was dropped)."""

    def done() -> dict[str, Any] | None:
        record = client.get(f"/api/missions/{mission_id}").json()
        return record if record["state"] in ("finished", "dropped") else None

    return wait_for(done, timeout, f"mission {mission_id} to finish")


@pytest.fixture
def heard() -> Iterator[Any]:
    """A scripted OpenAI-compatible transcription server (tests/speech_server.py)."""
    from tests.speech_server import ScriptedTranscriber

    with ScriptedTranscriber() as srv:
        yield srv


def approach(robot: Any, name: str, timeout: float = SAFETY) -> float:
    """While something drives the simulated robot at the object `name`: wait until it has come
    past 1 m and stopped, and return how close its body came to the object (truth), metres."""
    thing = next(o for o in robot.world.objects if o.name == name)
    body = robot.config.body_radius
    closest = math.inf

    def stopped_near() -> bool:
        nonlocal closest
        s = robot.get_state()
        closest = min(closest, math.hypot(thing.x - s.x, thing.y - s.y) - thing.radius - body)
        return bool(s.x > 1.0 and s.vx == 0.0)

    wait_for(stopped_near, timeout, f"the robot to drive up to the {name} and stop")
    return closest
