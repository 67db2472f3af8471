"""Test-side ROS 2 helpers: a client node spinning in a thread, inboxes, node processes, and
`wait_matched`, the one way a test waits until DDS has connected it with another process.

Imported only after rclpy is known to be importable (see test_mission_node.py).
"""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.action import ActionClient
from rclpy.client import Client
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from shadowhound_interfaces.action import ExecuteMission
from shadowhound_interfaces.srv import Approve, Chat
from std_msgs.msg import Empty, String

from shadowhound.robot_config import ESTOP_RELEASE_TOPIC, ESTOP_TOPIC

RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
ROOT = Path(__file__).resolve().parents[2]
TIMEOUT = 30.0


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
    """One rclpy node in its own context, spun by a background thread.

    Its readers (inboxes), writers and clients are numbered in the order they are made:
    `wait_matched` needs to know which was made last."""

    def __init__(self, name: str = "shadowhound_test_client") -> None:
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._made = itertools.count(1)
        self._order: dict[int, int] = {}  # id(endpoint) -> its number
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

    def call(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """`fn(*args, **kwargs)` run on the spin thread, its result returned. For an action
        client's send_goal_async, cancel_goal_async and get_result_async: rclpy's ActionClient
        sends the request first and notes its sequence number after, so a reply that the spin
        thread takes in between is dropped as "unexpected" and the future never completes."""
        task = self.executor.create_task(lambda: fn(*args, **kwargs))
        wait_until(task.done, TIMEOUT, f"{getattr(fn, '__name__', fn)} on the spin thread")
        return task.result()

    def _number(self, endpoint: Any) -> Any:
        self._order[id(endpoint)] = next(self._made)
        return endpoint

    def order(self, endpoint: Any) -> int:
        """When `endpoint` (an inbox, a publisher, a client) was made, counted in this client."""
        return self._order[id(endpoint)]

    def subscribe(self, msg_type: Any, topic: str, qos: Any = RELIABLE) -> Inbox:
        inbox = Inbox()
        inbox.subscription = self.node.create_subscription(msg_type, topic, inbox.put, qos)
        return self._number(inbox)

    def publisher(self, msg_type: Any, topic: str, qos: Any = RELIABLE) -> Any:
        return self._number(self.node.create_publisher(msg_type, topic, qos))

    def action_client(self, name: str, action_type: Any = ExecuteMission) -> ActionClient:
        """Its goal, cancel and result services, feedback and status topics: readers and
        writers made now."""
        return self._number(ActionClient(self.node, action_type, name))

    def service_client(self, srv_type: Any, name: str) -> Client:
        return self._number(self.node.create_client(srv_type, name))

    def destroy(self, *endpoints: Any) -> None:
        """Remove inboxes, publishers and clients made here (a rig that ends takes its own
        along, so that a later rig's readers are the only ones on their topics). On the spin
        thread: nothing is destroyed under a wait that uses it."""
        self.call(self._destroy, endpoints)

    def _destroy(self, endpoints: Sequence[Any]) -> None:
        for endpoint in endpoints:
            self._order.pop(id(endpoint), None)
            if isinstance(endpoint, Inbox):
                self.node.destroy_subscription(endpoint.subscription)
            elif isinstance(endpoint, ActionClient):
                endpoint.destroy()
            elif isinstance(endpoint, Client):
                self.node.destroy_client(endpoint)
            else:
                self.node.destroy_publisher(endpoint)


def wait_matched(
    client: RosClient,
    what: str,
    readers: Sequence[Inbox],
    writers: Sequence[Any] = (),
    *,
    ping: Callable[[], Callable[[], bool]] | None = None,
    alive: Callable[[], object] = lambda: None,
    timeout: float = TIMEOUT,
) -> None:
    """Wait until DDS has matched both sides of every topic between `client` and one other
    process: `readers` are topics the test reads from it, `writers` topics it writes to it.
    Tests wait through here before they rely on a topic.

    This side is visible: each reader counts a publisher, each writer a subscription. The
    other side is not: the other process's writer may not have matched this reader yet, and
    what it publishes meanwhile never arrives (a volatile status line is lost). So the other
    side is proven by a delivery. A participant announces its readers in one reliable, ordered
    stream (its writers in another), and the other participant matches each announcement as it
    arrives; hence:

    - `readers[-1]` must be the last of them made, on a topic the other process publishes
      periodically, and this client's only reader of that topic: once a message has arrived
      there, the other process has matched it, and every reader made before it.
    - With `writers`, `ping()` sends one message over `writers[-1]` (the last of them made),
      which the other process answers on a reader, and returns a check for the answer: once
      answered, the other process has matched that writer and every writer made before it. A
      message from a writer that counts the reader is not lost, only late until the reader has
      matched it too, so one ping is enough and nothing of it arrives after this returns.
    """
    proof = readers[-1]
    assert all(client.order(r) < client.order(proof) for r in readers[:-1]), (
        f"{what}: the periodic reader that proves the match must be the last made"
    )
    if writers:
        assert ping is not None, f"{what}: writers need a ping to prove the other side"
        assert all(client.order(w) < client.order(writers[-1]) for w in writers[:-1]), (
            f"{what}: the ping must go over the writer made last"
        )
    topic = proof.subscription.topic_name
    me = (client.node.get_name(), client.node.get_namespace())
    ours = [
        info
        for info in client.node.get_subscriptions_info_by_topic(topic)
        if (info.node_name, info.node_namespace) == me
    ]
    assert len(ours) == 1, f"{what}: this client has {len(ours)} readers of {topic}, not 1"

    def this_side() -> bool:
        alive()
        return all(r.subscription.get_publisher_count() > 0 for r in readers) and all(
            w.get_subscription_count() > 0 for w in writers
        )

    wait_until(this_side, timeout, f"{what}: this side of the DDS match")
    wait_until(lambda: alive() or proof.items, timeout, f"{what}: a message on {topic}")
    if ping is not None:
        answered = ping()
        wait_until(lambda: alive() or answered(), timeout, f"{what}: the answer to a ping")


class Agent:
    """The topics, action and services of one running mission node, seen from the test client.

    Everything a test uses of the node is made here, in the order `wait_ready` relies on (see
    `wait_matched`): tests make no readers or writers of their own towards the node."""

    def __init__(self, client: RosClient, ns: str = "", speech_topic: str = "") -> None:
        self.client = client
        self.ns = ns
        # A namespaced test node is started with its status topics under its namespace.
        base = ns or "/shadowhound"
        self.action = client.action_client(f"{ns}/execute_mission")
        self.chat = client.service_client(Chat, f"{ns}/chat")
        self.approve = client.service_client(Approve, f"{ns}/approve")
        self.approvals = client.subscribe(String, f"{ns}/approval_request")
        self.status = client.subscribe(String, f"{ns}/mission_status")
        self.diagnostics = client.subscribe(DiagnosticArray, f"{base}/diagnostics")
        self.estop = client.publisher(Empty, ESTOP_TOPIC)
        self.release = client.publisher(Empty, ESTOP_RELEASE_TOPIC)
        self.missions = client.publisher(String, f"{ns}/mission_command")  # the last writer
        # What a Go2 node says (robot:=go2): matched before the node's robot_status proves it.
        self.speech = client.subscribe(String, speech_topic) if speech_topic else None
        self.robot = client.subscribe(String, f"{base}/robot_status")  # the last reader: 5 Hz

    def wait_ready(self, process: NodeProcess, timeout: float = TIMEOUT) -> None:
        """Until the node and this client have matched every topic both ways, and the node's
        action and services answer."""

        def ping() -> Callable[[], bool]:
            # An empty mission: refused at once, moves nothing; answered on mission_status.
            mark = self.status.mark()
            self.missions.publish(String(data=""))
            return lambda: any(
                m.data.startswith("FAILED: Refused: the mission is empty")
                for m in self.status.since(mark)
            )

        where = f"the mission node {self.ns or '/'}"
        wait_matched(
            self.client,
            where,
            readers=[
                self.approvals,
                self.status,
                self.diagnostics,
                *([self.speech] if self.speech is not None else []),
                self.robot,
            ],
            writers=[self.estop, self.release, self.missions],
            ping=ping,
            alive=process.check_alive,
            timeout=timeout,
        )
        services = (self.action.server_is_ready, self.chat.service_is_ready)
        services += (self.approve.service_is_ready,)
        wait_until(
            lambda: process.check_alive() or all(ready() for ready in services),
            timeout,
            f"the action and services of {where}",
        )

    def close(self) -> None:
        """Remove this client's readers, writers and clients of the node."""
        self.client.destroy(
            self.action,
            self.chat,
            self.approve,
            self.approvals,
            self.status,
            self.diagnostics,
            self.estop,
            self.release,
            self.missions,
            *([self.speech] if self.speech is not None else []),
            self.robot,
        )

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
    """`python -m shadowhound node --ros-args ...` in a child process, output in a file, with
    `env` on top of this process's environment.

    `command="sim-driver"` starts the simulated Go2 driver instead; `options` go before
    `--ros-args` (the driver's own options, e.g. ("--odom-delay", "0.5"))."""

    def __init__(
        self,
        *ros_args: str,
        command: str = "node",
        options: tuple[str, ...] = (),
        env: dict[str, str] | None = None,
    ) -> None:
        self.command = command
        fd, name = tempfile.mkstemp(prefix=f"{command.replace('-', '_')}_", suffix=".log")
        self.log = Path(name)
        env = {
            **os.environ,
            "PYTHONUNBUFFERED": "1",
            "RCUTILS_LOGGING_BUFFERED_STREAM": "0",
            **(env or {}),
        }
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
