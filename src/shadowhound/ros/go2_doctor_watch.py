"""Watching the ROS graph and the Go2 driver's topics for `shadowhound doctor --go2` (rclpy,
imported lazily by the CLI): `observe` gathers the `Observation` that go2_doctor's pure rules
(`diagnose`) turn into findings; the rest of the stack's topics (TF, the map, the detector's
boxes and camera_info; the speech topic's subscribers) are watched alongside.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from ..robot.go2.topics import VELOCITY_TOPICS, node_name
from .go2_doctor import BATTERY_TYPE
from .go2_doctor_observation import Endpoint, Observation

BATTERY_GRACE = 5.0  # extra seconds to wait for a slow battery topic


def require_ros() -> None:
    """Raise ImportError naming what is missing when ROS 2 or go2_interfaces is not installed
    (before anything is printed about watching topics)."""
    import rclpy  # noqa: F401
    from go2_interfaces.msg import Go2State  # noqa: F401


def observe(
    namespace: str = "",
    *,
    seconds: float = 3.0,
    cmd_vel_topic: str = "",
    battery_topic: str = "",
    coco_detections_topic: str = "detected_objects",
    camera_info_topic: str = "camera/camera_info",
    speech_topic: str = "/tts",
    map_topic: str = "map",
) -> Observation:
    """Watch the driver's topics, and the stack's (TF, map, detector, speech; '' = not
    checked), for `seconds` in a private rclpy context."""
    import rclpy
    from go2_interfaces.msg import Go2State, WebRtcReq
    from nav_msgs.msg import Odometry
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import BatteryState

    obs = Observation(
        namespace=namespace.strip("/"),
        seconds=seconds,
        cmd_vel_topic=cmd_vel_topic,
        battery_topic=battery_topic,
        coco_detections_topic=coco_detections_topic,
        camera_info_topic=camera_info_topic,
        speech_topic=speech_topic,
        map_topic=map_topic,
    )
    context = Context()
    rclpy.init(context=context)
    node = Node(
        "shadowhound_doctor",
        namespace="/" + obs.namespace,
        context=context,
        use_global_arguments=False,
        start_parameter_services=False,
    )
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    keys = ["odom", "go2_states", "webrtc_req", *VELOCITY_TOPICS]
    if cmd_vel_topic and cmd_vel_topic not in keys:
        keys.append(cmd_vel_topic)
    obs.names = {k: node.resolve_topic_name(k) for k in keys}
    if battery_topic:
        obs.names["battery"] = node.resolve_topic_name(battery_topic)
    stack = {
        "coco_detections": coco_detections_topic,
        "camera_info": camera_info_topic if coco_detections_topic else "",
        "speech": speech_topic,
        "map": map_topic,
        "tf": "/tf",
        "tf_static": "/tf_static",
    }
    obs.names.update({k: node.resolve_topic_name(t) for k, t in stack.items() if t})
    node.create_subscription(
        Odometry, "odom", lambda _m: obs.odom_receipts.append(time.monotonic()), qos
    )

    def on_state(msg: Any) -> None:
        obs.states.append((int(msg.mode), float(msg.body_height)))

    def on_battery(msg: Any) -> None:
        obs.battery_levels.append(float(msg.percentage) * 100.0)

    node.create_subscription(Go2State, "go2_states", on_state, qos)
    probe = node.create_publisher(WebRtcReq, "shadowhound_doctor/type_probe", qos)
    if battery_topic:
        node.create_subscription(BatteryState, battery_topic, on_battery, qos)
    typed = _watch_stack(node, obs)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        # Battery sources often publish at 1 Hz or slower: give a configured one that has a
        # publisher up to BATTERY_GRACE more seconds for its first message.
        if battery_topic and node.get_publishers_info_by_topic(obs.names["battery"]):
            grace = time.monotonic() + BATTERY_GRACE
            while not obs.battery_levels and time.monotonic() < grace:
                executor.spin_once(timeout_sec=0.05)
        obs.ended = time.monotonic()
        me = node.get_fully_qualified_name()
        for key, full in obs.names.items():
            obs.publishers[key] = _endpoints(node.get_publishers_info_by_topic(full), me)
            obs.subscribers[key] = _endpoints(node.get_subscriptions_info_by_topic(full), me)
        own = [
            *node.get_subscriptions_info_by_topic(obs.names["go2_states"]),
            *node.get_subscriptions_info_by_topic(obs.names["odom"]),
            *node.get_publishers_info_by_topic(probe.topic_name),
            *(i for k in typed for i in node.get_subscriptions_info_by_topic(obs.names[k])),
        ]
        obs.local_hashes = {
            i.topic_type: str(i.topic_type_hash)
            for i in own
            if node_name(i.node_namespace, i.node_name) == me
        }
        obs.nodes = sorted(
            full
            for name, namespace in node.get_node_names_and_namespaces()
            if (full := node_name(namespace, name)) != me
        )
        obs.root_cmd_vel_subscribed = bool(node.get_subscriptions_info_by_topic("/cmd_vel"))
        obs.root_webrtc_subscribed = bool(node.get_subscriptions_info_by_topic("/webrtc_req"))
        obs.battery_elsewhere = sorted(
            n for n, types in node.get_topic_names_and_types() if BATTERY_TYPE in types
        )
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return obs


def _watch_stack(node: Any, obs: Observation) -> list[str]:
    """Subscribe the stack's topics that carry data (TF, the map, boxes, camera_info); a type
    this Python cannot import is noted in `obs.unreadable`. Returns the keys subscribed with a
    type whose hash is compared (go2_doctor_stack)."""
    from nav_msgs.msg import OccupancyGrid
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import CameraInfo

    from ..robot.go2.world_msgs import MAP_QOS

    # Best effort takes a reliable publisher's samples too (coco_detector's are reliable, the
    # driver's camera_info best effort).
    sensor = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
    tf_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    static_qos = QoSProfile(
        depth=100,
        history=HistoryPolicy.KEEP_LAST,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    typed = []

    def on_tf(msg: Any) -> None:
        for t in msg.transforms:
            edge = (t.header.frame_id.lstrip("/"), t.child_frame_id.lstrip("/"))
            obs.tf[edge] = obs.tf.get(edge, 0) + 1

    def on_tf_static(msg: Any) -> None:
        for t in msg.transforms:
            obs.tf_static.add((t.header.frame_id.lstrip("/"), t.child_frame_id.lstrip("/")))

    def on_boxes(msg: Any) -> None:
        obs.detection_receipts.append(time.monotonic())
        obs.detection_classes += [
            str(d.results[0].hypothesis.class_id) for d in msg.detections if d.results
        ]

    def on_info(msg: Any) -> None:
        obs.camera_infos.append((int(msg.width), int(msg.height), float(msg.k[0])))

    try:
        from tf2_msgs.msg import TFMessage
    except ImportError as exc:
        obs.unreadable["tf"] = str(exc)
    else:
        node.create_subscription(TFMessage, obs.names["tf"], on_tf, tf_qos)
        node.create_subscription(TFMessage, obs.names["tf_static"], on_tf_static, static_qos)
        typed.append("tf")
    if "map" in obs.names:
        node.create_subscription(
            OccupancyGrid,
            obs.names["map"],
            lambda msg: obs.map_frames.append(str(msg.header.frame_id)),
            MAP_QOS,
        )
    if "coco_detections" in obs.names:
        try:
            from vision_msgs.msg import Detection2DArray
        except ImportError as exc:
            obs.unreadable["coco_detections"] = str(exc)
        else:
            node.create_subscription(
                Detection2DArray, obs.names["coco_detections"], on_boxes, sensor
            )
            typed.append("coco_detections")
    if "camera_info" in obs.names:
        node.create_subscription(CameraInfo, obs.names["camera_info"], on_info, sensor)
    return typed


def _endpoints(infos: Sequence[Any], me: str) -> list[Endpoint]:
    ends = (
        Endpoint(node_name(i.node_namespace, i.node_name), i.topic_type, str(i.topic_type_hash))
        for i in infos
    )
    return [e for e in ends if e.node != me]
