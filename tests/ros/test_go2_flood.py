"""A detector flooding the Go2's boxes topic, over DDS, judged by the simulated driver's truth
(issue 32, item 7).

`shadowhound sim-driver --detector coco` publishes what its camera sees as go2_ros2_sdk's
coco_detector does; `shadowhound node -p robot:=go2 -p coco_detections_topic:=detected_objects`
places the boxes. Beside them this test publishes on the same topic, ten times a second,
vision_msgs/Detection2DArray messages of 1,000 boxes, and of 120 (within the size a message may
have). Reading one 1,000-box message took the node's executor 0.2 s, the thread
that also reads odometry: "no odometry for 0.5 s", and Nav2's goals were not accepted. Now a
message over its size is refused unread, one within it is read off the executor (its 100 most
confident boxes), and the node says both in its diagnostics. Judged by outcomes, never by time:
the missions end where they should in truth, the node never lost its odometry, both reported.

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import math
import struct
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "nav2_msgs", "vision_msgs")

from rclpy.serialization import serialize_message  # noqa: E402
from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose  # noqa: E402

from shadowhound.robot.input_limits import MAX_BYTES, size_words  # noqa: E402
from tests.ros.rosclient import RosClient, wait_until  # noqa: E402
from tests.ros.test_go2_truth import TIMEOUT, Rig, frame_of, start_rig  # noqa: E402

SIZES = (1000, 120)  # boxes per message, in turn: over the size a message may have, within it
RATE_HZ = 10.0  # a camera-rate detector
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_flood_client")
    yield c
    c.close()


@pytest.fixture(scope="module")
def rig(client: RosClient, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Rig]:
    profile = Path(tmp_path_factory.mktemp("flood")) / "flood.yaml"
    profile.write_text("backend: offline\nrobot: go2\nmemory:\n  enabled: false\n")
    rig, stop = start_rig(
        client,
        ("--detector", "coco"),
        "/flood",
        "/flood",
        "flood",
        "-p",
        "coco_detections_topic:=detected_objects",
        "-p",
        f"backend_config:={profile}",
    )
    yield rig
    stop()


def flood_message(boxes: int) -> bytearray:
    """`boxes` boxes of a kite (nothing in the scene) across the image, serialized once: the
    stamp (the first 8 bytes after the CDR header) is written anew for each publish."""
    msg = Detection2DArray()
    msg.header.frame_id = "front_camera"
    for i in range(boxes):
        d = Detection2D()
        hypothesis = ObjectHypothesisWithPose()
        hypothesis.hypothesis.class_id = "kite"
        hypothesis.hypothesis.score = 0.3 + i / (10 * boxes)
        d.results = [hypothesis]
        d.bbox.center.position.x = float(i % 1280)
        d.bbox.center.position.y = 360.0
        d.bbox.size_x = d.bbox.size_y = 8.0
        msg.detections.append(d)
    return bytearray(serialize_message(msg))


class Flood:
    """Publishes the messages of SIZES in turn at RATE_HZ, freshly stamped, until stopped."""

    def __init__(self, client: RosClient, topic: str) -> None:
        self.client, self.data = client, [flood_message(n) for n in SIZES]
        self.pub = client.publisher(Detection2DArray, topic)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> Flood:
        wait_until(lambda: self.pub.get_subscription_count() >= 1, TIMEOUT, "the node's reader")
        self._thread.start()
        return self

    def __exit__(self, *_exc: Any) -> None:
        self._stop.set()
        self._thread.join(5.0)
        self.client.destroy(self.pub)

    def _run(self) -> None:
        sent = 0
        while not self._stop.is_set():
            data = self.data[sent % len(self.data)]
            now = self.client.node.get_clock().now().nanoseconds
            struct.pack_into("<iI", data, 4, *divmod(now, 1_000_000_000))
            self.pub.publish(bytes(data))
            sent += 1
            time.sleep(1.0 / RATE_HZ)


def test_a_flood_of_boxes_neither_starves_odometry_nor_stops_the_missions(
    client: RosClient, rig: Rig
) -> None:
    with Flood(client, "/flood/detected_objects"):
        # Nav2's goal accepted, the walk ends at it in truth; a turn steered on odometry.
        final = rig.agent.run("go to x=4, y=0", 120.0)
        end = rig.truth.still()
        assert final.startswith("COMPLETED: ") and "through Nav2" in final, (
            final,
            rig.node.output()[-3000:],
        )
        assert math.hypot(end["x"] - 4.0, end["y"]) < 0.10, end
        start = end
        final = rig.agent.run("turn left 90 degrees", 60.0)
        end = rig.truth.still()
        assert final.startswith("COMPLETED: "), (final, rig.node.output()[-3000:])
        assert abs(frame_of(start, end)[2] - 90.0) < 3.0, (start, end)
        _status, values = rig.agent.diagnostic(
            timeout=TIMEOUT,
            match=lambda v: all(
                words in v.get("input_problems", "")
                for words in ("refused unread", "detections in one message")
            ),
        )
    said = values["input_problems"]
    big = size_words(len(flood_message(SIZES[0])))
    limit = size_words(MAX_BYTES["detections"])
    assert (
        f"/flood/detected_objects: a Detection2DArray of {big} refused unread (at most {limit} "
        "is taken)" in said
    ), said
    assert (
        f"/flood/detected_objects: {SIZES[1]} detections in one message: read the 100 most "
        "confident" in said
    ), said
    # The node lost no odometry ("no odometry on /flood/odom for 0.6 s", not the start-up's
    # "no odometry on /flood/odom yet" before the driver was matched).
    assert "no odometry on /flood/odom for" not in rig.node.output(), rig.node.output()[-3000:]
