"""`shadowhound doctor --go2` over DDS, the rest of a Go2 owner's stack: TF and SLAM's map, the
object detector and its camera model, who hears `/tts` (the rules themselves: tests/
test_go2_doctor_stack.py).

The doctor runs as its own process, as a person runs it. What it watches is published from
this process (TF as tf2_msgs/TFMessage, a map in `map`, Detection2DArray, camera_info, and a
`tts_node` that subscribes `/tts` or does not), or by `shadowhound sim-driver --detector coco`.

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "vision_msgs", "tf2_msgs")

from geometry_msgs.msg import TransformStamped  # noqa: E402
from nav_msgs.msg import OccupancyGrid  # noqa: E402
from rclpy.qos import (  # noqa: E402
    DurabilityPolicy,
    QoSProfile,
    ReliabilityPolicy,
)
from sensor_msgs.msg import CameraInfo  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose  # noqa: E402

from shadowhound.robot.go2.world_msgs import MAP_QOS  # noqa: E402
from tests.ros.rosclient import ROOT, NodeProcess, RosClient  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
TIMEOUT = 30.0
STACK = "shadowhound_test_stack"  # the node that plays driver, SLAM and detector here
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)  # tf2's broadcaster
STATIC_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
SENSOR = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)  # the driver's camera_info


def run_doctor(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", "doctor", "--go2", "--seconds", "6", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )


def transform(parent: str, child: str, x: float, stamp: Any) -> TransformStamped:
    t = TransformStamped()
    t.header.frame_id, t.header.stamp, t.child_frame_id = parent, stamp, child
    t.transform.translation.x = x
    t.transform.rotation.w = 1.0
    return t


class Stack:
    """The stack's publishers in this process: the driver's odom -> base_link, SLAM's map ->
    odom and map (in `map`), robot_state_publisher's static frame, the detector's boxes and
    the driver's camera_info, each part switched off by its flag (`slam`, `detector`)."""

    def __init__(self, client: RosClient) -> None:
        self.client, self.slam, self.detector = client, True, True
        self.tf = client.publisher(TFMessage, "/tf", TF_QOS)
        self.static = client.publisher(TFMessage, "/tf_static", STATIC_QOS)
        self.map = client.publisher(OccupancyGrid, "/map", MAP_QOS)
        self.boxes = client.publisher(Detection2DArray, "/detected_objects")
        self.info = client.publisher(CameraInfo, "/camera/camera_info", SENSOR)
        stamp = client.node.get_clock().now().to_msg()
        self.static.publish(
            TFMessage(transforms=[transform("base_link", "front_camera", 0.3, stamp)])
        )
        grid = OccupancyGrid()
        grid.header.frame_id, grid.header.stamp = "map", stamp
        grid.info.resolution, grid.info.width, grid.info.height = 0.05, 4, 4
        grid.info.origin.orientation.w = 1.0
        grid.data = [0] * 16
        self.map.publish(grid)
        self.timers = [
            client.call(client.node.create_timer, 0.05, self._publish_tf),
            client.call(client.node.create_timer, 0.2, self._publish_boxes),
        ]

    def _publish_tf(self) -> None:
        stamp = self.client.node.get_clock().now().to_msg()
        moves = [transform("odom", "base_link", 1.0, stamp)]
        if self.slam:
            moves.append(transform("map", "odom", 0.1, stamp))
        self.tf.publish(TFMessage(transforms=moves))

    def _publish_boxes(self) -> None:
        if not self.detector:
            return
        stamp = self.client.node.get_clock().now().to_msg()
        seen = Detection2DArray()
        seen.header.stamp, seen.header.frame_id = stamp, "front_camera"
        chair = Detection2D()
        chair.header = seen.header
        guess = ObjectHypothesisWithPose()
        guess.hypothesis.class_id, guess.hypothesis.score = "chair", 0.95
        chair.results.append(guess)
        chair.bbox.center.position.x, chair.bbox.size_x = 320.0, 80.0
        seen.detections.append(chair)
        self.boxes.publish(seen)
        info = CameraInfo()
        info.header = seen.header
        info.width, info.height = 640, 480
        info.k = [500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0]
        self.info.publish(info)

    def stop_detector(self) -> None:
        """The detector and the camera go away (on the spin thread: no timer call between)."""

        def stop() -> None:
            self.detector = False
            self.client.node.destroy_publisher(self.boxes)
            self.client.node.destroy_publisher(self.info)

        self.client.call(stop)


@pytest.fixture
def stack() -> Iterator[Stack]:
    client = RosClient(STACK)
    yield Stack(client)
    client.close()


def test_doctor_reads_tf_slams_map_the_detector_and_who_hears_tts(stack: Stack) -> None:
    """No driver here (the doctor fails on that first), but every part of the rest of the
    stack in turn: all there, then SLAM, the detector and the speaker's key gone."""
    tts = RosClient("tts_node")  # go2_ros2_sdk's speech_processor, by its node's name
    try:
        listens = tts.subscribe(String, "/tts")
        done = run_doctor()
        out = done.stdout
        assert done.returncode == 1 and "fail no go2_driver_node on the graph" in out, out
        found = out.splitlines()
        assert any(
            x.startswith("ok   odom -> base_link on /tf: ") and x.endswith(f"; /tf from /{STACK}")
            for x in found
        ), out
        assert any(x.startswith("ok   map -> odom on /tf: ") for x in found), out
        assert "ok   map on /map in frame map, and TF gives map -> odom" in found, out
        assert any(
            x.startswith(f"ok   detections on /detected_objects from /{STACK}: ")
            and re.search(r"boxes: chair \(\d+\)$", x)
            for x in found
        ), out
        assert (
            f"ok   camera model on /camera/camera_info from /{STACK}: 640 x 480, fx 500 px" in found
        ), out
        assert "ok   speech on /tts reaches /tts_node" in found, out
        # ShadowHound's copies of vision_msgs and tf2_msgs are Jazzy's, and DDS delivers.
        assert "Jazzy's" not in out and "DDS drops" not in out, out

        stack.slam = False  # SLAM stops: its map (transient local) stays, in `map`
        stack.stop_detector()
        tts.destroy(listens)  # tts_node without its provider's key subscribes nothing
        again = run_doctor().stdout
        lines = again.splitlines()
        assert any(x.startswith("ok   odom -> base_link on /tf: ") for x in lines), again
        assert any(
            x.startswith("info no map -> odom on /tf: no SLAM or localization running")
            for x in lines
        ), again
        assert any(
            x.startswith(
                "warn the map on /map is in frame 'map', but nothing publishes map -> odom"
            )
            for x in lines
        ), again
        assert any(
            x.startswith("info nothing publishes /detected_objects: no object detector")
            for x in lines
        ), again
        assert any(
            x.startswith("warn /tts_node is up but does not subscribe /tts") for x in lines
        ), again
        assert "camera_info" not in again, again  # without a detector nothing is said of it
    finally:
        tts.close()


def test_doctor_finds_the_simulated_coco_detector_and_its_camera_model() -> None:
    """`shadowhound sim-driver --detector coco` under /docs: the doctor, given the namespace,
    finds its Detection2DArray boxes and camera_info, and nothing fails."""
    client = RosClient("shadowhound_doctor_stack_client")
    driver = NodeProcess("-r", "__ns:=/docs", command="sim-driver", options=("--detector", "coco"))
    try:
        boxes = client.subscribe(Detection2DArray, "/docs/detected_objects", SENSOR)
        boxes.latest(TIMEOUT, "the simulated detector's first boxes")
        done = run_doctor("--namespace", "docs")
        out = done.stdout
        assert done.returncode == 0, out + done.stderr
        found = out.splitlines()
        assert any(x.startswith("ok   driver: /docs/shadowhound_sim_driver") for x in found), out
        assert any(
            x.startswith(
                "ok   detections on /docs/detected_objects from /docs/shadowhound_sim_driver: "
            )
            for x in found
        ), out
        assert (
            "ok   camera model on /docs/camera/camera_info from /docs/shadowhound_sim_driver: "
            "160 x 120, fx 80 px" in found
        ), out
        assert any(x.startswith("ok   map on /docs/map in frame odom") for x in found), out
    finally:
        client.close()
        assert driver.stop() == 0, driver.output()[-3000:]
