"""The node's start-up and shutdown as a process: bad parameters exit 2 with a clear message;
SIGINT and SIGTERM stop the robot and exit 0, also in the middle of a mission."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces")

from std_msgs.msg import String  # noqa: E402

from tests.ros.rosclient import ROOT, Agent, NodeProcess, RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


BAD = {
    "several": (
        [
            "-p",
            "web_interface_port:=70000",
            "-p",
            "time_scale:=fast",
            "-p",
            "camera_type:=jpeg",
            "-p",
            "enable_web_ui:=maybe",
        ],
        [
            "web_interface_port must be in 1..65535, got 70000",
            "time_scale must be a number, got str 'fast'",
            "camera_type must be one of auto, raw, compressed, got 'jpeg'",
            "enable_web_ui must be true or false, got str 'maybe'",
        ],
    ),
    "go2": (
        ["-p", "robot:=go2", "-p", "odom_timeout:=0.0"],
        ["odom_timeout must be a number of seconds in 0.05..10, got 0.0"],
    ),
    "profile": (
        ["-p", "backend_config:=no_such_profile"],
        ["unknown config profile 'no_such_profile'", "available profiles: "],
    ),
    "port type": (
        ["-p", "web_interface_port:=80.5"],
        ["web_interface_port must be an integer, got float 80.5"],
    ),
    "unknown": (["-p", "web_port:=8080"], ["unknown ROS parameter(s): web_port"]),
    "topic": (
        ["-p", "mission_topic:=9 bad topic"],
        ["mission_topic '9 bad topic' is not a valid ROS topic name"],
    ),
}


def test_invalid_parameters_are_rejected_at_start_up_with_exit_code_2() -> None:
    procs = {
        name: subprocess.Popen(
            [sys.executable, "-m", "shadowhound", "node", "--ros-args", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=ROOT,
        )
        for name, (args, _expected) in BAD.items()
    }
    for name, proc in procs.items():
        _out, err = proc.communicate(timeout=60)
        assert proc.returncode == 2, (name, err)
        for expected in BAD[name][1]:
            assert expected in err, (name, expected, err)
        assert "Traceback" not in err, err


def test_stray_arguments_and_help() -> None:
    stray = subprocess.run(
        [sys.executable, "-m", "shadowhound", "node", "--port", "1"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert stray.returncode == 2 and "--ros-args -p NAME:=VALUE" in stray.stderr
    helped = subprocess.run(
        [sys.executable, "-m", "shadowhound", "node", "--help"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert helped.returncode == 0 and "web_interface_port (default 8080)" in helped.stdout


def test_sigint_and_sigterm_stop_the_robot_and_exit_0() -> None:
    client = RosClient("shadowhound_lifecycle_client")
    runs = {}
    try:
        ports = {}
        for sig, ns in ((signal.SIGINT, "/int"), (signal.SIGTERM, "/term")):
            ports[sig] = free_port()
            process = NodeProcess(
                "-r",
                f"__ns:={ns}",
                "-p",
                f"diagnostics_topic:={ns}/diagnostics",
                "-p",
                f"robot_status_topic:={ns}/robot_status",
                "-p",
                "enable_web_ui:=true",
                "-p",
                f"web_interface_port:={ports[sig]}",
            )
            runs[sig] = (process, Agent(client, ns))
        for sig, (process, agent) in runs.items():
            agent.wait_ready(process)
            agent.missions.publish(String(data="walk backward 3 meters"))
            wait_until(lambda a=agent: a.robot_state()["moving"], 30, "the robot to move")
            mark = agent.status.mark()
            assert process.stop(sig) == 0, process.output()
            final = agent.status.wait_for(
                lambda m: m.data.startswith("FAILED"), 10, "the mission's last status", mark
            )
            assert final.data.startswith(
                "FAILED: Stopped at step 1 (nav.move): mission cancelled"
            ), final.data
            log = process.output()
            assert "shutting down: cancelling the mission and stopping the robot" in log, log
            assert f"web dashboard on http://127.0.0.1:{ports[sig]}" in log, log
            assert "Traceback" not in log, log
    finally:
        for process, _agent in runs.values():
            if process.proc.poll() is None:
                process.proc.kill()
        client.close()
