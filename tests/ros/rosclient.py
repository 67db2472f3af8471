"""Test-side ROS 2 helpers: a client node spinning in a thread, inboxes, node processes.

Imported only after rclpy is known to be importable (see test_mission_node.py).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.action import ActionClient
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from shadowhound_interfaces.action import ExecuteMission
from std_msgs.msg import String

RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
ROOT = Path(__file__).resolve().parents[2]


def wait_until(
    predicate: Callable[[], Any], timeout: float, what: str, interval: float = 0.02
) -> Any:
    """Poll `predicate` until it returns something truthy; fail with `what` after `timeout`."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(interval)


class Inbox:
    """Messages received on one subscription, thread-safe."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._items: list[Any] = []
        self.subscription: Any = None

    def put(self, msg: Any) -> None:
        with self._lock:
            self._items.append(msg)

    @property
    def items(self) -> list[Any]:
        with self._lock:
            return list(self._items)

    def mark(self) -> int:
        """Position to read new messages from (see `since`)."""
        return len(self.items)

    def since(self, mark: int) -> list[Any]:
        return self.items[mark:]

    def latest(self, timeout: float = 10.0, what: str = "a first message") -> Any:
        """The newest message, waiting for the first one if none has arrived yet (DDS
        matches each reader on its own: another topic having delivered proves nothing)."""
        return wait_until(lambda: (self.items or [None])[-1], timeout, what)

    def wait_for(
        self, match: Callable[[Any], bool], timeout: float, what: str, mark: int = 0
    ) -> Any:
        return wait_until(
            lambda: next((m for m in self.since(mark) if match(m)), None), timeout, what
        )


class RosClient:
    """One rclpy node in its own context, spun by a background thread."""

    def __init__(self, name: str = "shadowhound_test_client") -> None:
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # shutting down
                if self.context.ok():
                    raise

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        self._thread.join(2.0)

    def subscribe(self, msg_type: Any, topic: str, qos: Any = RELIABLE) -> Inbox:
        inbox = Inbox()
        inbox.subscription = self.node.create_subscription(msg_type, topic, inbox.put, qos)
        return inbox

    def publisher(self, msg_type: Any, topic: str, qos: Any = RELIABLE) -> Any:
        return self.node.create_publisher(msg_type, topic, qos)

    def action_client(self, name: str) -> ActionClient:
        return ActionClient(self.node, ExecuteMission, name)


class Agent:
    """The topics of one running mission node, seen from the test client."""

    def __init__(self, client: RosClient, ns: str = "") -> None:
        self.client = client
        self.ns = ns
        self.status = client.subscribe(String, f"{ns}/mission_status")
        # A namespaced test node is started with its status topics under its namespace.
        base = ns or "/shadowhound"
        self.diagnostics = client.subscribe(DiagnosticArray, f"{base}/diagnostics")
        self.robot = client.subscribe(String, f"{base}/robot_status")
        self.missions = client.publisher(String, f"{ns}/mission_command")
        self.action = client.action_client(f"{ns}/execute_mission")

    def wait_ready(self, process: NodeProcess, timeout: float = 30.0) -> None:
        def ready() -> bool:
            process.check_alive()
            return (
                self.missions.get_subscription_count() > 0
                and self.status.subscription.get_publisher_count() > 0
                and self.action.server_is_ready()
            )

        wait_until(ready, timeout, f"the mission node {self.ns or '/'} to be discovered")

    def run(self, command: str, timeout: float = 30.0) -> str:
        """Publish a mission; return the COMPLETED/FAILED line that ends it."""
        mark = self.status.mark()
        self.missions.publish(String(data=command))
        self.status.wait_for(
            lambda m: m.data.startswith("EXECUTING: ") or m.data.startswith("FAILED: "),
            timeout,
            f"{command[:40]!r} to start",
            mark,
        )
        done = self.status.wait_for(
            lambda m: m.data.startswith(("COMPLETED: ", "FAILED: ")),
            timeout,
            f"{command[:40]!r} to finish",
            mark,
        )
        return str(done.data)

    def diagnostic(
        self,
        mark: int = 0,
        timeout: float = 5.0,
        match: Callable[[dict[str, str]], bool] = lambda _v: True,
    ) -> tuple[Any, dict[str, str]]:
        """The next diagnostics (from this node) whose key-values satisfy `match`."""

        def ours(msg: Any) -> bool:
            status = msg.status[0]
            values = {kv.key: kv.value for kv in status.values}
            return match(values)

        msg = self.diagnostics.wait_for(ours, timeout, "matching diagnostics", mark)
        return msg.status[0], {kv.key: kv.value for kv in msg.status[0].values}

    def robot_state(self, timeout: float = 5.0) -> dict[str, Any]:
        mark = self.robot.mark()
        return json.loads(self.robot.wait_for(lambda _m: True, timeout, "robot status", mark).data)


class NodeProcess:
    """`python -m shadowhound node --ros-args ...` in a child process, output in a file.

    `command="sim-driver"` starts the simulated Go2 driver instead; `options` go before
    `--ros-args` (the driver's own options, e.g. ("--odom-delay", "0.5"))."""

    def __init__(
        self, *ros_args: str, command: str = "node", options: tuple[str, ...] = ()
    ) -> None:
        self.command = command
        fd, name = tempfile.mkstemp(prefix=f"{command.replace('-', '_')}_", suffix=".log")
        self.log = Path(name)
        env = dict(os.environ, PYTHONUNBUFFERED="1", RCUTILS_LOGGING_BUFFERED_STREAM="0")
        with os.fdopen(fd, "w") as log:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "shadowhound", command, *options, "--ros-args", *ros_args],
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                cwd=ROOT,
            )

    def output(self) -> str:
        return self.log.read_text(encoding="utf-8", errors="replace")

    def check_alive(self) -> None:
        if self.proc.poll() is not None:
            raise AssertionError(
                f"{self.command} exited with {self.proc.returncode}:\n{self.output()}"
            )

    def stop(self, sig: int = signal.SIGINT, timeout: float = 15.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)
            raise AssertionError(
                f"{self.command} did not exit within {timeout} s after "
                f"{signal.Signals(sig).name}:\n{self.output()}"
            ) from None

    def wait(self, timeout: float = 30.0) -> int:
        return self.proc.wait(timeout)
