"""Subscriptions that read no more than they may: each message arrives serialized, and one
larger than its kind's limit (input_limits.MAX_BYTES) is refused before it is read, so no
sender can make one message cost the executor more than that. What may take long to read (a
map, an image, a detector's boxes, TF) is read on a thread of its own (handoff.py), never on
the executor thread that serves odometry and the stops, and that thread spends at most
READ_SHARE of its time reading: rclpy holds the interpreter while it reads a message, so a
flood of them, read back to back, would still hold odometry's callbacks back.

Every refusal goes to the node's log (each kind when it begins, then at most every 30 s) and
to an InputReport the node's diagnostics show (`input_problems`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.serialization import deserialize_message

from .handoff import Handoff
from .input_limits import MAX_BYTES, READ_SHARE, InputReport, size_words


class RosInputs:
    """The capped subscriptions of one node, and what they refused (`report`)."""

    def __init__(self, node: Node, report: InputReport | None = None) -> None:
        self.node = node
        self.report = report or InputReport()
        self._handoffs: list[Handoff[bytes]] = []

    def subscribe(
        self,
        msg_type: Any,
        topic: str,
        on_msg: Callable[[Any], None],
        qos: QoSProfile,
        kind: str,
        *,
        thread: str = "",
        depth: int = 1,
    ) -> None:
        """`on_msg(msg)` for each message on `topic` of at most MAX_BYTES[kind] bytes; with
        `thread`, called on that thread for the newest `depth` messages in order (depth 1: the
        newest only), reading at most READ_SHARE of its time, else on the executor."""
        limit = MAX_BYTES[kind]
        name = self.node.resolve_topic_name(topic)
        what = msg_type.__name__

        def read(data: bytes) -> None:
            try:
                msg = deserialize_message(data, msg_type)
            except Exception as exc:  # rclpy raises several types for bytes it cannot read
                self.refuse(name, "unreadable", f"a {what} that cannot be read ({exc}): dropped")
                return
            on_msg(msg)

        handoff = Handoff(read, thread, depth, READ_SHARE) if thread else None
        if handoff is not None:
            self._handoffs.append(handoff)

        def arrived(data: bytes) -> None:
            if len(data) > limit:
                self.refuse(
                    name,
                    "too large",
                    f"a {what} of {size_words(len(data))} refused unread (at most "
                    f"{size_words(limit)} is taken)",
                )
            elif handoff is not None:
                if handoff.offer(data) and depth > 1:  # depth 1 keeps the newest on purpose
                    self.refuse(
                        name,
                        "behind",
                        f"reading fell {depth} messages behind: dropped the oldest unread",
                    )
            else:
                read(data)

        self.node.create_subscription(msg_type, topic, arrived, qos, raw=True)

    def refuse(self, topic: str, kind: str, text: str) -> None:
        """Record a refusal on `topic` (its full name); logged when its kind begins, then at
        most every `report.quiet` seconds."""
        if self.report.note(topic, kind, text, time.monotonic()):
            self.node.get_logger().warning(f"{topic}: {text}")

    def summary(self) -> str:
        """What was refused or cut lately, for diagnostics ('' when nothing)."""
        return self.report.summary(time.monotonic())

    def close(self) -> None:
        """End the reading threads (before the node is destroyed)."""
        for handoff in self._handoffs:
            handoff.close()
