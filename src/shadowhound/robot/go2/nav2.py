"""Nav2's NavigateToPose action (`navigate_to_pose`) as the Go2 robot's Navigator.

The client lives on the robot's node and is served by its executor thread. Requests (send,
cancel, result) are made on that thread too (`call_soon`): rclpy's ActionClient stores a
request's sequence number only after sending it, so a reply taken by the executor in between
would be dropped. Callbacks only record what arrived. Goals go out in the odometry frame (Nav2
transforms them to its global frame with TF). Every goal this client sent that still runs is
cancelled by `cancel_all`, which the robot's `stop` and `emergency_stop` call: Nav2's controller
keeps publishing velocity until its goal ends, so a stop that did not cancel would be
overridden at once.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

from action_msgs.msg import GoalStatus
from nav2_msgs.action import NavigateToPose
from rclpy.action import ActionClient
from rclpy.node import Node

from ..base import RobotError
from ..navigator import NavFeedback, NavReport, NavStatus, nav2_error_words

_ENDED = {
    GoalStatus.STATUS_SUCCEEDED: NavStatus.SUCCEEDED,
    GoalStatus.STATUS_ABORTED: NavStatus.FAILED,
    GoalStatus.STATUS_CANCELED: NavStatus.CANCELED,
}


def _seconds(duration: Any) -> float:
    return float(duration.sec) + float(duration.nanosec) / 1e9


class Nav2Goal:
    """One NavigateToPose goal: its status as callbacks report it, and its cancellation."""

    def __init__(self, name: str, call_soon: Callable[[Callable[[], Any]], Any]) -> None:
        self._name = name
        self._call_soon = call_soon
        self._lock = threading.Lock()
        self._status = NavStatus.PENDING
        self._feedback: NavFeedback | None = None
        self._message = ""
        self._handle: Any = None
        self._cancel_wanted = False

    # -- callbacks (the robot's executor thread) -------------------------------------------

    def sent(self, future: Any) -> None:
        exc = future.exception()
        with self._lock:
            if exc is not None:
                self._status, self._message = NavStatus.FAILED, f"could not send the goal: {exc}"
                return
            handle = future.result()
            if not handle.accepted:
                self._status = NavStatus.FAILED
                self._message = f"{self._name} rejected the goal"
                return
            self._handle, self._status = handle, NavStatus.RUNNING
            cancel = self._cancel_wanted
        handle.get_result_async().add_done_callback(self._ended)
        if cancel:  # cancelled while the goal was on its way
            handle.cancel_goal_async()

    def on_feedback(self, msg: Any) -> None:
        fb = msg.feedback
        feedback = NavFeedback(
            float(fb.distance_remaining),
            int(fb.number_of_recoveries),
            _seconds(fb.navigation_time),
            _seconds(fb.estimated_time_remaining),
        )
        with self._lock:
            self._feedback = feedback

    def _ended(self, future: Any) -> None:
        exc = future.exception()
        with self._lock:
            if exc is not None:
                self._status, self._message = NavStatus.FAILED, f"no result: {exc}"
                return
            response = future.result()
            self._status = _ENDED.get(response.status, NavStatus.FAILED)
            result = response.result
            if self._status is NavStatus.FAILED:
                self._message = nav2_error_words(int(result.error_code), str(result.error_msg))
            elif self._status is NavStatus.CANCELED and not self._cancel_wanted:
                self._message = "cancelled by another client or a newer goal"

    # -- the skill's side ------------------------------------------------------------------

    def report(self) -> NavReport:
        with self._lock:
            return NavReport(self._status, self._feedback, self._message)

    def cancel(self) -> None:
        with self._lock:
            if self._status not in (NavStatus.PENDING, NavStatus.RUNNING):
                return
            self._cancel_wanted = True
            handle = self._handle
        if handle is not None:
            self._call_soon(handle.cancel_goal_async)

    @property
    def running(self) -> bool:
        with self._lock:
            return self._status in (NavStatus.PENDING, NavStatus.RUNNING)


class Nav2Navigator:
    """NavigateToPose on `action` (relative to the node's namespace); `call_soon(fn)` runs
    `fn` on the thread that spins `node`."""

    def __init__(
        self,
        node: Node,
        action: str,
        call_soon: Callable[[Callable[[], Any]], Any],
        frame: str = "odom",
    ) -> None:
        self._node = node
        self._call_soon = call_soon
        self._client = ActionClient(node, NavigateToPose, action)
        self.frame = frame  # the frame goals are sent in: the odometry's
        self._lock = threading.Lock()
        self._goals: list[Nav2Goal] = []
        self._action = node.resolve_topic_name(action)

    @property
    def name(self) -> str:
        return f"Nav2 ({self._action})"

    def ready(self, timeout: float) -> bool:
        return bool(self._client.wait_for_server(timeout_sec=max(0.0, timeout)))

    def navigate(self, x: float, y: float, yaw: float) -> Nav2Goal:
        if not all(math.isfinite(v) for v in (x, y, yaw)):
            raise RobotError(f"a navigation goal must be finite, got {(x, y, yaw)}")
        goal = NavigateToPose.Goal()
        pose = goal.pose
        pose.header.frame_id = self.frame
        pose.header.stamp = self._node.get_clock().now().to_msg()
        pose.pose.position.x, pose.pose.position.y = float(x), float(y)
        pose.pose.orientation.z = math.sin(yaw / 2.0)
        pose.pose.orientation.w = math.cos(yaw / 2.0)
        handle = Nav2Goal(self.name, self._call_soon)
        with self._lock:
            self._goals = [g for g in self._goals if g.running] + [handle]

        def send() -> None:
            future = self._client.send_goal_async(goal, feedback_callback=handle.on_feedback)
            future.add_done_callback(handle.sent)

        try:
            self._call_soon(send)
        except Exception as exc:  # rclpy raises several types when the context is gone
            raise RobotError(f"cannot send a goal to {self.name}: {exc}") from exc
        return handle

    @property
    def driving(self) -> bool:
        """A goal is under way: Nav2's controller, not our commands, moves the robot."""
        with self._lock:
            return any(g.running for g in self._goals)

    def cancel_all(self) -> None:
        with self._lock:
            goals = list(self._goals)
        for goal in goals:
            goal.cancel()

    def destroy(self) -> None:
        self._client.destroy()
