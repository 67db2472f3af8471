"""MissionNode end to end on real rclpy and DDS (loopback only), across processes.

Two node processes are started once for the module: the default one (raw camera, real-time
simulated robot) and one in namespace /cam with a compressed camera. A client node in this
process publishes, subscribes and calls the action. Skipped without rclpy (Python 3.10 runs)
or without the built interface package, unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

import json
import signal
import socket
import urllib.request
from collections.abc import Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces")

from action_msgs.msg import GoalStatus  # noqa: E402
from sensor_msgs.msg import CompressedImage, Image  # noqa: E402
from shadowhound_interfaces.action import ExecuteMission  # noqa: E402
from shadowhound_interfaces.srv import Approve, Chat  # noqa: E402
from std_msgs.msg import Empty, String  # noqa: E402

from tests.images import tiny_jpeg  # noqa: E402
from tests.ros.rosclient import RELIABLE, Agent, NodeProcess, RosClient, wait_until  # noqa: E402

TIMEOUT = 30.0
# rclpy's message generator imports lark, which imports deprecated sre_* modules.
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient()
    yield c
    c.close()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


WEB_PORT = free_port()


@pytest.fixture(scope="module")
def nodes(client: RosClient) -> Iterator[dict[str, tuple[NodeProcess, Agent]]]:
    main = NodeProcess(
        "-p",
        "time_scale:=1.0",
        "-p",
        "enable_web_ui:=true",
        "-p",
        f"web_interface_port:={WEB_PORT}",
    )
    cam = NodeProcess(
        "-r",
        "__ns:=/cam",
        "-p",
        "camera_topic:=/cam/camera/compressed",
        "-p",
        "diagnostics_topic:=/cam/diagnostics",
        "-p",
        "robot_status_topic:=/cam/robot_status",
        "-p",
        "time_scale:=0.0",
    )
    started = {"main": (main, Agent(client)), "cam": (cam, Agent(client, "/cam"))}
    try:
        for process, agent in started.values():
            agent.wait_ready(process)
        yield started
    finally:
        codes = {name: process.stop(signal.SIGINT) for name, (process, _a) in started.items()}
    assert codes == {"main": 0, "cam": 0}, {n: p.output()[-2000:] for n, (p, _a) in started.items()}


@pytest.fixture
def agent(nodes: dict[str, tuple[NodeProcess, Agent]]) -> Iterator[Agent]:
    process, a = nodes["main"]
    yield a
    process.check_alive()


@pytest.fixture
def cam_agent(nodes: dict[str, tuple[NodeProcess, Agent]]) -> Iterator[Agent]:
    process, a = nodes["cam"]
    yield a
    process.check_alive()


def send_goal(
    agent: Agent, command: str, dry_run: bool = False, feedback: list | None = None
) -> object:
    future = agent.client.call(
        agent.action.send_goal_async,
        ExecuteMission.Goal(command=command, dry_run=dry_run),
        feedback_callback=(lambda fb: feedback.append(fb.feedback))
        if feedback is not None
        else None,
    )
    wait_until(future.done, TIMEOUT, "the goal to be answered")
    return future.result()


def get_result(agent: Agent, goal_handle: object) -> object:
    future = agent.client.call(goal_handle.get_result_async)
    wait_until(future.done, TIMEOUT, "the action result")
    return future.result()


def wait_moving(agent: Agent) -> dict:
    return wait_until(
        lambda: (s := agent.robot_state()) and s["moving"] and s, TIMEOUT, "the robot to move"
    )


# -- missions on the topic -------------------------------------------------------------------


def test_mission_command_reports_executing_then_completed(agent: Agent) -> None:
    mark = agent.status.mark()
    final = agent.run("turn left 10 degrees")
    lines = [m.data for m in agent.status.since(mark)]
    assert lines[0] == "EXECUTING: turn left 10 degrees"
    assert final.startswith("COMPLETED: Done: turned 10.0 degrees left"), final
    assert lines.index(final) == 1


def test_malformed_missions_fail_and_the_node_keeps_running(agent: Agent) -> None:
    assert agent.run("").startswith("FAILED: Refused: the mission is empty")
    huge = agent.run("walk forward " + "very " * 20_000 + "slowly")  # about 100 kB
    assert huge.startswith("FAILED: Refused: the mission is 100"), huge[:200]
    assert "limit" in huge
    gibberish = agent.run("flarp the zorblax \x00\x01 \u2603")
    assert gibberish.startswith("FAILED: "), gibberish
    assert agent.run("turn right 5 degrees").startswith("COMPLETED: ")


# -- the ExecuteMission action ---------------------------------------------------------------


def test_action_goal_gets_feedback_per_step_and_a_result(agent: Agent) -> None:
    feedback: list = []
    handle = send_goal(
        agent, "walk forward 0.2 meters then turn left 20 degrees", feedback=feedback
    )
    assert handle.accepted
    response = get_result(agent, handle)
    assert response.status == GoalStatus.STATUS_SUCCEEDED
    result = response.result
    assert result.success, result.response
    steps = json.loads(result.steps_json)
    assert [s["skill"] for s in steps] == ["nav.move", "nav.rotate"]
    assert all(s["status"] == "succeeded" for s in steps)
    wait_until(lambda: len(feedback) >= 5, 5, "feedback for the plan and each step")
    assert {f.step_count for f in feedback} == {2}
    assert [f.current_skill for f in feedback[1:5]] == ["nav.move"] * 2 + ["nav.rotate"] * 2
    assert [f.step_index for f in feedback[1:5]] == [1, 1, 2, 2]
    assert feedback[-1].progress == pytest.approx(1.0)


def test_dry_run_plans_and_checks_without_moving(agent: Agent) -> None:
    before = agent.robot_state()
    result = get_result(agent, send_goal(agent, "walk forward 2 meters", dry_run=True)).result
    assert result.success, result.response
    assert result.response.startswith("Dry run")
    assert [s["skill"] for s in json.loads(result.steps_json)] == ["nav.move"]
    refused = get_result(agent, send_goal(agent, "walk forward 50 meters", dry_run=True)).result
    assert not refused.success and "refused" in refused.response
    after = agent.robot_state()
    assert after["distance_travelled"] == before["distance_travelled"]


def test_cancel_stops_the_robot_and_a_second_goal_is_rejected(agent: Agent) -> None:
    feedback: list = []
    handle = send_goal(agent, "walk forward 2 meters", feedback=feedback)
    assert handle.accepted
    wait_moving(agent)
    assert not send_goal(agent, "turn left 10 degrees").accepted  # one mission at a time
    cancel = agent.client.call(handle.cancel_goal_async)
    wait_until(cancel.done, TIMEOUT, "the cancel response")
    response = get_result(agent, handle)
    assert response.status == GoalStatus.STATUS_CANCELED
    assert not response.result.success
    assert "mission cancelled" in response.result.response
    stopped = wait_until(
        lambda: (s := agent.robot_state()) and not s["moving"] and s, 5, "the robot to stop"
    )
    assert stopped["x"] < 1.8  # cancelled before the end (x = 2.0)
    # the node takes goals again
    assert get_result(agent, send_goal(agent, "turn right 5 degrees")).result.success


def test_empty_goal_is_aborted_with_a_reason(agent: Agent) -> None:
    response = get_result(agent, send_goal(agent, "   "))
    assert response.status == GoalStatus.STATUS_ABORTED
    assert "empty" in response.result.response


# -- e-stop ----------------------------------------------------------------------------------


def test_estop_stops_latches_and_releases(agent: Agent) -> None:
    mark = agent.status.mark()
    agent.missions.publish(String(data="walk forward 2 meters"))
    wait_moving(agent)
    diag_mark = agent.diagnostics.mark()
    agent.estop.publish(Empty())
    final = agent.status.wait_for(
        lambda m: m.data.startswith(("COMPLETED", "FAILED")), TIMEOUT, "the mission to end", mark
    )
    assert final.data.startswith("FAILED: Stopped") and "e-stop" in final.data, final.data
    state = wait_until(
        lambda: (s := agent.robot_state()) and not s["moving"] and s, 5, "the robot to stop"
    )
    assert state["estopped"]
    status, values = agent.diagnostic(diag_mark, match=lambda v: v["estop"] == "true")
    assert status.level == b"\x02" and status.message == "e-stop latched"
    assert agent.run("turn left 5 degrees").startswith("FAILED: Refused: the e-stop is latched")
    agent.release.publish(Empty())
    wait_until(lambda: not agent.robot_state()["estopped"], 5, "the e-stop to be released")
    assert agent.run("turn left 5 degrees").startswith("COMPLETED: ")


# -- status out ------------------------------------------------------------------------------


def test_diagnostics_decode_as_diagnostic_array(agent: Agent) -> None:
    mark = agent.diagnostics.mark()
    status, values = agent.diagnostic(mark)
    assert status.name == "shadowhound: mission agent"
    assert status.hardware_id == "sim-go2"
    assert status.level in (b"\x00", b"\x01")
    for key in (
        "status",
        "current_skill",
        "progress",
        "errors",
        "backend",
        "pose_x",
        "pose_y",
        "pose_yaw",
        "battery",
        "estop",
    ):
        assert key in values, key
    assert values["backend"] == "offline"
    float(values["battery"]), float(values["pose_yaw"])
    wait_until(lambda: len(agent.diagnostics.since(mark)) >= 2, 5, "a second diagnostics")
    first, second = agent.diagnostics.since(mark)[:2]
    gap = (second.header.stamp.sec + second.header.stamp.nanosec * 1e-9) - (
        first.header.stamp.sec + first.header.stamp.nanosec * 1e-9
    )
    assert 0.5 < gap < 1.5  # 1 Hz


def test_robot_status_is_json(agent: Agent) -> None:
    state = agent.robot_state()
    assert {"x", "y", "yaw", "battery", "posture", "moving", "estopped"} <= set(state)


def test_chat_service_answers(agent: Agent) -> None:
    future = agent.chat.call_async(Chat.Request(text="where are you?"))
    wait_until(future.done, TIMEOUT, "the chat answer")
    assert future.result().answer.startswith("I am at x=")


def test_risky_plans_wait_for_approval_over_ros(agent: Agent) -> None:
    requests, approve = agent.approvals, agent.approve

    def decide(command: str, yes: bool) -> str:
        mark, seen = agent.status.mark(), requests.mark()
        agent.missions.publish(String(data=command))
        announced = json.loads(
            requests.wait_for(
                lambda m: command in m.data, TIMEOUT, "the approval request", seen
            ).data
        )
        assert "risky trick" in announced["reasons"][0]
        future = approve.call_async(
            Approve.Request(request_id=announced["request_id"], approve=yes, reason="not indoors")
        )
        wait_until(future.done, TIMEOUT, "the approve service to answer")
        assert future.result().accepted
        return str(
            agent.status.wait_for(
                lambda m: m.data.startswith(("COMPLETED", "FAILED")),
                TIMEOUT,
                "the mission to end",
                mark,
            ).data
        )

    assert decide("do a front flip", yes=False).startswith(
        "FAILED: Refused before moving: not approved (rejected: not indoors)"
    )
    assert decide("do a backflip", yes=True) == "COMPLETED: Done: performed backflip."
    nothing = approve.call_async(Approve.Request(approve=True))
    wait_until(nothing.done, TIMEOUT, "the approve service to answer")
    assert not nothing.result().accepted
    assert nothing.result().message == "no plan is waiting for approval"


# -- camera ----------------------------------------------------------------------------------


def raw_image(width: int, height: int, encoding: str, pad: int = 0) -> Image:
    channels = {"rgb8": 3, "bgr8": 3, "mono8": 1}.get(encoding, 2)
    step = width * channels + pad
    return Image(
        width=width, height=height, encoding=encoding, step=step, data=bytes(step * height)
    )


def deliver(agent: Agent, publisher: object, msg: object, expect: str, key: str) -> None:
    """Publish (best effort) until the node's diagnostics show it took the message."""
    wait_until(publisher.get_subscription_count, TIMEOUT, "the camera subscription")

    def taken() -> bool:
        publisher.publish(msg)
        try:
            agent.diagnostic(
                agent.diagnostics.mark(), timeout=1.5, match=lambda v: expect in v[key]
            )
        except AssertionError:
            return False
        return True

    wait_until(taken, TIMEOUT, f"{key} to show {expect!r}", interval=0.0)


def test_raw_frames_reach_the_agent(agent: Agent, client: RosClient) -> None:
    camera = client.publisher(Image, "/camera/image_raw", RELIABLE)
    deliver(agent, camera, raw_image(64, 48, "rgb8", pad=8), "64x48 rgb8", "camera_last_frame")
    assert "64x48 RGB8 frame from the camera" in agent.run("what do you see?")
    deliver(agent, camera, raw_image(32, 24, "bgr8"), "32x24 bgr8", "camera_last_frame")
    deliver(agent, camera, raw_image(30, 20, "mono8", pad=2), "30x20 mono8", "camera_last_frame")
    assert "30x20 MONO8 frame" in agent.run("what do you see?")


def test_bad_raw_frames_are_dropped_with_a_warning(agent: Agent, client: RosClient) -> None:
    camera = client.publisher(Image, "/camera/image_raw", RELIABLE)
    deliver(
        agent,
        camera,
        raw_image(16, 16, "yuv422"),
        "unsupported image encoding 'yuv422'",
        "camera_last_error",
    )
    short = raw_image(16, 16, "rgb8")
    short.data = bytes(100)
    deliver(agent, camera, short, "image data has 100 bytes", "camera_last_error")
    assert agent.run("turn left 5 degrees").startswith("COMPLETED: ")


def test_compressed_frames_reach_the_agent(cam_agent: Agent, client: RosClient) -> None:
    camera = client.publisher(CompressedImage, "/cam/camera/compressed", RELIABLE)
    jpeg = CompressedImage(format="jpeg", data=tiny_jpeg(64, 48))
    deliver(cam_agent, camera, jpeg, "64x48 jpeg", "camera_last_frame")
    assert "64x48 JPEG frame from the camera" in cam_agent.run("what do you see?")
    deliver(
        cam_agent,
        camera,
        CompressedImage(format="jpeg", data=b"not an image at all"),
        "image bytes must be JPEG or PNG",
        "camera_last_error",
    )
    deliver(
        cam_agent, camera, CompressedImage(format="png", data=b""), "empty", "camera_last_error"
    )
    assert cam_agent.run("turn left 5 degrees").startswith("COMPLETED: ")


# -- the web dashboard inside the node -----------------------------------------------------------


def web(path: str, body: dict | None = None) -> dict:
    data = json.dumps(body).encode() if body is not None else None
    request = urllib.request.Request(
        f"http://127.0.0.1:{WEB_PORT}{path}",
        data=data,
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        return json.loads(response.read())


def test_web_ui_shares_the_nodes_mission_worker(agent: Agent) -> None:
    assert web("/api/health")["status"] == "healthy"
    mark = agent.status.mark()
    mission_id = web("/api/mission", {"command": "turn left 10 degrees"})["mission_id"]
    # The page's mission runs on the node's worker, so ROS sees it like any other.
    agent.status.wait_for(
        lambda m: m.data == "EXECUTING: turn left 10 degrees",
        TIMEOUT,
        "the web mission on mission_status",
        mark,
    )
    agent.status.wait_for(
        lambda m: m.data.startswith("COMPLETED: "), TIMEOUT, "the web mission to complete", mark
    )
    wait_until(
        lambda: web(f"/api/missions/{mission_id}").get("status") == "succeeded",
        TIMEOUT,
        "the web record to finish",
    )
    assert agent.run("sit down").startswith("COMPLETED")  # a topic mission, listed too
    listed = [m["command"] for m in web("/api/missions")["missions"]]
    assert "sit down" in listed and "turn left 10 degrees" in listed


def test_patrol_until_i_say_stop_ends_on_a_cancelled_goal(agent: Agent) -> None:
    """Issue 26: a cancelled goal is the person's stop "patrol until I say stop" waited for:
    the goal succeeds, saying why, and the robot stands still."""
    handle = send_goal(agent, "stand up and patrol until I say stop")
    assert handle.accepted
    wait_moving(agent)
    cancel = agent.client.call(handle.cancel_goal_async)
    wait_until(cancel.done, TIMEOUT, "the cancel response")
    response = get_result(agent, handle)
    assert response.status == GoalStatus.STATUS_SUCCEEDED, response.result.response
    assert response.result.success
    assert "stopped: you said stop (until I say stop)" in response.result.response
    wait_until(lambda: (s := agent.robot_state()) and not s["moving"] and s, 5, "the robot to stop")
