"""`serve_main` (what `shadowhound serve` calls) as a process: it serves the page on loopback,
runs a mission on the real-time simulator, and stops cleanly on Ctrl-C and SIGTERM."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys

import httpx
import pytest

from tests.web.conftest import wait_for

SCRIPT = ("import sys; from shadowhound import load_config; from shadowhound.web import "
          "serve_main; sys.exit(serve_main(load_config('offline', {'sim': {'time_scale': 0.1}}),"
          " '127.0.0.1', int(sys.argv[1])))")


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def _up(url: str) -> bool:
    try:
        return httpx.get(url + "/api/health", timeout=1).status_code == 200
    except httpx.TransportError:
        return False


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_serve_runs_the_dashboard_and_stops_cleanly(stop: signal.Signals) -> None:
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    process = subprocess.Popen([sys.executable, "-c", SCRIPT, str(port)],
                               stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: _up(url) or process.poll() is not None, 30, "the server to start")
        assert process.poll() is None, process.stderr.read() if process.stderr else ""
        assert 'id="estop"' in httpx.get(url + "/").text
        mission = httpx.post(url + "/api/mission", json={"command": "turn left 45 degrees"})
        mission_id = mission.json()["mission_id"]
        wait_for(lambda: httpx.get(f"{url}/api/missions/{mission_id}").json()["status"]
                 == "succeeded", 20, "the mission to succeed")
        process.send_signal(stop)
        assert process.wait(15) == 0
        assert process.stderr is not None
        err = process.stderr.read()
        assert "ShadowHound dashboard on http://127.0.0.1" in err and "stopped" in err
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(5)
