"""A client that goes away mid-mission stops its mission and the robot, in every protocol version,
with and without a progress token: over Streamable HTTP (a call's stream dropped; a session's
client vanishing) and over stdio (stdin closed). Raw sockets and pipes, so the drop happens
exactly when the test says; the server is `shadowhound mcp` in its own process with the
simulated robot in real time, judged by the robot's own state (get_state reads the SimRobot)."""

from __future__ import annotations

import json
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest

from .conftest import HttpServer, server_command, server_env
from .wire import ALL_VERSIONS, HANDSHAKE_VERSIONS, MODERN, Caller, Wire

REAL_TIME = 1.0
# 20 s of walking: the robot is still far from the 2 m (under 1 m) when a drop is noticed, on
# any machine; how soon it is noticed is bench_mcp_drop.py's figure.
WALK = {"text": "walk forward 2 meters at 0.1 m/s"}
WAIT = 60.0  # seconds: generous, for a loaded machine; the benchmark measures the latency


def until(check: Callable[[], Any], what: str, timeout: float = WAIT) -> Any:
    """Poll `check` until it returns something true; that value."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if value := check():
            return value
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def robot(server: HttpServer) -> dict[str, Any]:
    """The simulated robot's state and the server's mission state, read without a session."""
    return Wire(server.url, MODERN).call("get_state")


def walking(server: HttpServer) -> dict[str, Any] | None:
    state = robot(server)
    return state if state["robot"]["moving"] and state["robot"]["x"] > 0.05 else None


def still_and_idle(server: HttpServer) -> dict[str, Any] | None:
    state = robot(server)
    return state if not state["robot"]["moving"] and not state["busy"] else None


def last_mission(server: HttpServer) -> dict[str, Any]:
    return dict(Wire(server.url, MODERN).call("history", {"limit": 1})["missions"][0])


def assert_stopped_short(server: HttpServer) -> None:
    state = until(lambda: still_and_idle(server), "the robot to stop")
    assert state["robot"]["x"] < 1.0, state  # far from the 2 m asked
    mission = last_mission(server)
    assert mission["mission"] == WALK["text"] and mission["status"] == "stopped", mission


# -- Streamable HTTP -----------------------------------------------------------------------------


@pytest.mark.parametrize("progress", [True, False], ids=["progress", "no-progress"])
@pytest.mark.parametrize("version", ALL_VERSIONS)
def test_a_dropped_call_stream_stops_the_mission(version, progress, http_server):
    server = http_server(time_scale=REAL_TIME)
    client = Wire(server.url, version)
    client.initialize()
    call = client.open(client.tool_call("run_mission", WALK, progress=progress))
    if progress:
        call.wait_for(b"nav.move")
    until(lambda: walking(server), "the robot to walk")
    call.close()
    assert_stopped_short(server)


@pytest.mark.parametrize("version", HANDSHAKE_VERSIONS)
def test_a_session_whose_client_vanishes_stops_its_mission_and_closes(version, http_server):
    server = http_server("-v", time_scale=REAL_TIME)
    client = Wire(server.url, version)
    client.initialize()
    listening = client.open_get_stream()
    call = client.open(client.tool_call("run_mission", WALK, progress=True))
    call.wait_for(b"nav.move")
    until(lambda: walking(server), "the robot to walk")
    call.close()  # the client's process ends: every connection drops
    listening.close()
    assert_stopped_short(server)
    server.wait_for_log("closed: its client dropped the connection")
    assert client.send(client.tool_call("get_state", {})).status == 404


def test_a_dropped_call_of_a_listening_client_stops_only_that_call(http_server):
    server = http_server(time_scale=REAL_TIME)
    client = Wire(server.url, "2025-11-25")
    client.initialize()
    listening = client.open_get_stream()  # the client is still there, listening
    call = client.open(client.tool_call("run_mission", WALK))
    until(lambda: walking(server), "the robot to walk")
    call.close()
    assert_stopped_short(server)
    assert client.call("get_state")["busy"] is False  # its session lives on
    listening.close()


def test_an_sdk_client_killed_mid_mission_stops_the_robot(http_server):
    """The official SDK's client, handshake era (a GET stream, pooled connections), killed."""
    server = http_server(time_scale=REAL_TIME)
    script = f"""
import asyncio
from mcp import Client

async def main():
    async def progress(done, total, message):
        print(message, flush=True)
    async with Client({server.url!r}, mode="legacy") as client:
        await client.call_tool("run_mission", {WALK!r}, progress_callback=progress)

asyncio.run(main())
"""
    proc = subprocess.Popen(
        [sys.executable, "-c", script], env=server_env(), stdout=subprocess.PIPE, text=True
    )
    try:
        assert proc.stdout is not None
        while "nav.move" not in proc.stdout.readline():
            assert proc.poll() is None, "the client ended before the walk"
        until(lambda: walking(server), "the robot to walk")
    finally:
        proc.kill()
        proc.wait()
    assert_stopped_short(server)


# -- stdio ---------------------------------------------------------------------------------------


class StdioClient:
    """`shadowhound mcp` as a child on pipes; its stdout lines read on a thread."""

    def __init__(self, version: str, data_dir: str) -> None:
        self.env = server_env(SHADOWHOUND_MEMORY__DATA_DIR=data_dir)
        self.proc = subprocess.Popen(
            server_command(time_scale=REAL_TIME),
            env=self.env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            bufsize=1,
        )
        self.caller = Caller(version)
        self.lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line)

    def send(self, message: dict[str, Any]) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(message) + "\n")
        self.proc.stdin.flush()

    def answer(self, request: dict[str, Any]) -> dict[str, Any]:
        self.send(request)
        while True:
            message = json.loads(self.lines.get(timeout=WAIT))
            if message.get("id") == request["id"]:
                return dict(message)

    def robot(self) -> dict[str, Any]:
        result = self.answer(self.caller.tool_call("get_state", {}))["result"]
        return dict(result["structuredContent"]["robot"])


def last_record(env: dict[str, str]) -> dict[str, Any]:
    """The full history record of the last mission (`shadowhound history ID --json`); {}
    before the first."""

    def cli(*args: str) -> Any:
        done = subprocess.run(
            [sys.executable, "-m", "shadowhound", "history", *args, "--json"],
            env=env,
            capture_output=True,
            text=True,
            timeout=2 * WAIT,
        )
        return json.loads(done.stdout)

    listing = cli("--limit", "1")
    return dict(cli(listing[0]["id"])) if listing else {}


@pytest.mark.parametrize("progress", [True, False], ids=["progress", "no-progress"])
@pytest.mark.parametrize("version", ALL_VERSIONS)
def test_closing_stdin_mid_mission_stops_the_robot(version, progress, tmp_path):
    client = StdioClient(version, str(tmp_path))
    if not client.caller.modern:
        assert "result" in client.answer(client.caller.initialize_body())
        client.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
    client.send(client.caller.tool_call("run_mission", WALK, progress=progress))
    until(lambda: client.robot()["moving"], "the robot to walk")
    assert client.proc.stdin is not None
    client.proc.stdin.close()  # the client is gone (a desktop client quitting closes the pipe)
    assert client.proc.wait(WAIT) == 0
    mission = last_record(client.env)
    assert mission["mission"] == WALK["text"] and mission["status"] == "stopped", mission
    assert mission["robot"]["x"] < 1.0, mission["robot"]


def test_a_stdio_client_that_closes_stdout_first_stops_the_robot(tmp_path):
    """A killed client's pipes close in any order: a write that finds stdout broken stops the
    mission, and the server ends as when the client leaves (exit 0), not as an error."""
    env = server_env(SHADOWHOUND_MEMORY__DATA_DIR=str(tmp_path))
    proc = subprocess.Popen(
        server_command(time_scale=REAL_TIME),
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        bufsize=1,
    )
    assert proc.stdin is not None and proc.stdout is not None and proc.stderr is not None
    caller = Caller("2025-06-18")
    for message in (
        caller.initialize_body(),
        {"jsonrpc": "2.0", "method": "notifications/initialized"},
        caller.tool_call("run_mission", WALK, progress=True),
    ):
        proc.stdin.write(json.dumps(message) + "\n")
        proc.stdin.flush()
    while "nav.move" not in proc.stdout.readline():
        pass
    proc.stdout.close()
    proc.stdin.write(json.dumps(caller.tool_call("get_state", {})) + "\n")  # its answer finds
    proc.stdin.flush()  # the pipe broken: that alone stops the mission
    until(lambda: last_record(env).get("status") == "stopped", "the mission to stop")
    proc.stdin.close()
    assert proc.wait(WAIT) == 0, proc.stderr.read()[-2000:]
    assert "Traceback" not in proc.stderr.read()
    mission = last_record(env)
    assert mission["status"] == "stopped" and mission["robot"]["x"] < 1.0, mission
