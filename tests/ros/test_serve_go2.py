"""`shadowhound serve --robot go2`: the dashboard's HTTP API drives a Go2 (issue 25), over DDS,
judged by the simulated driver's ground truth.

The robot is built by the one factory (robot/factory.py) from the profile's settings
(`robot: {type: go2, namespace: served}`), as the ROS node, the MCP server and the CLI build
theirs. `shadowhound sim-driver` plays go2_ros2_sdk's driver under /served.

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import math
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "fastapi")

from tests.ros.rosclient import (  # noqa: E402
    NodeProcess,
    RosClient,
    wait_until,
)
from tests.ros.test_go2_truth import Truth, free_port  # noqa: E402

TIMEOUT = 40.0
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_serve_go2_client")
    yield c
    c.close()


def _up(url: str) -> bool:
    try:
        return httpx.get(url + "/api/health", timeout=1).status_code == 200
    except httpx.TransportError:
        return False


def test_serve_robot_go2_walks_the_driver_from_the_http_api(
    client: RosClient, tmp_path: Path
) -> None:
    driver = NodeProcess(
        "-r", "__ns:=/served", command="sim-driver", options=("--camera-rate-hz", "0")
    )
    truth = Truth(client, "/served")
    profile = tmp_path / "go2.yaml"
    profile.write_text(
        "backend: offline\nrobot:\n  type: go2\n  namespace: served\nmemory:\n  enabled: false\n"
    )
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    log = tmp_path / "serve.log"
    with log.open("w") as out:
        server = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "shadowhound",
                "serve",
                "--robot",
                "go2",
                "--config",
                str(profile),
                "--port",
                str(port),
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    try:
        truth.wait_ready(driver)
        wait_until(lambda: _up(url) or server.poll() is not None, TIMEOUT, "the dashboard to start")
        assert server.poll() is None, log.read_text()
        wait_until(
            lambda: httpx.get(url + "/api/status").json()["robot"]["connected"],
            TIMEOUT,
            "the served Go2 to receive odometry",
        )
        start = truth.now()
        mission = httpx.post(url + "/api/mission", json={"command": "walk forward 1 meter"})
        mission_id = mission.json()["mission_id"]
        wait_until(
            lambda: (
                httpx.get(f"{url}/api/missions/{mission_id}").json()["state"]
                in ("finished", "dropped")  # whatever its status: stopped too
            ),
            TIMEOUT,
            "the mission to end",
        )
        record = httpx.get(f"{url}/api/missions/{mission_id}").json()
        assert record["status"] == "succeeded", (record, log.read_text()[-3000:])
        end = truth.still()
        walked = math.hypot(end["x"] - start["x"], end["y"] - start["y"])
        assert abs(walked - 1.0) < 0.05, (walked, start, end)
    finally:
        if server.poll() is None:
            server.send_signal(signal.SIGINT)
            server.wait(15)
        truth.close()
        assert driver.stop(signal.SIGTERM) == 0, driver.output()[-3000:]
    assert server.returncode == 0, log.read_text()[-3000:]
