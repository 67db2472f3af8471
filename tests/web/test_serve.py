"""`serve_main` (what `shadowhound serve` calls) as a process: it serves the page on loopback,
runs a mission on the real-time simulator, and stops cleanly on Ctrl-C and SIGTERM."""

from __future__ import annotations

import contextlib
import json
import signal
import socket
import subprocess
import sys
import time

import httpx
import pytest

from tests.web.conftest import SAFETY, wait_for

START = 2 * SAFETY  # a loaded machine starts Python, FastAPI and the simulator slowly

SCRIPT = (
    "import sys; from shadowhound import load_config; from shadowhound.web import "
    "serve_main; sys.exit(serve_main(load_config('offline', {'sim': {'time_scale': 0.1}}),"
    " '127.0.0.1', int(sys.argv[1])))"
)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def _up(url: str) -> bool:
    try:
        return httpx.get(url + "/api/health", timeout=SAFETY).status_code == 200
    except httpx.TransportError:
        return False


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_serve_runs_the_dashboard_and_stops_cleanly(stop: signal.Signals) -> None:
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    process = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, str(port)], stderr=subprocess.PIPE, text=True
    )
    try:
        wait_for(lambda: _up(url) or process.poll() is not None, START, "the server to start")
        assert process.poll() is None, process.stderr.read() if process.stderr else ""
        with httpx.Client(base_url=url, timeout=SAFETY) as client:
            assert 'id="estop"' in client.get("/").text
            mission = client.post("/api/mission", json={"command": "turn left 45 degrees"})
            mission_id = mission.json()["mission_id"]
            wait_for(
                lambda: client.get(f"/api/missions/{mission_id}").json()["status"] == "succeeded",
                what="the mission to succeed",
            )
        process.send_signal(stop)
        assert process.wait(SAFETY) == 0
        assert process.stderr is not None
        err = process.stderr.read()
        assert "ShadowHound dashboard on http://127.0.0.1" in err and "stopped" in err
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(5)


def test_ctrl_c_stops_the_walking_robot_before_the_dashboards_are_disconnected() -> None:
    """The robot's e-stop goes out on a watching dashboard's stream before the server closes
    it: the stop does not wait for the graceful shutdown (which waits for open streams)."""
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    real_time = SCRIPT.replace("'time_scale': 0.1", "'time_scale': 1.0")
    process = subprocess.Popen(
        [sys.executable, "-c", real_time, str(port)], stderr=subprocess.PIPE, text=True
    )
    kinds: list[str] = []
    try:
        wait_for(lambda: _up(url) or process.poll() is not None, START, "the server to start")
        with (
            httpx.Client(base_url=url, timeout=SAFETY) as client,
            client.stream("GET", "/api/events") as stream,
        ):
            # 20 s of walking: the Ctrl-C comes while it walks on any machine.
            client.post("/api/mission", json={"command": "walk backward 2 meters at 0.1 m/s"})
            lines = stream.iter_lines()
            deadline = time.monotonic() + SAFETY
            for line in lines:
                assert time.monotonic() < deadline, "the robot never walked"
                if (
                    line.startswith("data: ")
                    and json.loads(line[6:]).get("kind") == "state"
                    and json.loads(line[6:])["robot"]["moving"]
                ):
                    break
            process.send_signal(signal.SIGINT)
            with contextlib.suppress(httpx.HTTPError):
                for line in lines:
                    if line.startswith("data: "):
                        kinds.append(json.loads(line[6:])["kind"])
        assert process.wait(SAFETY) == 0
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(5)
    assert "estop" in kinds, kinds


def test_serve_takes_its_startup_objects_out_of_the_collectors_full_passes() -> None:
    """A full collection of an unfrozen server heap holds every thread for about 50 ms here
    (no e-stop answered, no control tick); serve freezes what startup built (serving.py)."""
    port = _free_port()
    report = "import atexit, gc; atexit.register(lambda: print('frozen', gc.get_freeze_count()));"
    process = subprocess.Popen(
        [sys.executable, "-c", report + SCRIPT, str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_for(
            lambda: _up(f"http://127.0.0.1:{port}") or process.poll() is not None,
            START,
            "the server to start",
        )
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=SAFETY)
    finally:
        with contextlib.suppress(ProcessLookupError):
            process.kill()
    assert process.returncode == 0, err
    frozen = int(out.split("frozen ")[1].split()[0])
    assert frozen > 10_000, out  # modules, classes, the app and the robot
