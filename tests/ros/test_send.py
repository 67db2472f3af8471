"""`shadowhound send`, `estop` and `sim-fault`: the command line talking to real node processes
over real DDS (loopback only), as a robot owner does from the venv without the `ros2` command.

One `shadowhound node` (simulated robot in real time) and one `shadowhound sim-driver` serve
the module; each command runs as a process of its own. Skipped without rclpy or the interface
package unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces")

from std_msgs.msg import String  # noqa: E402

from tests.ros.rosclient import ROOT, Agent, NodeProcess, RosClient, wait_until  # noqa: E402

TIMEOUT = 60.0
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


def shadowhound(*args: str, timeout: float = TIMEOUT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
    )


def start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "shadowhound", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )


def until_line(proc: subprocess.Popen[str], text: str) -> list[str]:
    """Lines of the process's stderr up to the first that holds `text`."""
    assert proc.stderr is not None
    seen = []
    for line in proc.stderr:
        seen.append(line)
        if text in line:
            return seen
    raise AssertionError(f"no {text!r} on stderr: {''.join(seen)}")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient()
    yield c
    c.close()


@pytest.fixture(scope="module")
def node(client: RosClient) -> Iterator[Agent]:
    process = NodeProcess("-p", "time_scale:=1.0")
    agent = Agent(client)
    try:
        agent.wait_ready(process)
        yield agent
        process.check_alive()
    finally:
        code = process.stop(signal.SIGINT)
    assert code == 0, process.output()[-2000:]


def test_send_runs_a_mission_by_the_action_and_follows_it_to_its_end(node: Agent) -> None:
    before = node.robot_state()
    proc = shadowhound("send", "stand up, walk forward 0.5 meters then turn left 90 degrees")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("Done: already standing; moved 0.50 m forward; turned 90.0")
    lines = proc.stderr.splitlines()
    assert lines[0] == (
        "mission: 'stand up, walk forward 0.5 meters then turn left 90 degrees' -> "
        "/execute_mission (action)"
    )
    assert "plan: 3 step(s)" in lines
    assert "  [2/3] nav.move ..." in lines, lines
    assert any(line.startswith("  [3/3] nav.rotate done (100% ") for line in lines), lines
    after = node.robot_state()
    assert after["distance_travelled"] - before["distance_travelled"] == pytest.approx(
        0.5, abs=0.05
    )


def test_a_failed_mission_exits_1_with_the_node_s_answer(node: Agent) -> None:
    proc = shadowhound("send", "-q", "blorp the zanzibar")
    assert proc.returncode == 1, proc.stderr
    assert "did not understand" in proc.stdout and proc.stderr == ""


def test_send_by_the_topic_prints_each_status_line(node: Agent) -> None:
    proc = shadowhound("send", "--topic", "turn right 45 degrees")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.splitlines()
    assert lines[0] == "mission: 'turn right 45 degrees' -> /mission_command (topic)"
    assert "status: EXECUTING: turn right 45 degrees" in lines, lines
    assert any(line.startswith("status: COMPLETED: Done: turned 45.0") for line in lines), lines
    assert proc.stdout.startswith("Done: turned 45.0 degrees right")


def test_without_a_node_send_says_what_to_compare_and_exits_2() -> None:
    proc = shadowhound("send", "--namespace", "/nobody", "--wait", "1", "stand up")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "no mission node answers at /nobody/mission_command after 1 s" in proc.stderr
    assert f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']}" in proc.stderr


def test_ctrl_c_cancels_the_mission_and_the_robot_stops(node: Agent) -> None:
    proc = start("send", "walk backward 2 meters")
    until_line(proc, "[1/1] nav.move ...")
    wait_until(lambda: node.robot_state()["moving"], TIMEOUT, "the robot to walk")
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=TIMEOUT)
    assert proc.returncode == 130, err
    assert "interrupted: cancelling the mission (the robot stops)" in err
    assert "cancelled" in out, out
    wait_until(lambda: not node.robot_state()["moving"], 5.0, "the robot to stop")


def test_timeout_cancels_the_mission_and_exits_1(node: Agent) -> None:
    proc = shadowhound("send", "--timeout", "1", "-q", "walk forward 2 meters")
    assert proc.returncode == 1, proc.stderr
    assert "no end after 1 s (--timeout): cancelling the mission" in proc.stderr
    assert "cancelled" in proc.stdout
    wait_until(lambda: not node.robot_state()["moving"], 5.0, "the robot to stop")


def test_estop_stops_a_walking_mission_and_release_lets_missions_run_again(node: Agent) -> None:
    # 20 s at 0.1 m/s: the e-stop lands mid-walk however long `shadowhound estop` takes to start
    # on a loaded machine (2 m at the default speed ended before it, in CI)
    walking = start("send", "walk backward 2 meters at 0.1 m/s")
    until_line(walking, "[1/1] nav.move ...")
    wait_until(lambda: node.robot_state()["moving"], TIMEOUT, "the robot to walk")
    pressed = shadowhound("estop")
    assert pressed.returncode == 0, pressed.stderr
    assert pressed.stdout.startswith("e-stop pressed: 1 subscriber(s) of /shadowhound/estop")
    out, _err = walking.communicate(timeout=TIMEOUT)
    assert walking.returncode == 1 and "e-stop" in out, out
    wait_until(lambda: node.robot_state()["estopped"], 5.0, "the e-stop to latch")
    refused = shadowhound("send", "-q", "turn left 10 degrees")
    assert refused.returncode == 1 and "e-stop" in refused.stdout, refused.stdout
    released = shadowhound("estop", "--release")
    assert released.returncode == 0, released.stderr
    assert released.stdout.startswith("e-stop released: 1 subscriber(s)")
    wait_until(lambda: not node.robot_state()["estopped"], 5.0, "the e-stop to be released")
    assert shadowhound("send", "-q", "walk forward 1 meter").returncode == 0


# -- sim-fault ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def driver(client: RosClient) -> Iterator[object]:
    process = NodeProcess(command="sim-driver")
    truth = client.subscribe(String, "/sim_driver/truth")
    try:
        wait_until(lambda: (process.check_alive(), truth.items)[1], TIMEOUT, "the driver's truth")
        yield truth
    finally:
        process.stop(signal.SIGINT)


def test_sim_fault_sets_the_driver_s_faults(driver) -> None:
    proc = shadowhound("sim-fault", '{"odom": false, "delay_ms": 200}')
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == 'fault set on /sim_driver/fault: {"odom": false, "delay_ms": 200}'

    def faults() -> dict:
        return json.loads(driver.items[-1].data)["faults"]

    wait_until(lambda: faults().get("odom") is False, 5.0, "the fault in the truth")
    assert faults()["delay_ms"] == 200
    assert shadowhound("sim-fault", "{}").returncode == 0
    wait_until(lambda: faults().get("odom") is not False, 5.0, "the faults cleared")


def test_sim_fault_refuses_what_is_not_a_json_object() -> None:
    proc = shadowhound("sim-fault", "odom off")
    assert proc.returncode == 2 and "give a JSON object such as" in proc.stderr
