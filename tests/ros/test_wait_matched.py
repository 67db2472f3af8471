"""`wait_matched` (tests/ros/rosclient.py), the suite's one wait for DDS to connect a test with
another process: it waits for both sides of every match (issue 22: a readiness check that
counted only this side let the node's first status line go out before the node's writer had
matched the test's reader, and the line was lost). Skipped without rclpy or the interface
package unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails)."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces")

from std_msgs.msg import String  # noqa: E402

from tests.ros.rosclient import Agent, NodeProcess, RosClient, wait_matched, wait_until  # noqa: E402

NS = "/fresh"
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_wait_matched_client")
    yield c
    c.close()


@pytest.fixture(scope="module")
def node() -> Iterator[NodeProcess]:
    process = NodeProcess(
        "-r",
        f"__ns:={NS}",
        "-p",
        f"diagnostics_topic:={NS}/diagnostics",
        "-p",
        f"robot_status_topic:={NS}/robot_status",
        "-p",
        "time_scale:=0.0",
    )
    yield process
    os.kill(process.proc.pid, signal.SIGCONT)
    assert process.stop() == 0, process.output()[-2000:]


def state(process: NodeProcess) -> str:
    """The process's state letter in /proc (T: stopped)."""
    stat = Path(f"/proc/{process.proc.pid}/stat").read_text()
    return stat.rsplit(")", 1)[1].split()[0]


def test_ready_waits_for_the_nodes_side_of_the_match(client: RosClient, node: NodeProcess) -> None:
    """Readers and writers made while the node is stopped (SIGSTOP): this side matches them at
    once (it knows the node's endpoints), the node cannot. Ready must not pass until the node
    runs again and has matched them; then the first status line arrives."""
    first = Agent(client, NS)
    first.wait_ready(node)  # the node is up and this client knows its endpoints
    first.close()
    os.kill(node.proc.pid, signal.SIGSTOP)
    try:
        wait_until(lambda: state(node) == "T", 10, "the node to stop")
        agent = Agent(client, NS)
        with pytest.raises(AssertionError, match="timed out"):
            agent.wait_ready(node, timeout=3.0)
    finally:
        os.kill(node.proc.pid, signal.SIGCONT)
    agent.wait_ready(node)
    mark = agent.status.mark()
    agent.missions.publish(String(data="   "))
    agent.status.wait_for(
        lambda m: m.data.startswith("FAILED: Refused: the mission is empty"),
        10.0,
        "the answer to the first mission once ready",
        mark,
    )
    agent.close()


def test_the_proof_is_the_reader_made_last_and_the_only_one_on_its_topic(
    client: RosClient,
) -> None:
    first = client.subscribe(String, "/wait_matched/first")
    second = client.subscribe(String, "/wait_matched/second")
    writer = client.publisher(String, "/wait_matched/commands")
    try:
        with pytest.raises(AssertionError, match="must be the last made"):
            wait_matched(client, "readers out of order", [second, first], timeout=0.1)
        with pytest.raises(AssertionError, match="writers need a ping"):
            wait_matched(client, "no ping", [first, second], [writer], timeout=0.1)
        again = client.subscribe(String, "/wait_matched/second")
        with pytest.raises(AssertionError, match="has 2 readers of /wait_matched/second"):
            wait_matched(client, "two readers", [first, again], timeout=0.1)
        client.destroy(again)
    finally:
        client.destroy(first, second, writer)
