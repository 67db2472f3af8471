"""The e-stop listener: `/shadowhound/estop` on a node and thread of its own.

Whoever spins a busy node (the mission node takes camera frames 30 times a second, a Go2 robot
reads odometry, maps and scans) would queue an e-stop message behind that work. This listener is
a second, tiny node in the same context, spun by its own executor on its own thread, with
nothing else to do: an e-stop is handled as soon as DDS delivers it. The release goes through
the same listener, so an e-stop and a release published in that order are handled in that
order. The mission node uses it, and so does a Go2 robot wherever it runs (MCP, scripts).
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable

from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from std_msgs.msg import Empty


class EstopListener:
    """Calls `on_estop` / `on_release` for messages on the two topics, on its own thread."""

    def __init__(
        self,
        name: str,
        namespace: str,
        context: Context,
        qos: QoSProfile,
        *,
        estop_topic: str,
        release_topic: str,
        on_estop: Callable[[], None],
        on_release: Callable[[], None],
    ) -> None:
        self.node = Node(name, namespace=namespace, context=context, start_parameter_services=False)
        self.node.create_subscription(Empty, estop_topic, lambda _msg: on_estop(), qos)
        if release_topic:  # '' = released elsewhere only
            self.node.create_subscription(Empty, release_topic, lambda _msg: on_release(), qos)
        self._executor = SingleThreadedExecutor(context=context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="shadowhound-estop", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException):  # shutting down: close() cleans up
            self._executor.spin()

    def close(self) -> None:
        """Stop the thread and destroy the node. Safe to call twice."""
        if not self._thread.is_alive() and self.node is None:
            return
        self._executor.shutdown(timeout_sec=2.0)
        self._thread.join(2.0)
        if self.node is not None:
            self.node.destroy_node()
            self.node = None  # type: ignore[assignment]
