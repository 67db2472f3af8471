"""MissionNode: the ROS 2 shell around RobotAgent (parse ROS input, call the agent, render).

Interfaces (names relative to the node's namespace unless absolute):
- subscribes `mission_command` (std_msgs/String), the camera (sensor_msgs/Image or
  CompressedImage, best effort, depth 1); `/shadowhound/estop` and `/shadowhound/estop_release`
  (std_msgs/Empty) are taken by a companion node `<name>_estop` on a thread of its own, so no
  other callback can delay an e-stop (robot/estop_listener.py);
- publishes `mission_status` (std_msgs/String), `/shadowhound/diagnostics`
  (diagnostic_msgs/DiagnosticArray, 1 Hz), `/shadowhound/robot_status` (std_msgs/String JSON,
  5 Hz), and for RViz `planned_path` (nav_msgs/Path) and `known_objects`
  (visualization_msgs/MarkerArray), see rviz.py;
- serves the `execute_mission` action (shadowhound_interfaces/ExecuteMission) and the `chat`
  service (shadowhound_interfaces/Chat) when the interface package is installed.

Missions run on one worker thread (see worker.py), chat answers on another, camera frames are
read and converted on a third (robot/ros_inputs.py, which also caps a frame's size); every ROS
callback is short, so one SingleThreadedExecutor serves them all (the action's execute
callback and the chat service are coroutines that await the other threads). Topic missions
queue, action goals are rejected while a mission runs or waits.

Long because: one node's whole ROS surface (topics, action, service, parameters, status and
diagnostics publishing) reads as one plain node class, as nav2_simple_commander's does; the
pure helpers live in their own modules (params, convert, rviz; the e-stop listener is
robot/estop_listener.py, the capped camera subscription robot/ros_inputs.py).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any, cast

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from sensor_msgs.msg import CompressedImage, Image
from std_msgs.msg import String

from .. import events as ev
from .. import jsonout
from ..agent import RobotAgent, RobotAgentConfig
from ..camera import raw_image_frame, to_camera_frame
from ..config import ShadowHoundConfig
from ..errors import ConfigError, ParameterError
from ..result import MissionResult
from ..robot.base import RobotError
from ..robot.estop_listener import EstopListener
from ..robot.factory import make_robot
from ..robot.ros_inputs import RosInputs
from ..robot_config import ESTOP_RELEASE_TOPIC, ESTOP_TOPIC
from ..worker import MissionJob, MissionWorker
from .convert import (
    diagnostic_level,
    diagnostic_message,
    diagnostic_values,
    robot_status_json,
    shorten,
)
from .params import NODE_NAME, PARAMETERS, describe_parameters, parse_parameters
from .process import run_node
from .rviz import RvizPublisher

if TYPE_CHECKING:
    from ..robot.base import Robot
    from ..robot.go2.robot import Go2RosRobot

try:  # built by scripts/build_ros.sh (ros2/shadowhound_interfaces)
    from shadowhound_interfaces.action import ExecuteMission
    from shadowhound_interfaces.srv import Approve, Chat
except ImportError:  # the node still runs its topics; the action and services are off
    ExecuteMission = Chat = Approve = None

ACTION_NAME = "execute_mission"
CHAT_SERVICE = "chat"
APPROVE_SERVICE = "approve"
APPROVAL_TOPIC = "approval_request"
ROBOT_STATUS_HZ = 5.0
DIAGNOSTICS_NAME = "shadowhound: mission agent"

_COMMANDS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
_CAMERA = QoSProfile(
    depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
_FEEDBACK_EVENTS = (ev.PlanReady, ev.StepStarted, ev.StepFinished)


class MissionNode(Node):
    """The mission agent on ROS 2. Give `agent` to drive an existing RobotAgent (its own
    settings then win over `backend_config`, `robot` and `time_scale`).

    Raises ParameterError (a ConfigError) for invalid parameters, ConfigError for a bad
    profile or an unavailable backend.
    """

    def __init__(
        self, agent: RobotAgent | None = None, *, node_name: str = NODE_NAME, **node_kwargs: Any
    ) -> None:
        super().__init__(node_name, **node_kwargs)
        try:
            self.settings = parse_parameters(self._declare_parameters())
        except BaseException:  # no half-made node left for ROS's shutdown to find
            Node.destroy_node(self)  # rclpy's own: this node's destroy_node needs what follows
            raise
        self._go2: Go2RosRobot | None = None  # the Go2 this node built (its topics are logged)
        if agent is None:
            settings = self.settings.agent_settings()
            agent = RobotAgent(
                RobotAgentConfig(robot=self._make_robot(settings), settings=settings)
            )
        agent.initialize()
        self.agent = agent
        self._frames = {"received": 0, "dropped": 0}
        self._last_frame = ""
        self._last_camera_error = ""
        self._worker = MissionWorker(agent)
        self._worker.on("started", self._on_mission_start)
        self._worker.on("finished", self._on_mission_finish)
        self._chat_thread = ThreadPoolExecutor(1, thread_name_prefix="shadowhound-chat")
        self._web: Any = None
        self._inputs = RosInputs(self)  # the node's own capped subscriptions (the camera)
        self._build_interfaces()
        if self.settings.enable_web_ui:
            self._start_web()
        self._report_startup()

    # -- set-up --------------------------------------------------------------------------

    def _declare_parameters(self) -> dict[str, Any]:
        known = set(PARAMETERS) | {"use_sim_time"}
        unknown = sorted(set(getattr(self, "_parameter_overrides", {})) - known)
        if unknown:
            raise ParameterError(
                f"unknown ROS parameter(s): {', '.join(unknown)}; known: {', '.join(PARAMETERS)}"
            )
        values = {}
        for name, (default, text) in PARAMETERS.items():
            descriptor = ParameterDescriptor(description=text, dynamic_typing=True)
            values[name] = self.declare_parameter(name, default, descriptor).value
        return values

    def _make_robot(self, settings: ShadowHoundConfig) -> Robot:
        """The profile's robot as the parameters fill it (robot/factory.py), on this node's
        context. A Go2's camera is off here (the node's own camera subscription,
        `camera_topic`, gives the agent its frames) and so are its e-stop topics (the node
        listens itself, and drops queued missions with it)."""
        if settings.robot.type == "go2":
            settings.robot = settings.robot.model_copy(
                update={"camera_topic": "", "estop_topic": "", "estop_release_topic": ""}
            )
        try:
            robot = make_robot(settings, context=self.context)
        except ConfigError as exc:
            raise ParameterError(str(exc)) from exc
        if settings.robot.type == "go2":
            self._go2 = cast("Go2RosRobot", robot)
        return robot

    def _build_interfaces(self) -> None:
        s = self.settings
        try:
            self._status_pub = self.create_publisher(String, s.status_topic, _COMMANDS)
            self._robot_pub = self.create_publisher(String, s.robot_status_topic, 10)
            self._diag_pub = self.create_publisher(DiagnosticArray, s.diagnostics_topic, 10)
            self.create_subscription(String, s.mission_topic, self._on_mission, _COMMANDS)
            self._estop = EstopListener(
                f"{self.get_name()}_estop",
                self.get_namespace(),
                self.context,
                _COMMANDS,
                estop_topic=ESTOP_TOPIC,
                release_topic=ESTOP_RELEASE_TOPIC,
                on_estop=self._on_estop,
                on_release=self._on_estop_release,
            )
            # Within the image's size limit; the callback only keeps the newest frame, which
            # is read and converted off the executor (robot/ros_inputs.py).
            self._inputs.subscribe(
                CompressedImage if s.camera_compressed else Image,
                s.camera_topic,
                self._on_compressed if s.camera_compressed else self._on_image,
                _CAMERA,
                "image",
                thread="shadowhound-camera",
            )
        except Exception as exc:  # rclpy raises several types for bad names
            raise ParameterError(f"cannot create the node's topics: {exc}") from exc
        self.create_timer(1.0, self._publish_diagnostics)
        self.create_timer(1.0 / ROBOT_STATUS_HZ, self._publish_robot_status)
        self._rviz = RvizPublisher(self, self.agent)  # planned_path, known_objects (rviz.py)
        self._goals: dict[bytes, MissionJob] = {}
        if ExecuteMission is not None and Chat is not None:
            self._action = ActionServer(
                self,
                ExecuteMission,
                ACTION_NAME,
                self._execute_goal,
                goal_callback=self._on_goal,
                cancel_callback=self._on_cancel,
            )
            self.create_service(Chat, CHAT_SERVICE, self._on_chat)
            # Risky plans wait for a person: announced on a topic, decided by a service.
            self._approval_pub = self.create_publisher(String, APPROVAL_TOPIC, _COMMANDS)
            self.create_service(Approve, APPROVE_SERVICE, self._on_approve)
            self.agent.add_listener(self._announce_approval)
            self.agent.enable_approvals()

    def _report_startup(self) -> None:
        s, log = self.settings, self.get_logger()
        log.info(
            f"mission agent ready: backend {self.agent.settings.backend} "
            f"(profile {self.agent.settings.profile}), robot {self.agent.robot.name}, "
            f"missions on {self.resolve_topic_name(s.mission_topic)}, camera "
            f"{s.camera_topic} ({'compressed' if s.camera_compressed else 'raw'})"
        )
        if self._go2 is not None:
            topic = self._go2.topic
            velocity = (
                topic(s.cmd_vel_topic)
                if s.cmd_vel_topic
                else f"{topic('cmd_vel')} when a relay (twist_mux) carries it to "
                f"{topic('cmd_vel_out')}, else {topic('cmd_vel_out')}"
            )
            battery = (
                topic(s.battery_topic) if s.battery_topic else "none (battery reported unknown)"
            )
            speech = topic(s.speech_topic) if s.speech_topic else "none (the robot does not speak)"
            log.info(
                f"Go2 through go2_ros2_sdk: velocity on {velocity}, sport "
                f"commands on {topic(s.webrtc_topic)}, odometry from "
                f"{topic(s.odom_topic)}, state from {topic(s.go2_states_topic)}, battery "
                f"{battery}, speech on {speech}, "
                + (
                    f"SLAM's {s.map_frame} -> odom from /tf (poses in {s.map_frame} once it "
                    "arrives)"
                    if s.map_frame
                    else "no TF read (poses in odometry's frame)"
                )
            )
        if ExecuteMission is None:
            log.warning(
                "shadowhound_interfaces is not installed: the execute_mission action "
                "and the chat service are off (build it with scripts/build_ros.sh)"
            )
        if self._web is not None:
            log.info(f"web dashboard on {self._web.url}")

    def _start_web(self) -> None:
        """The dashboard on 127.0.0.1:web_interface_port, sharing this node's mission worker
        (one mission at a time whether it came from a topic, an action or the page)."""
        try:
            from ..web.app import create_app
            from ..web.server import ServeError, WebServer
        except ImportError as exc:
            raise ParameterError(
                f"enable_web_ui needs the 'web' extra (pip install 'shadowhound[web]'): {exc}"
            ) from exc
        app = create_app(self.agent, worker=self._worker)  # the page listens to it too
        try:
            self._web = WebServer(app, "127.0.0.1", self.settings.web_interface_port).start()
        except ServeError as exc:
            raise ParameterError(f"enable_web_ui: {exc}") from exc

    def shutdown(self) -> None:
        """Cancel the mission, stop the robot, end the worker. Safe to call twice."""
        if self._web is not None:
            self._web.stop()
            self._web = None
        self._worker.stop()
        # The mission's last status ("FAILED: ...") was just published: let every reader
        # acknowledge it before the writer goes (a reliable line is lost with its writer).
        self._status_pub.wait_for_all_acked(Duration(seconds=2.0))
        self._chat_thread.shutdown(wait=False, cancel_futures=True)
        self.agent.cleanup()
        self._inputs.close()
        self._estop.close()
        self._rviz.close()

    def destroy_node(self) -> None:
        self._estop.close()
        super().destroy_node()

    # -- missions from the topic -----------------------------------------------------------

    def _on_mission(self, msg: String) -> None:
        refused = self._worker.submit(MissionJob(msg.data, source="topic"))
        if refused:
            self._publish_status(f"FAILED: {refused}")

    def _on_mission_start(self, job: MissionJob) -> None:
        if not job.dry_run:
            self._publish_status(f"EXECUTING: {shorten(job.command)}")

    def _on_mission_finish(self, job: MissionJob) -> None:
        if job.dry_run:
            return
        if job.dropped or job.result is None:
            self._publish_status(f"FAILED: not run: {job.dropped or 'no result'}")
        elif job.result.success:
            self._publish_status(f"COMPLETED: {job.result.response}")
        else:
            self._publish_status(f"FAILED: {job.result.response}")

    def _publish_status(self, text: str) -> None:
        self._status_pub.publish(String(data=text))

    # -- e-stop ------------------------------------------------------------------------------

    def _on_estop(self) -> None:
        """On the e-stop listener's own thread (see robot/estop_listener.py)."""
        dropped = self._worker.estop()  # the robot stops first, then the queue is dropped
        self.get_logger().warning(
            f"E-STOP latched: robot stopped, {len(dropped)} waiting "
            f"mission(s) dropped; publish on {ESTOP_RELEASE_TOPIC} to "
            "release"
        )

    def _on_estop_release(self) -> None:
        self.agent.release_estop()
        self.get_logger().info("e-stop released")

    # -- the ExecuteMission action -----------------------------------------------------------

    def _on_goal(self, _request: Any) -> GoalResponse:
        if self._worker.busy:
            self.get_logger().info("rejected an ExecuteMission goal: a mission is running")
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _on_cancel(self, goal_handle: Any) -> CancelResponse:
        job = self._goals.get(bytes(goal_handle.goal_id.uuid))
        if job is not None:
            self._worker.cancel(job.mission_id)
        return CancelResponse.ACCEPT

    async def _execute_goal(self, goal_handle: Any) -> Any:
        request = goal_handle.request
        key = bytes(goal_handle.goal_id.uuid)
        finished = Future()
        job = MissionJob(
            request.command,
            source="action",
            dry_run=request.dry_run,
            on_event=lambda event: self._send_feedback(goal_handle, event),
            on_done=lambda _job: self._resolve(finished, True),
        )
        self._goals[key] = job
        try:
            refused = self._worker.start_now(job)
            if refused:
                goal_handle.abort()
                return ExecuteMission.Result(success=False, response=f"Refused: {refused}.")
            await finished  # the executor keeps serving everything else meanwhile
        finally:
            self._goals.pop(key, None)
        result = _action_result(job)
        if goal_handle.is_cancel_requested and not result.success:
            goal_handle.canceled()
        elif result.success:
            goal_handle.succeed()
        else:
            goal_handle.abort()
        return result

    def _resolve(self, future: Future, value: Any) -> None:
        """Complete `future` from another thread and wake the executor to resume its awaiter."""
        future.set_result(value)
        executor = self.executor
        if executor is not None:
            executor.wake()

    def _send_feedback(self, goal_handle: Any, event: ev.MissionEvent) -> None:
        if not isinstance(event, _FEEDBACK_EVENTS):
            return
        progress = self.agent.diagnostics().progress
        step = event.step if isinstance(event, ev.StepStarted | ev.StepFinished) else None
        count = len(event.plan.steps) if isinstance(event, ev.PlanReady) else progress.steps
        goal_handle.publish_feedback(
            ExecuteMission.Feedback(
                current_skill=step.skill if step else "",
                step_index=step.index if step else 0,
                step_count=count,
                progress=progress.progress,
            )
        )

    # -- chat ------------------------------------------------------------------------------

    async def _on_chat(self, request: Any, response: Any) -> Any:
        answered = Future()
        self._chat_thread.submit(self._answer, request.text, answered)
        response.answer = await answered
        return response

    def _answer(self, text: str, answered: Future) -> None:
        try:
            answer = self.agent.chat(text)
        except Exception as exc:  # a model or network failure is an answer, not a crash
            self.get_logger().error(f"chat failed: {exc!r}")
            answer = f"Sorry, I could not answer: {exc}"
        self._resolve(answered, answer)

    # -- approvals ---------------------------------------------------------------------------

    def _announce_approval(self, event: ev.MissionEvent) -> None:
        if isinstance(event, ev.ApprovalRequired):
            self._approval_pub.publish(String(data=jsonout.dumps(event.request.to_dict())))

    def _on_approve(self, request: Any, response: Any) -> Any:
        wanted = request.request_id.strip() or None
        if request.approve:
            response.accepted = self.agent.approve(wanted)
        else:
            response.accepted = self.agent.reject(wanted, request.reason.strip())
        verdict = "approved" if request.approve else "rejected"
        response.message = (
            verdict
            if response.accepted
            else (
                "no plan with that id is waiting for approval"
                if wanted
                else "no plan is waiting for approval"
            )
        )
        return response

    # -- camera ----------------------------------------------------------------------------

    def _on_image(self, msg: Image) -> None:
        """On the camera intake's thread, like `_on_compressed`."""
        try:
            frame = raw_image_frame(msg.data, msg.width, msg.height, msg.encoding, msg.step)
            self.agent.update_camera_image(frame)
        except ValueError as exc:
            self._drop_frame(exc)
        else:
            self._take_frame(f"{frame.width}x{frame.height} {frame.encoding}")

    def _on_compressed(self, msg: CompressedImage) -> None:
        try:
            frame = to_camera_frame(bytes(msg.data))  # JPEG or PNG, told apart by content
            self.agent.update_camera_image(frame)
        except ValueError as exc:
            self._drop_frame(exc)
        else:
            self._take_frame(f"{frame.width}x{frame.height} {frame.encoding}")

    def _take_frame(self, what: str) -> None:
        self._frames["received"] += 1
        self._last_frame = what

    def _drop_frame(self, exc: ValueError) -> None:
        self._frames["dropped"] += 1
        self._last_camera_error = str(exc)
        self.get_logger().warning(
            f"dropped a camera frame on {self.settings.camera_topic}: {exc}",
            throttle_duration_sec=5.0,
        )

    # -- status out ------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        self._diag_pub.publish(self.diagnostics_message())

    def diagnostics_message(self) -> DiagnosticArray:
        """The agent's diagnostics as one DiagnosticStatus (what is published at 1 Hz)."""
        diagnostics = self.agent.diagnostics().to_dict()  # the one conversion, then key-values
        extra = {
            "node": self.get_fully_qualified_name(),
            "robot": self.agent.robot.name,
            "camera_frames": self._frames["received"],
            "camera_dropped": self._frames["dropped"],
            "camera_last_frame": self._last_frame,
            "camera_last_error": self._last_camera_error,
            "busy": self._worker.busy,
        }
        # What the node and its Go2 refused or cut of their inputs lately (input_limits).
        refused = [self._inputs.summary(), self._go2.input_problems if self._go2 else ""]
        extra["input_problems"] = "; ".join(r for r in refused if r)
        if self._go2 is not None:  # which topic reaches the driver, and why (go2_topics)
            route = self._go2.velocity_route
            extra.update(velocity_topic=route.topic, velocity_route=route.why)
            extra["odom_latency"] = f"{self._go2.odom_latency:.2f} s"  # measured when it moves
        name = DIAGNOSTICS_NAME
        if self.get_fully_qualified_name() != f"/{NODE_NAME}":  # keep several agents apart
            name += f" ({self.get_fully_qualified_name()})"
        status = DiagnosticStatus(
            level=bytes([diagnostic_level(diagnostics)]),
            name=name,
            message=diagnostic_message(diagnostics),
            hardware_id=self.agent.robot.name,
            values=[KeyValue(key=k, value=v) for k, v in diagnostic_values(diagnostics, extra)],
        )
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        return array

    def _publish_robot_status(self) -> None:
        try:
            state = self.agent.get_robot_status()
        except RobotError:  # a Go2 whose odometry stopped: its last state, connected false
            state = self._last_robot_state()
        self._robot_pub.publish(String(data=robot_status_json(state)))

    def _last_robot_state(self) -> dict[str, Any]:
        return self.agent.robot.last_state().to_dict()


MissionAgentNode = MissionNode


def _action_result(job: MissionJob) -> Any:
    result = job.result
    if isinstance(result, MissionResult):
        steps = [s.to_dict() for s in result.steps]
        return ExecuteMission.Result(
            success=result.success, response=result.response, steps_json=jsonout.dumps(steps)
        )
    return ExecuteMission.Result(
        success=False, steps_json="[]", response=f"Not run: {job.dropped or 'no result'}."
    )


_USAGE = f"""usage: shadowhound node [--ros-args -p NAME:=VALUE ...]

Run the ShadowHound mission agent as the ROS 2 node '{NODE_NAME}'. Parameters:
{describe_parameters()}
Exit codes: 0 after Ctrl-C / SIGTERM (the robot is stopped first), 2 for invalid parameters.
"""


def main(argv: Sequence[str] | None = None) -> int:
    """`shadowhound node --ros-args -p name:=value ...` (also the `mission_node` script)."""
    return run_node(
        "shadowhound node",
        "mission_node",
        argv,
        _USAGE,
        MissionNode,
        lambda node: node.shutdown(),  # type: ignore[attr-defined]
        "shutting down: cancelling the mission and stopping the robot",
    )


if __name__ == "__main__":
    sys.exit(main())
