"""`navigate_to_pose` for one robot of `shadowhound sim-driver`: Nav2's NavigateToPose action
served with the project's own planner (world/) on the scene's map and its own path follower
(world/follow.py), so a mission through Nav2's interface is tested end to end over DDS.

Like Nav2 it plans on the map, drives the robot, publishes feedback (distance and time
remaining, recoveries), cancels on request, and aborts with Nav2's error codes (206 goal
occupied, 208 no valid path, 105 no progress, ...) and a message. A newer goal preempts the
running one. It drives the robot as Nav2's controller does, with velocity that becomes Moves
(through the same path as a Twist on `cmd_vel_out`), and ends a goal with StopMove. When the
robot is blocked it re-plans from a fresh scan (a "recovery"), at most three times.

The server has a node of its own, spun by its own multi-threaded executor: a goal runs for
seconds in the execute callback while cancel requests must still be heard.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from builtin_interfaces.msg import Duration
from nav2_msgs.action import NavigateToPose
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node

from ..robot.sim.sensors import scene_belief
from ..state import Pose2D
from ..world import Belief, PlanError, apply_scan, plan_route
from ..world.follow import PathFollower
from .sport import SimSportMode

PERIOD = 0.1  # s: the controller's 10 Hz, as Nav2's controller server defaults to 20 Hz
STALL_SECONDS = 5.0  # no progress for this long is a blockage (then a recovery)
MAX_RECOVERIES = 3
# Nav2 Jazzy's error codes (nav2_msgs: ComputePathToPose 2xx, FollowPath 1xx).
GOAL_OCCUPIED, NO_VALID_PATH, TF_ERROR, FAILED_TO_MAKE_PROGRESS = 206, 208, 202, 105
FRAMES = ("", "odom", "map")  # map is the truth's frame; odom too unless odometry drifts


def _duration(seconds: float) -> Duration:
    seconds = max(0.0, seconds)
    return Duration(sec=int(seconds), nanosec=int((seconds % 1.0) * 1e9))


class SimNavigator:
    """NavigateToPose on `action` for the robot `body` (truth from its simulator). Goals in
    `map` are in the truth's frame; goals in `odom` too, unless `odom_in_map` says where a
    drifting odometry's frame lies in it now (--slam), as Nav2 transforms a goal with TF."""

    def __init__(
        self,
        parent: Node,
        action: str,
        body: SimSportMode,
        drive: Callable[[float, float, float], None],
        speed: float = 0.4,
        odom_in_map: Callable[[], tuple[float, float, float]] | None = None,
    ) -> None:
        self.body, self._drive, self.speed = body, drive, speed
        self._odom_in_map = odom_in_map
        name = f"{parent.get_name()}_{action.strip('/').replace('/', '_')}"
        self.node = Node(
            name,
            namespace=parent.get_namespace(),
            context=parent.context,
            use_global_arguments=False,
            start_parameter_services=False,
        )
        self._lock = threading.Lock()
        self._active: Any = None  # the goal handle now driving the robot
        self._stats = {"goals": 0, "succeeded": 0, "aborted": 0, "canceled": 0, "recoveries": 0}
        self._last = ""
        self._belief: Belief | None = None
        self.server = ActionServer(
            self.node,
            NavigateToPose,
            action,
            self._execute,
            goal_callback=self._on_goal,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
            handle_accepted_callback=self._on_accepted,
            callback_group=ReentrantCallbackGroup(),
        )
        self.action = self.node.resolve_topic_name(action)
        self._executor = MultiThreadedExecutor(num_threads=3, context=parent.context)
        self._executor.add_node(self.node)
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._spin, name="sim-nav", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            while not self._closed.is_set() and self.node.context.ok():
                self._executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass

    def close(self) -> None:
        self._closed.set()
        with self._lock:
            running = self._active is not None
        if running:  # let the goal's loop see `_closed` and end the goal
            time.sleep(2 * PERIOD)
        self._thread.join(2.0)
        self._executor.shutdown(timeout_sec=1.0)
        self.server.destroy()
        self.node.destroy_node()

    def truth(self) -> dict[str, Any]:
        """For sim_driver/truth: goals received and how they ended, and the one running."""
        with self._lock:
            return {**self._stats, "active": self._active is not None, "last": self._last}

    # -- goals -----------------------------------------------------------------------------

    def _on_goal(self, request: Any) -> GoalResponse:
        return GoalResponse.ACCEPT  # checked in execute, where Nav2 reports its error codes

    def _on_accepted(self, handle: Any) -> None:
        with self._lock:  # a running goal's loop sees it is no longer active and aborts
            self._stats["goals"] += 1
            self._active = handle
        handle.execute()

    def _belief_now(self) -> Belief:
        if self._belief is None:
            sim = self.body.sim
            self._belief = scene_belief(sim.map_world, sim.config.body_radius)
        return self._belief

    def _execute(self, handle: Any) -> Any:
        result = NavigateToPose.Result()
        pose = handle.request.pose
        frame = pose.header.frame_id.lstrip("/")
        if frame not in FRAMES and not frame.endswith("/odom"):
            return self._end(
                handle,
                result,
                "aborted",
                TF_ERROR,
                f"unknown frame {frame!r}: the simulator knows odom and map",
            )
        q = pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        goal = (float(pose.pose.position.x), float(pose.pose.position.y))
        if self._odom_in_map is not None and frame != "map":  # carried into the map by TF
            mx, my, myaw = self._odom_in_map()
            c, s = math.cos(myaw), math.sin(myaw)
            goal = (mx + c * goal[0] - s * goal[1], my + s * goal[0] + c * goal[1])
            yaw += myaw
        started = time.monotonic()
        recoveries = 0
        follower = self._plan(handle, result, goal, yaw)
        if follower is None:
            return result
        best, best_at = math.inf, started
        while True:
            with self._lock:
                preempted = self._active is not handle
            if handle.is_cancel_requested:
                self.body.stop_move()
                return self._end(handle, result, "canceled")
            if self._closed.is_set():  # the driver shuts down: the robot stops
                return self._end(handle, result, "aborted", 0, "the simulated driver stopped")
            if preempted or not handle.is_active:
                return self._end(
                    handle, result, "aborted", 0, "preempted by a newer goal", stop=False
                )
            t = self.body.truth()
            here = Pose2D(t.x, t.y, t.yaw)
            command = follower.command(here)
            if command is None:
                self.body.stop_move()
                return self._end(handle, result, "succeeded")
            left = follower.remaining(here)
            if left < best - 0.05 or command[0] == 0.0:  # turning in place is progress too
                best, best_at = min(best, left), time.monotonic()
            elif time.monotonic() - best_at > STALL_SECONDS:
                if recoveries == MAX_RECOVERIES:
                    self.body.stop_move()
                    return self._end(
                        handle,
                        result,
                        "aborted",
                        FAILED_TO_MAKE_PROGRESS,
                        f"no progress for {STALL_SECONDS:g} s after {recoveries} recoveries",
                    )
                recoveries += 1
                with self._lock:
                    self._stats["recoveries"] += 1
                self.body.stop_move()
                scan = self.body.sim.get_scan()
                if scan is not None:
                    apply_scan(self._belief_now().grid, scan)
                    self._belief_now().changed()
                follower = self._plan(handle, result, goal, yaw)
                if follower is None:
                    return result
                best, best_at = math.inf, time.monotonic()
                continue
            self._drive(*command)
            feedback = NavigateToPose.Feedback()
            feedback.current_pose.header.frame_id = "map" if self._odom_in_map else "odom"
            feedback.current_pose.header.stamp = self.node.get_clock().now().to_msg()
            feedback.current_pose.pose.position.x, feedback.current_pose.pose.position.y = t.x, t.y
            feedback.current_pose.pose.orientation.z = math.sin(t.yaw / 2.0)
            feedback.current_pose.pose.orientation.w = math.cos(t.yaw / 2.0)
            feedback.navigation_time = _duration(time.monotonic() - started)
            feedback.estimated_time_remaining = _duration(left / self.speed)
            feedback.number_of_recoveries = recoveries
            feedback.distance_remaining = float(left)
            handle.publish_feedback(feedback)
            time.sleep(PERIOD)

    def _plan(
        self, handle: Any, result: Any, goal: tuple[float, float], yaw: float
    ) -> PathFollower | None:
        t = self.body.truth()
        try:
            path = plan_route(self._belief_now(), (t.x, t.y), goal)
        except PlanError as exc:
            code = GOAL_OCCUPIED if "goal" in str(exc) else NO_VALID_PATH
            self._end(handle, result, "aborted", code, str(exc))
            return None
        points = list(path.waypoints[1:]) or [goal]
        points[-1] = goal
        return PathFollower(points, yaw, speed=self.speed)

    def _end(
        self,
        handle: Any,
        result: Any,
        how: str,
        code: int = 0,
        message: str = "",
        stop: bool = True,
    ) -> Any:
        result.error_code, result.error_msg = code, message
        with self._lock:
            self._stats[how] += 1
            self._last = how
            if self._active is handle:
                self._active = None
        if handle.is_active:
            {"succeeded": handle.succeed, "aborted": handle.abort, "canceled": handle.canceled}[
                how
            ]()
        if stop and how != "succeeded":
            self.body.stop_move()
        return result
