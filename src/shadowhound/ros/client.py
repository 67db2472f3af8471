"""A client of running ShadowHound nodes, for the command line: send a mission and follow it
(`shadowhound send`), press or release the e-stop (`shadowhound estop`), set a fault of the
simulated driver (`shadowhound sim-fault`). What `ros2 topic pub` and `ros2 topic echo` would
do, from the virtual environment: the `ros2` command is not on PyPI.

`NodeClient` is one rclpy node in a private context, spun on a thread of its own, so the
caller's thread only waits and stays free for Ctrl-C. Nothing is sent before DDS has matched
both sides the message needs: for a mission on the topic, the node's `mission_command`
subscription seen by the client's publisher and the node's `mission_status` publisher seen by
the client's subscription; for the `execute_mission` action, the action server ready
(`wait_for_server`); for a one-off message, a subscriber, and then every subscriber's
acknowledgement before the client goes away.
"""

from __future__ import annotations

import os
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.action.graph import get_action_names_and_types
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import Empty, String

from ..errors import NodeNotFound
from ..robot_config import ESTOP_RELEASE_TOPIC, ESTOP_TOPIC
from .convert import shorten
from .params import PARAMETERS

try:  # built by scripts/build_ros.sh; without it missions go by topic
    from shadowhound_interfaces.action import ExecuteMission
except ImportError:
    ExecuteMission = None

ACTION = "execute_mission"  # the node's ExecuteMission action (ros/node.py ACTION_NAME)
MISSION_TOPIC = str(PARAMETERS["mission_topic"][0])
STATUS_TOPIC = str(PARAMETERS["status_topic"][0])
_RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
_ACTION_GRACE = 2.0  # seconds to let the action's endpoints match once the node's topics have
_ACK_WAIT = 5.0  # seconds for every subscriber to acknowledge a one-off message


# -- what the client sees of a mission --------------------------------------------------------


@dataclass(frozen=True)
class PlanSeen:
    """The node planned the mission (action feedback)."""

    steps: int


@dataclass(frozen=True)
class StepSeen:
    """A step started or finished (action feedback); `progress` is the mission's, 0..1."""

    index: int
    count: int
    skill: str
    finished: bool
    progress: float


@dataclass(frozen=True)
class StatusSeen:
    """A line of `mission_status` (missions sent on the topic)."""

    text: str


@dataclass(frozen=True)
class MissionEnd:
    """How the mission ended: its success and the node's response."""

    success: bool
    response: str
    cancelled: bool = False


MissionUpdate = PlanSeen | StepSeen | StatusSeen | MissionEnd


def where(namespace: str, name: str) -> str:
    """`name` in `namespace` ("/robot1/mission_command"); absolute names stay as they are."""
    if name.startswith("/"):
        return name
    return f"/{namespace.strip('/')}/{name}" if namespace.strip("/") else f"/{name}"


def graph_settings() -> str:
    """The settings two ROS 2 processes must share to meet, as this process has them."""
    keys = ("ROS_DOMAIN_ID", "RMW_IMPLEMENTATION", "ROS_AUTOMATIC_DISCOVERY_RANGE")
    return ", ".join(f"{k}={os.environ.get(k, '(unset)')}" for k in keys)


# -- the client ---------------------------------------------------------------------------------


class NodeClient:
    """One rclpy node spinning on its own thread. `close()` when done."""

    def __init__(self, namespace: str = "", name: str = "shadowhound_cli") -> None:
        self.namespace = namespace
        self._context = Context()
        rclpy.init(context=self._context, signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node(
            name,
            context=self._context,
            use_global_arguments=False,
            start_parameter_services=False,
        )
        self._executor = SingleThreadedExecutor(context=self._context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="shadowhound-cli", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while self._context.ok():
            try:
                self._executor.spin_once(timeout_sec=0.05)
            except Exception:  # shutting down
                if self._context.ok():
                    raise

    def close(self) -> None:
        self._executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self._context)
        self._thread.join(2.0)

    # -- one message ------------------------------------------------------------------------

    def publish(self, topic: str, message: Any, wait: float) -> int:
        """Publish `message` once subscribed, wait until every subscriber has it; returns how
        many there were. Raises NodeNotFound when nothing subscribes within `wait` seconds."""
        publisher = self.node.create_publisher(type(message), topic, _RELIABLE)
        try:
            if not _until(lambda: publisher.get_subscription_count() > 0, wait):
                raise NodeNotFound(
                    f"nothing subscribes {topic} after {wait:g} s, so nothing got the message. "
                    f"Is the node running on this ROS graph? Here: {graph_settings()}"
                )
            publisher.publish(message)
            if not publisher.wait_for_all_acked(Duration(seconds=_ACK_WAIT)):
                raise NodeNotFound(
                    f"published on {topic}, but not every subscriber acknowledged it within "
                    f"{_ACK_WAIT:g} s (a subscriber that went away, or a link that drops data)"
                )
            return int(publisher.get_subscription_count())
        finally:
            self.node.destroy_publisher(publisher)

    def estop(self, release: bool, wait: float) -> int:
        """Press (or release) the e-stop of every agent on the graph; returns the subscribers."""
        return self.publish(ESTOP_RELEASE_TOPIC if release else ESTOP_TOPIC, Empty(), wait)

    # -- a mission --------------------------------------------------------------------------

    def send(self, command: str, wait: float, use_topic: bool = False) -> Mission:
        """Send `command` to the mission node in this client's namespace: by its action when it
        offers one (unless `use_topic`), else on `mission_command`. Raises NodeNotFound when no
        node answers within `wait` seconds."""
        mission = Mission(self, command)
        topic_ready = mission.connect_topic()
        action_ready = mission.connect_action() if not use_topic else lambda: False
        deadline = time.monotonic() + wait
        seen_topic = 0.0
        while not action_ready():
            now = time.monotonic()
            if topic_ready():
                seen_topic = seen_topic or now
                # The node's topics matched; the action's endpoints follow within moments, if
                # the node serves it (a node without shadowhound_interfaces does not).
                waited = now - seen_topic > _ACTION_GRACE and not mission.action_offered()
                if not mission.by_action or waited:
                    mission.publish()
                    return mission
            if now > deadline:
                mission.close()
                raise NodeNotFound(
                    f"no mission node answers at {where(self.namespace, MISSION_TOPIC)} after "
                    f"{wait:g} s. Start one (shadowhound node), with the same ROS graph "
                    f"settings as here: {graph_settings()}; --namespace if it runs in one"
                )
            time.sleep(0.02)
        mission.send_goal()
        return mission


class Mission:
    """One mission sent by a NodeClient: `next()` gives what is seen of it, a MissionEnd last."""

    def __init__(self, client: NodeClient, command: str) -> None:
        self.client = client
        self.command = command
        self.via = ""  # "action" or "topic", once sent
        self._updates: queue.Queue[MissionUpdate] = queue.Queue()
        self._node = client.node
        self._publisher: Any = None
        self._status: Any = None
        self._action: Any = None
        self._goal: Any = None
        self._cancel_asked = False
        self._lock = threading.Lock()  # the goal handle arrives on the client's thread
        self._started: set[int] = set()
        self._ours_started = False

    def next(self, timeout: float) -> MissionUpdate | None:
        """The next thing seen of the mission, or None when nothing came within `timeout`."""
        try:
            return self._updates.get(timeout=timeout)
        except queue.Empty:
            return None

    def cancel(self) -> bool:
        """Cancel the mission (the robot stops), also before the node has accepted it; False
        when it went by topic: such a mission cannot be cancelled (`shadowhound estop` stops
        every robot)."""
        if self.via != "action":
            return False
        with self._lock:
            self._cancel_asked = True
            goal = self._goal
        if goal is not None:
            goal.cancel_goal_async()
        return True

    def close(self) -> None:
        if self._publisher is not None:
            self._node.destroy_publisher(self._publisher)
        if self._status is not None:
            self._node.destroy_subscription(self._status)
        if self._action is not None:
            self._action.destroy()

    # -- by topic -------------------------------------------------------------------------

    def connect_topic(self) -> Callable[[], bool]:
        ns = self.client.namespace
        self._publisher = self._node.create_publisher(String, where(ns, MISSION_TOPIC), _RELIABLE)
        self._status = self._node.create_subscription(
            String, where(ns, STATUS_TOPIC), self._on_status, _RELIABLE
        )
        return lambda: bool(
            self._publisher.get_subscription_count() > 0 and self._status.get_publisher_count() > 0
        )

    def publish(self) -> None:
        self.via = "topic"
        self._publisher.publish(String(data=self.command))

    def _on_status(self, msg: String) -> None:
        if self.via != "topic":
            return
        text = str(msg.data)
        self._updates.put(StatusSeen(text))
        if text == f"EXECUTING: {shorten(self.command)}":
            self._ours_started = True
        # The status names no mission: ours ends with the first end after it started, or with
        # a refusal before any mission started (a full queue, an e-stop dropping it).
        elif text.startswith(("COMPLETED: ", "FAILED: ")) and (
            self._ours_started or text.startswith("FAILED: not run:") or "waiting" in text
        ):
            success, _, response = text.partition(": ")
            self._updates.put(MissionEnd(success == "COMPLETED", response))

    # -- by action ------------------------------------------------------------------------

    @property
    def by_action(self) -> bool:
        """Whether the mission may go by the action (this client can speak it)."""
        return self._action is not None

    def connect_action(self) -> Callable[[], bool]:
        if ExecuteMission is None:
            return lambda: False
        self._action = ActionClient(
            self._node, ExecuteMission, where(self.client.namespace, ACTION)
        )
        return lambda: bool(self._action.server_is_ready())

    def action_offered(self) -> bool:
        """The graph shows an action server by that name (its endpoints may not match yet)."""
        if self._action is None:
            return False
        name = where(self.client.namespace, ACTION)
        return any(n == name for n, _ in get_action_names_and_types(self._node))

    def send_goal(self) -> None:
        self.via = "action"
        goal = ExecuteMission.Goal(command=self.command, dry_run=False)
        future = self._action.send_goal_async(goal, feedback_callback=self._on_feedback)
        future.add_done_callback(self._on_goal)

    def _on_goal(self, future: Any) -> None:
        handle = future.result()
        if not handle.accepted:
            self._updates.put(
                MissionEnd(
                    False,
                    "refused: the node is running or has queued a mission (the action refuses "
                    "a second one; --topic queues it behind)",
                )
            )
            return
        with self._lock:
            self._goal = handle
            cancel = self._cancel_asked
        handle.get_result_async().add_done_callback(self._on_result)
        if cancel:
            handle.cancel_goal_async()

    def _on_feedback(self, msg: Any) -> None:
        fb = msg.feedback
        if fb.step_index == 0:
            self._updates.put(PlanSeen(int(fb.step_count)))
            return
        finished = fb.step_index in self._started
        self._started.add(fb.step_index)
        self._updates.put(
            StepSeen(
                int(fb.step_index),
                int(fb.step_count),
                str(fb.current_skill),
                finished,
                float(fb.progress),
            )
        )

    def _on_result(self, future: Any) -> None:
        answer = future.result()
        cancelled = answer.status == GoalStatus.STATUS_CANCELED
        self._updates.put(
            MissionEnd(bool(answer.result.success), answer.result.response, cancelled)
        )


def _until(condition: Callable[[], bool], seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True
