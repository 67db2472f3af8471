"""Big inputs against the Go2's control path (issue 32, item 7): what rclpy takes to read a
message by size, and how old the Go2 robot's odometry gets while a detector floods it.

Run:  .venv/bin/python bench/bench_inputs.py [--seconds S] [--hogs N] [--write]
Needs rclpy, go2_interfaces and vision_msgs (bash scripts/build_ros.sh). DDS stays on loopback
(the project's Fast DDS profile, LOCALHOST discovery, a domain id from this pid). --write
replaces the "inputs" section of bench/RESULTS.md.

Method.
- Reading: `rclpy.serialization.deserialize_message` of one message, the median of 11 (each
  after a garbage collection), for
  Detection2DArray (10, 100, 150, 1,000 boxes of one hypothesis), TFMessage (30, 300, 2,000
  transforms), LaserScan (1,440 ranges) and a 1080p rgb8 Image: what a callback pays before it
  starts, holding the interpreter.
- Odometry under a flood: a Go2RosRobot (`coco_detections_topic` set) in this process; a child
  process publishes odometry at 20 Hz and, in the flood runs, a Detection2DArray (serialized
  once, stamped anew) at 10 Hz. Every 10 ms this process reads how long ago the robot's last
  odometry arrived (its `_pose_at`); the figures are that age's median, 99th percentile and
  maximum over `--seconds`, and the share of samples over `odom_timeout` (0.5 s: a moving
  robot's step fails). Runs: no flood; 120 boxes a message (within the size, read off the
  executor at most a quarter of its thread's time, the 100 most confident kept); 1,000 boxes
  (over the size: refused unread); 1,000 boxes also read on the executor, as a plain
  subscription did before issue 32 (reading only: the boxes' processing came on top). With
  `--hogs N`, N processes spin a processor each all along (a loaded robot computer: SLAM, Nav2
  and a detector beside ShadowHound); both tables are written, quiet and loaded.
"""

from __future__ import annotations

import argparse
import gc
import math
import os
import platform
import statistics
import struct
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

from shadowhound.ros.dds import claim_domain, loopback_env

if "--publish" not in sys.argv:
    _DOMAIN, _HELD = claim_domain()  # held for this process's life: no other run meets it
    os.environ.update(loopback_env(_DOMAIN))  # before rclpy is imported

import rclpy  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402

from results import write_section  # noqa: E402

NS = "bench_inputs"
SENSOR = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def box_array(count: int) -> object:
    from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose

    msg = Detection2DArray()
    msg.header.frame_id = "front_camera"
    for i in range(count):
        d = Detection2D()
        hypothesis = ObjectHypothesisWithPose()
        hypothesis.hypothesis.class_id, hypothesis.hypothesis.score = "kite", 0.3 + i / 1e5
        d.results = [hypothesis]
        d.bbox.center.position.x, d.bbox.size_x = float(i % 1280), 8.0
        msg.detections.append(d)
    return msg


def reading_costs() -> list[tuple[str, int, float]]:
    """(what, serialized bytes, median ms to read) per message kind and size."""
    import array

    from geometry_msgs.msg import TransformStamped
    from sensor_msgs.msg import Image, LaserScan
    from tf2_msgs.msg import TFMessage

    def tf(count: int) -> TFMessage:
        msg = TFMessage()
        for i in range(count):
            t = TransformStamped()
            t.header.frame_id, t.child_frame_id = "base_link", f"link_{i}"
            msg.transforms.append(t)
        return msg

    scan = LaserScan()
    scan.ranges = array.array("f", [1.0] * 1440)
    image = Image()
    image.width, image.height, image.encoding, image.step = 1920, 1080, "rgb8", 1920 * 3
    image.data = bytes(1920 * 1080 * 3)
    cases = [
        ("Detection2DArray, 10 boxes", box_array(10)),
        ("Detection2DArray, 100 boxes", box_array(100)),
        ("Detection2DArray, 150 boxes", box_array(150)),
        ("Detection2DArray, 1,000 boxes", box_array(1000)),
        ("TFMessage, 30 transforms", tf(30)),
        ("TFMessage, 300 transforms", tf(300)),
        ("TFMessage, 2,000 transforms", tf(2000)),
        ("LaserScan, 1,440 ranges", scan),
        ("Image, 1920 x 1080 rgb8", image),
    ]
    out = []
    for what, msg in cases:
        data = serialize_message(msg)
        times = []
        for _ in range(11):
            gc.collect()
            began = time.perf_counter()
            deserialize_message(data, type(msg))
            times.append((time.perf_counter() - began) * 1000.0)
        out.append((what, len(data), statistics.median(times)))
    return out


def publish(boxes_per_message: int) -> None:
    """The child process: odometry at 20 Hz, and that many boxes at 10 Hz (0: none)."""
    from vision_msgs.msg import Detection2DArray

    rclpy.init()
    node = Node("bench_inputs_publisher")
    odom = node.create_publisher(Odometry, f"/{NS}/odom", RELIABLE)
    boxes = node.create_publisher(Detection2DArray, f"/{NS}/detected_objects", RELIABLE)
    data = bytearray(serialize_message(box_array(boxes_per_message)))
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = "odom", "base_link"
    msg.pose.pose.orientation.w = 1.0
    tick = 0
    while rclpy.ok():
        now = node.get_clock().now()
        msg.header.stamp = now.to_msg()
        odom.publish(msg)
        if boxes_per_message and tick % 2 == 0:
            struct.pack_into("<iI", data, 4, *divmod(now.nanoseconds, 1_000_000_000))
            boxes.publish(bytes(data))
        tick += 1
        time.sleep(0.05)


def odometry_ages(seconds: float, boxes: int, on_executor: bool = False) -> dict[str, float]:
    """Ages (s) of the robot's last odometry sampled every 10 ms while the child publishes."""
    from vision_msgs.msg import Detection2DArray

    from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot

    context = Context()
    rclpy.init(context=context)
    robot = Go2RosRobot(
        Go2RosConfig(
            namespace=NS,
            node_name="bench_inputs_go2",
            coco_detections_topic="detected_objects",
            map_topic="",
            nav2_action="",
            estop_topic="",
        ),
        context=context,
    )
    if on_executor:  # as a plain subscription read it before issue 32
        robot.node.create_subscription(
            Detection2DArray, "detected_objects", lambda _msg: None, SENSOR
        )
    child = subprocess.Popen(
        [sys.executable, __file__, "--publish", str(boxes)],
        cwd=Path(__file__).parent,
    )
    try:
        deadline = time.monotonic() + 30.0
        while robot._pose_at is None:
            if time.monotonic() > deadline:
                raise SystemExit("bench_inputs: no odometry from the publisher")
            time.sleep(0.01)
        time.sleep(2.0)  # the flood under way
        ages = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            pose_at = robot._pose_at
            ages.append(time.monotonic() - pose_at)
            time.sleep(0.01)
    finally:
        child.terminate()
        child.wait(10)
        robot.close()
        rclpy.try_shutdown(context=context)
    ages.sort()
    return {
        "median": statistics.median(ages),
        "p99": ages[math.ceil(0.99 * len(ages)) - 1],
        "max": ages[-1],
        "stale": sum(a > 0.5 for a in ages) / len(ages),
        "load": os.getloadavg()[0],
    }


class Hogs:
    """`count` processes that each keep a processor busy, while in use."""

    def __init__(self, count: int) -> None:
        self.count = count
        self.procs: list[subprocess.Popen[bytes]] = []

    def __enter__(self) -> Hogs:
        spin = "while True: pass"
        self.procs = [subprocess.Popen([sys.executable, "-c", spin]) for _ in range(self.count)]
        return self

    def __exit__(self, *_exc: object) -> None:
        for proc in self.procs:
            proc.kill()
            proc.wait(10)


def flood_runs(seconds: float) -> list[tuple[str, dict[str, float]]]:
    return [
        ("no flood", odometry_ages(seconds, 0)),
        ("120 boxes at 10 Hz (read, the 100 most confident kept)", odometry_ages(seconds, 120)),
        ("1,000 boxes at 10 Hz (refused unread)", odometry_ages(seconds, 1000)),
        (
            "1,000 boxes at 10 Hz, also read on the executor (before issue 32)",
            odometry_ages(seconds, 1000, on_executor=True),
        ),
    ]


def flood_table(title: str, runs: list[tuple[str, dict[str, float]]]) -> list[str]:
    return [
        title,
        "",
        "| run | median (s) | p99 (s) | max (s) | samples older than 0.5 s | load |",
        "|---|---|---|---|---|---|",
        *(
            f"| {what} | {r['median']:.3f} | {r['p99']:.3f} | {r['max']:.3f} | "
            f"{100 * r['stale']:.1f} % | {r['load']:.1f} |"
            for what, r in runs
        ),
        "",
    ]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument("--hogs", type=int, default=2, help="CPU hogs in the loaded runs")
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--publish", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.publish is not None:
        publish(args.publish)
        return 0
    costs = reading_costs()
    quiet = flood_runs(args.seconds)
    with Hogs(args.hogs):
        loaded = flood_runs(args.seconds)
    lines = [
        "<!-- inputs:start -->",
        "## Big inputs against the Go2's control path (issue 32, `bench/bench_inputs.py`)",
        "",
        f"Measured {date.today().isoformat()} with `python bench/bench_inputs.py --write` on "
        f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()} "
        "(a shared machine: other work ran beside it).",
        "",
        "What rclpy takes to read one message (deserialize_message, median of 11):",
        "",
        "| message | bytes | read (ms) |",
        "|---|---|---|",
        *(f"| {what} | {size:,} | {ms:.1f} |" for what, size, ms in costs),
        "",
        f"How old the Go2 robot's last odometry (20 Hz) is, sampled every 10 ms for "
        f"{args.seconds:g} s, while a detector floods its boxes topic; `load` is the machine's "
        "load average over the last minute at the end of the run.",
        "",
        *flood_table("Without hogs:", quiet),
        *flood_table(f"Loaded ({args.hogs} CPU hogs beside it):", loaded),
        "<!-- inputs:end -->",
    ]
    section = "\n".join(lines) + "\n"
    print(section)
    if args.write:
        write_section("inputs", section)
    return 0


if __name__ == "__main__":
    sys.exit(main())
